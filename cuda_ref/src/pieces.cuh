// The flat piece index space shared by occlusion and raster: item j owns the pieces
// piece_offset[j] <= p < piece_offset[j + 1]. An item without candidates has one piece, its
// triangle clipped to the tile, recomputed here rather than stored; clipped items keep theirs
// in the clip pools. Occlusion and raster visit items (one warp each), piece by piece.
#pragma once

#include "pipeline.cuh"

namespace tilevis::cuda {

template <class P>
struct PieceSource {
  const TileTri<P>* tris;
  const uint64_t* item_key;
  const uint32_t* item_tri;
  const uint64_t* piece_offset;
  const uint32_t* cand_count;
  const uint32_t* item_slot;
  const uint64_t* slot_poly;
  const PEdge<P>* pool;
  TileGrid grid;
};

// An item's pieces: flat indices [first, first + count). An item without candidates has one
// piece, its triangle clipped to the tile, computed into `local` once for all its visits.
template <class P>
struct ItemPieces {
  uint32_t tile, tri;
  uint64_t first, count;
  const uint64_t* slots;  // clipped item: its pieces' slot_poly entries; else null
  uint32_t n_local;
};

template <class P>
struct PieceView {
  const PEdge<P>* e;
  uint32_t n;
};

// `local` must hold kTileCap edges.
template <class P>
TV_HD inline ItemPieces<P> item_pieces(const PieceSource<P>& s, uint64_t j, PEdge<P>* local) {
  ItemPieces<P> v{};
  v.tile = uint32_t(s.item_key[j]);
  v.tri = s.item_tri[j];
  v.first = s.piece_offset[j];
  v.count = s.piece_offset[j + 1] - v.first;
  if (v.count == 0) return v;
  if (s.cand_count[j] == 0) {
    bool overflow = false;
    v.n_local = tile_polygon<P>(s.tris[v.tri], s.grid.rect(v.tile), local, overflow);
  } else {
    v.slots = s.slot_poly + s.item_slot[j];
  }
  return v;
}

template <class P>
TV_HD inline PieceView<P> piece_of(const PieceSource<P>& s, const ItemPieces<P>& it, uint64_t k,
                                   const PEdge<P>* local) {
  if (!it.slots) return {local, it.n_local};
  const uint64_t sp = it.slots[k];
  return {s.pool + (sp >> 32), uint32_t(sp)};
}

template <class P>
PieceSource<P> piece_source(Pipeline<P>& p) {
  PieceSource<P> s{};
  s.tris = p.tris.get();
  s.item_key = p.item_key_sorted.get();
  s.item_tri = p.item_tri_sorted.get();
  s.piece_offset = p.piece_offset.get();
  s.cand_count = p.cand_count.get();
  s.item_slot = p.item_slot.get();
  s.slot_poly = p.slot_poly.get();
  s.pool = p.clip_edges.get();
  s.grid = p.grid;
  return s;
}

}  // namespace tilevis::cuda
