// Fidelity rtl's cycle reference (model/units/early_visibility_unit/rtl_evu.h): a tile job
// replayed through the Verilated TileSequencer (×8, lists 512/256), Clip (×1) and Occlude (×1)
// in the analytic resolver's order, every decision and polygon checked against the public
// functions (the scoreboard) and the job's golden counters.
//
// What is simulated and what is stated:
//  - TileSequencer: simulated; its issued pairs must be the resolver's (analytic_resolver.cpp:
//    edges by z_min, per triangle up to test 6), their count golden's pair_tests.
//  - PairReject and DepthTest (tests 1-6 of each issued pair): not simulated here. Both take
//    one pair per clock per lane at a fixed latency of 3 (no stall, no data-dependent timing;
//    their testbenches check the latency and every decision on the same jobs), so behind a
//    sequencer at the same lane count their time is the sequencer's issue plus 3 + 3 clocks.
//    The candidates are the public functions' (svgpu::survives), counted against golden's
//    candidate_pairs.
//  - Clip: simulated, every split the resolver performs, both children compared bit for bit;
//    splits and pieces counted against golden's clip_polygons and pieces.
//  - Occlude: simulated, every piece's interior point and every exact test the resolver makes
//    (the resolver's own screens, z_min order and bounding box, pick the occluders), counted
//    against golden's occlusion_tests and visible_pieces.
#include "units/early_visibility_unit/rtl_evu.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "drivers.h"
#include "scoreboard.h"

