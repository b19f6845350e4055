// The flat piece index space shared by occlusion and raster: item j owns the pieces
// piece_offset[j] <= p < piece_offset[j + 1] (piece_item[p] = j). An item without candidates
// has one piece, its triangle clipped to the tile, recomputed here rather than stored;
// clipped items keep theirs in the clip pools.
#pragma once

#include "pipeline.cuh"

namespace tilevis::cuda {

template <class P>
struct PieceSource {
  const TileTri<P>* tris;
  const uint64_t* item_key;
  const uint32_t* item_tri;
  const uint64_t* piece_offset;
  const uint32_t* piece_item;
  const uint32_t* cand_count;
  const uint32_t* item_slot;
  const uint64_t* slot_poly;
  const PEdge<P>* pool;
  TileGrid grid;
};

template <class P>
struct PieceView {
  const PEdge<P>* e;
  uint32_t n;
  uint32_t item, tile, tri;
};

// `local` must hold kTileCap edges.
template <class P>
TV_HD inline PieceView<P> piece_at(const PieceSource<P>& s, uint64_t p, PEdge<P>* local) {
  const uint32_t j = s.piece_item[p];
  PieceView<P> v;
  v.item = j;
  v.tile = uint32_t(s.item_key[j]);
  v.tri = s.item_tri[j];
  if (s.cand_count[j] == 0) {
    bool overflow = false;
    v.n = tile_polygon<P>(s.tris[v.tri], s.grid.rect(v.tile), local, overflow);
    v.e = local;
  } else {
    const uint64_t sp = s.slot_poly[s.item_slot[j] + (p - s.piece_offset[j])];
    v.e = s.pool + (sp >> 32);
    v.n = uint32_t(sp);
  }
  return v;
}

template <class P>
PieceSource<P> piece_source(Pipeline<P>& p) {
  PieceSource<P> s{};
  s.tris = p.tris.get();
  s.item_key = p.item_key_sorted.get();
  s.item_tri = p.item_tri_sorted.get();
  s.piece_offset = p.piece_offset.get();
  s.piece_item = p.piece_item.get();
  s.cand_count = p.cand_count.get();
  s.item_slot = p.item_slot.get();
  s.slot_poly = p.slot_poly.get();
  s.pool = p.clip_edges.get();
  s.grid = p.grid;
  return s;
}

}  // namespace tilevis::cuda
