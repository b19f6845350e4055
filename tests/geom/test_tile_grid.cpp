// geom/tile_grid.h: the one valid tile range, tile rectangles cut at the screen's edges, and
// the tile-range rule of binning (closed boxes touch closed tile rectangles).
#include <vector>

#include <gtest/gtest.h>

#include "geom/tile_grid.h"

using tilevis::geom::Rect;
using tilevis::geom::TileGrid;

TEST(TileGrid, OneValidTileRange) {
  EXPECT_THROW(TileGrid::make(1920, 1080, 3, 32), std::invalid_argument);
  EXPECT_THROW(TileGrid::make(1920, 1080, 32, 257), std::invalid_argument);
  EXPECT_THROW(TileGrid::make(0, 1080, 32, 32), std::invalid_argument);
  EXPECT_NO_THROW(TileGrid::make(1920, 1080, 4, 256));
  try {
    TileGrid::make(64, 64, 512, 512);
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("4 <= N <= 256"), std::string::npos) << e.what();
  }
}

TEST(TileGrid, LastRowAndColumnAreCutAtTheScreen) {
  const TileGrid g = TileGrid::make(100, 50, 32, 32);
  EXPECT_EQ(g.tiles_x(), 4u);
  EXPECT_EQ(g.tiles_y(), 2u);
  EXPECT_EQ(g.rect(3, 1), (Rect{96 * 256, 32 * 256, 100 * 256, 50 * 256}));
  EXPECT_EQ(g.tile_at_pixel(99, 49), 7u);
  EXPECT_EQ(g.rect(g.tile_at_pixel(40, 10)), g.rect(1, 0));
}

TEST(TileGrid, ClosedBoxesTouchClosedTiles) {
  const TileGrid g = TileGrid::make(128, 128, 32, 32);
  auto tiles = [&](Rect b) {
    std::vector<uint32_t> t;
    g.for_tiles(b, [&](uint32_t tile, const Rect&) { t.push_back(tile); });
    return t;
  };
  // A box ending exactly on the line x = 32 px touches the tile right of it too.
  EXPECT_EQ(tiles({0, 0, 32 * 256, 10}), (std::vector<uint32_t>{0, 1}));
  EXPECT_EQ(tiles({0, 0, 32 * 256 - 1, 10}), (std::vector<uint32_t>{0}));
  // Off screen to the left and above: clamped, so nothing; across the screen: every tile.
  EXPECT_TRUE(tiles({-5000, -5000, -1, -1}).empty());
  EXPECT_EQ(g.range({-5000, -5000, -1, -1}).count(), 0u);
  EXPECT_EQ(g.range({-5000, -5000, 1 << 20, 1 << 20}).count(), 16u);
  EXPECT_EQ(tiles({-256, -256, 0, 0}), (std::vector<uint32_t>{0}));  // touching the corner
}