namespace tilevis::sim {
namespace {

class VerilatedEvu final : public RtlEvu {
 public:
  RtlTileClocks run(const vis::EvuJob& job) override {
    RtlTileClocks out;
    const auto fail = [&](const std::string& what) {
      throw std::runtime_error("fidelity rtl: tile " + std::to_string(job.tile) + ": " + what);
    };
    const auto counter = [&](const char* name, int64_t rtl, int64_t golden) {
      if (rtl != golden)
        fail(std::string("the RTL's ") + name + " " + std::to_string(rtl) + " differs from golden's " +
             std::to_string(golden));
    };
    counter("triangles", int64_t(job.triangles.size()), job.golden.triangles);
    counter("edges", int64_t(job.edges.size() / 2), job.golden.edges);
    if (job.triangles.empty()) {
      out.passes = 0;
      return out;
    }

    // The public functions' replay (the scoreboard), with every split it performs run through
    // Clip on the way.
    std::vector<uint32_t> split_clocks;
    const rtl::ReplayedJob r = rtl::replay_job(job, [&](const geom::ConvexPolygon& piece, const vis::svgpu::Edge& e) {
      const rtl::ClipDriver::Split s = m_clip.split(piece, e);
      if (!rtl::split_matches(s, vis::svgpu::split(piece, e)))
        fail("Clip's split of a " + std::to_string(piece.size()) + "-gon differs from geom::split");
      split_clocks.push_back(s.clocks);
    });

    // TileSequencer: the pairs it issues must be the resolver's.
    std::vector<uint32_t> tri_zmax, edge_zmin;
    for (const auto& t : r.triangles) tri_zmax.push_back(t.t.z_max);
    for (const auto& e : r.edges) edge_zmin.push_back(e.z_min);
    std::stable_sort(edge_zmin.begin(), edge_zmin.end());
    const rtl::TileSequencerDriver::Result seq = m_seq.run(tri_zmax, edge_zmin);
    std::vector<std::pair<uint32_t, uint32_t>> want;
    for (uint32_t t = 0; t < tri_zmax.size(); ++t)
      for (uint32_t e = 0; e < edge_zmin.size() && edge_zmin[e] <= tri_zmax[t]; ++e) want.emplace_back(t, e);
    std::vector<std::pair<uint32_t, uint32_t>> got = seq.issued;
    if (seq.passes > 1) {  // one pass issues in the resolver's order; passes interleave by edge chunk
      std::sort(got.begin(), got.end());
      std::sort(want.begin(), want.end());
    }
    if (got != want)
      fail("TileSequencer issued " + std::to_string(got.size()) + " pairs, not the resolver's " +
           std::to_string(want.size()));
    counter("pair_tests", int64_t(seq.issued.size()), job.golden.pair_tests);
    out.passes = seq.passes;
    out.list_load = seq.load_clocks;
    out.reject_latency = 2 * seq.passes + rtl::kPairRejectLatency + rtl::kDepthTestLatency;

    int64_t candidates = 0, clips = 0, pieces = 0;
    out.tris.resize(r.triangles.size());
    size_t next_split = 0;
    for (size_t i = 0; i < r.triangles.size(); ++i) {
      const auto& rt = r.triangles[i];
      RtlTriangleClocks& tc = out.tris[i];
      tc.id = rt.id;
      tc.reject = seq.tri_clocks[i];
      tc.splits.assign(split_clocks.begin() + ptrdiff_t(next_split),
                       split_clocks.begin() + ptrdiff_t(next_split + size_t(rt.clips)));
      next_split += size_t(rt.clips);
      candidates += int64_t(rt.candidates.size());
      clips += rt.clips;
      pieces += int64_t(rt.pieces.size());
    }
    counter("candidate_pairs (the public functions')", candidates, job.golden.candidate_pairs);
    counter("clip_polygons", clips, job.golden.clip_polygons);
    counter("pieces", pieces, job.golden.pieces);

    // Occlude: each piece against the tile's opaque triangles, nearest z_min first (stable), as
    // TileFrame::occluders, with the resolver's screens before each exact test.
    const std::vector<uint32_t> occ_ix = rtl::occluder_order(r);
    int64_t tests = 0, visible = 0;
    std::vector<rtl::OccludeDriver::Occluder> occ;
    for (size_t i = 0; i < r.triangles.size(); ++i) {
      const auto& rt = r.triangles[i];
      RtlTriangleClocks& tc = out.tris[i];
      for (const auto& piece : rt.pieces) {
        if (piece.empty()) {  // the resolver skips it (a split never leaves one)
          tc.pieces.push_back(0);
          continue;
        }
        rtl::screened_occluders(r, occ_ix, rt, geom::interior_point(piece), occ);
        const rtl::OccludeDriver::Result o = m_occlude.run(piece, rt.t, rt.id, occ);
        if (!o.q_matches) fail("Occlude's interior point differs from geom::interior_point");
        if (o.verdict_mismatches) fail("Occlude's verdicts differ from svgpu::occludes");
        tests += o.tests;
        visible += !o.occluded;
        tc.pieces.push_back(o.clocks);
      }
    }
    counter("occlusion_tests", tests, job.golden.occlusion_tests);
    counter("visible_pieces", visible, job.golden.visible_pieces);
    return out;
  }

 private:
  rtl::TileSequencerDriver m_seq;
  rtl::ClipDriver m_clip;
  rtl::OccludeDriver m_occlude;
};

}  // namespace

std::unique_ptr<RtlEvu> make_rtl_evu(uint32_t reject_lanes, uint32_t triangle_list_entries, uint32_t edge_list_entries) {
  if (reject_lanes != rtl::kSeqLanes || triangle_list_entries != rtl::kSeqTriCap ||
      edge_list_entries != rtl::kSeqEdgeCap)
    throw std::runtime_error("fidelity rtl: the Verilated TileSequencer is built with " +
                             std::to_string(rtl::kSeqLanes) + " lanes and lists of " +
                             std::to_string(rtl::kSeqTriCap) + " triangles / " + std::to_string(rtl::kSeqEdgeCap) +
                             " edges (evu.reject lanes, evu.triangle_list_entries, evu.edge_list_entries); asked for " +
                             std::to_string(reject_lanes) + ", " + std::to_string(triangle_list_entries) + ", " +
                             std::to_string(edge_list_entries));
  return std::make_unique<VerilatedEvu>();
}

bool rtl_evu_available() { return true; }

}  // namespace tilevis::sim
