// A recorded functional pass (sim.functional_record): what FrameWork answered to the units
// on one frame under one functional configuration (setup, binning, each segment's tile
// lists and each resolved tile's visibility), so that a later run with the same frame and
// functional configuration but other timing parameters replays it instead of computing it.
// FrameWork fills one while it computes and answers from a loaded one while it replays; the
// frame's outputs (ids, visible areas, samples covered) follow from the tiles' records in
// the order the replaying run resolves them, exactly as they follow from computed tiles.
// A tile's results depend on no other tile, only on the stored depth its own earlier
// resolves left (partial renders): a run may replay any of the recorded tiles (fidelity
// auto's sample of a record made at another level) as long as each tile it resolves was
// resolved in the same earlier segments as in the recording run (checked).
//
// File: magic "TVFREC\r\n", format version (u32), the key, the payload, and a checksum of
// every byte before it (u64: FNV-1a 64's step on 64-bit words); little-endian, integers wider
// than a byte as LEB128 varints (signed: zigzag), a tile's samples as runs of equal values, each
// resolved tile after its length in bytes (a replay decodes a tile when it reaches it). Written to a
// temporary file beside the target and renamed: an interrupted run leaves no partial record.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "tilevis/trace.h"
#include "units/common/work.h"
#include "visibility/setup.h"

namespace tilevis::sim {

struct FrameWorkConfig;

// What the functional answers depend on besides the segment plan (checked as the parameter
// buffer hands it over): the frame's content and the parameters FrameWork passes to setup,
// binning and the resolvers.
struct FunctionalKey {
  uint64_t frame_fnv1a64 = 0;  // FNV-1a 64's step on 64-bit words of the frame's trace encoding (trace::encode, this frame alone)
  uint32_t mode = 0, tile_w = 0, tile_h = 0, depth_bits = 0;
  uint32_t evu_triangle_entries = 0, evu_edge_entries = 0;
  uint64_t hybrid_pair_budget = 0;
  uint32_t detection_bin = 0;
  bool operator==(const FunctionalKey&) const = default;
};

FunctionalKey functional_key(const trace::Frame& frame, const FrameWorkConfig& config);
// sim.functional_cache's file for a key and the run's other parameters a record must match
// (`plan_parameters`: those the parameter buffer's segment plan follows): 16 hex digits, ".rec".
std::string cache_file_name(const FunctionalKey& key, const std::string& plan_parameters);
// "sim.tile_width: the record has 16, this run 32; ..." (empty when equal).
std::string key_differences(const FunctionalKey& recorded, const FunctionalKey& run);

// One tile of one segment after its visibility step.
struct RecordedTile {
  uint8_t per_pixel = 0;
  uint64_t detection_screens = 0, detection_tests = 0;
  std::vector<TriangleWork> tris;  // functional fields only (no RTL clocks)
  // The tile's samples after the step, row by row: ids (analytic modes, one segment) or the
  // stored depth's owners (FrameWork's per-sample setup triangle, several segments or
  // per-pixel modes).
  std::vector<int32_t> samples;
  std::vector<std::pair<uint32_t, double>> areas;  // visible areas as the resolver produced them
  uint64_t visible_triangles = 0;
};

// One segment's binning: its non-empty tiles (row-major) and per tile, in that order, its
// counts and its list (frame setup triangle indices, list order); silhouette edges binned to
// every tile of the grid (analytic modes; a tile may have edges and no triangle).
struct RecordedSegment {
  std::vector<uint32_t> tiles;
  std::vector<uint32_t> triangle_count;
  std::vector<uint64_t> pair_tests;
  std::vector<uint32_t> edge_count;  // per grid tile
  std::vector<uint32_t> list_begin;  // tiles.size() + 1 offsets into list
  std::vector<uint32_t> list;
  std::vector<uint32_t> resolved;     // tiles whose visibility was recorded, as resolved
  std::vector<RecordedTile> results;  // beside resolved: a recording run's
  // Beside resolved, a loaded record's: each tile's bytes in the mapped file, decoded only when
  // a replay reaches the tile (FunctionalRecord::tile). A record holds every tile's triangle
  // work, hundreds of megabytes decoded on a large frame; a run holds one tile's at a time.
  std::vector<std::pair<uint64_t, uint64_t>> encoded;  // (offset, bytes)
  size_t result_count() const { return results.size() + encoded.size(); }
};

struct FunctionalRecord {
  static constexpr uint32_t kVersion = 3;  // 2: varint integers; 3: the frame hashed by words, samples as runs

  FunctionalKey key;
  vis::Setup setup;
  std::vector<uint32_t> setup_begin;
  std::vector<uint32_t> tri_refs, tri_tests, edge_refs, edge_tests;
  std::vector<uint32_t> owned_begin, owned;
  std::vector<uint32_t> segment_plan;
  std::vector<RecordedSegment> segments;

  // Segment `segment`'s i-th resolved tile: results[i] as recorded, or a loaded record's tile
  // decoded into `scratch` (throws std::runtime_error naming the file if it does not decode).
  const RecordedTile& tile(uint32_t segment, uint32_t i, RecordedTile& scratch) const;

  // Throws std::runtime_error naming the file on any write failure; `path` appears whole or
  // not at all.
  void save(const std::filesystem::path& path) const;
  // Throws std::runtime_error naming the file and what is wrong: unreadable, another format or
  // version, truncated, corrupt (checksum), trailing bytes.
  static FunctionalRecord load(const std::filesystem::path& path);

 private:
  std::shared_ptr<const void> m_mapping;  // a loaded record's file, mapped while tiles are decoded from it
  const uint8_t* m_bytes = nullptr;
  std::string m_file;
};

}  // namespace tilevis::sim
