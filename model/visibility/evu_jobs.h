// Early-visibility tile jobs as vectors for the RTL testbenches (rtl_ref/tb): every tile that
// holds a front-facing triangle, with its rectangle, its triangles and silhouette edges in the
// binning order the analytic resolver reads them, and the resolver's counters for the tile.
// `tilevis golden T --dump-evu-jobs DIR` writes DIR/evu_jobs.txt; the format is in
// rtl_ref/README.md ("Vector format"). Text, one record a line, integers only. make_evu_job
// builds one tile's job in memory (fidelity rtl runs it through rtl_ref's Verilated units).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "geom/fixed.h"
#include "visibility/setup.h"
#include "visibility/tile_counters.h"

namespace tilevis::vis {

struct EvuJobTriangle {
  uint32_t id = 0;  // original triangle id (the tie rule of svgpu::occludes)
  geom::Vertex v[3];
  bool opaque = true;
};

struct EvuJob {
  uint32_t tile = 0;
  geom::Rect rect;
  std::vector<EvuJobTriangle> triangles;  // TileFrame::tile_triangles order (ascending setup index)
  std::vector<geom::Vertex> edges;        // pairs a, b in TileFrame::tile_edges order (ascending silhouette id)
  TileCounters golden;                    // the analytic resolver's counters for the tile
};

class TileFrame;
class TileResolver;

// The job of `tile` in a binned frame (TileFrame::bin): its rectangle, its front-facing
// triangles and silhouette edges in binning order. `golden`: the analytic resolver's counters
// for the tile, when the caller has them (its triangles and edges are set from the job's
// lists); nullptr leaves them zero. A tile without triangles gives a job without triangles.
EvuJob make_evu_job(const TileFrame& f, uint32_t tile, const TileCounters* golden = nullptr);

// The jobs of one binned frame with their golden counters from the analytic resolver: one
// resolver and one id buffer for every tile asked for (the buffer is the size of the frame's
// samples, so make one source per frame, not one per tile). `f` must outlive it.
class EvuJobSource {
 public:
  explicit EvuJobSource(const TileFrame& f);
  ~EvuJobSource();
  EvuJob job(uint32_t tile);

 private:
  const TileFrame& m_f;
  std::unique_ptr<TileResolver> m_resolver;
  std::vector<int32_t> m_ids;  // what the resolver writes and nothing reads
};

struct EvuJobsHeader {
  uint32_t width = 0, height = 0, subpixel_bits = 0, tile_w = 0, tile_h = 0, frame = 0;
};

// Writes the jobs of `setup` on a grid of tile_w x tile_h to `path`; returns the job count.
uint64_t write_evu_jobs(const Setup& setup, uint32_t tile_w, uint32_t tile_h, uint32_t frame, const std::string& path);

// Reads `path`, calling `job` for every job in file order. Throws std::runtime_error naming
// the file, the line and what was expected.
EvuJobsHeader read_evu_jobs(const std::string& path, const std::function<void(const EvuJob&)>& job);

}  // namespace tilevis::vis
