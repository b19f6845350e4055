#include "top/simulate.h"

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fstream>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>

#include "top/heatmap_png.h"
#include "top/tiler.h"
#include "units/early_visibility_unit/rtl_evu.h"
#include "visibility/parallel.h"

namespace tilevis::sim {
namespace {

std::vector<std::string>* g_reports = nullptr;

// Every warning or error SystemC raises is kept (tests fail on any); errors still throw.
void report_handler(const sc_core::sc_report& r, const sc_core::sc_actions& actions) {
  if (r.get_severity() >= sc_core::SC_WARNING && g_reports)
    g_reports->push_back(std::string(r.get_msg_type()) + ": " + r.get_msg());
  sc_core::sc_report_handler::default_handler(r, actions & ~sc_core::SC_DISPLAY);
}

nlohmann::json units_json(const Tiler& t) {
  nlohmann::json j = nlohmann::json::object();
  for (const StatsGroup* g : t.stats_groups()) {
    std::string name = g->name();
    if (name.rfind("tiler.", 0) == 0) name = name.substr(6);
    j[name] = g->to_json();
  }
  return j;
}

// The energy proxy (config.h's EnergyConfig): microjoules per part and in all.
nlohmann::json energy_json(const EnergyConfig& e, const nlohmann::json& totals, const Tiler& t) {
  auto total = [&](const char* k) { return totals.contains(k) ? totals.at(k).get<double>() : 0.0; };
  double lane_cycles = 0;
  for (const StatsGroup* g : t.stats_groups()) lane_cycles += g->value("shader_lane_cycles");
  const double evu_tests = total("pair_tests") + total("clip_polygons") + total("occlusion_tests") +
                           total("detection_tests");
  const double pj_dram = total("dram_bytes") * e.dram_pj_per_byte;
  const double pj_shader = lane_cycles * e.shader_pj_per_lane_cycle;
  const double pj_evu = evu_tests * e.evu_pj_per_test;
  const double pj_depth = total("depth_tests") * e.depth_test_pj;
  return {{"dram_uj", pj_dram * 1e-6}, {"shader_uj", pj_shader * 1e-6}, {"evu_uj", pj_evu * 1e-6},
          {"depth_test_uj", pj_depth * 1e-6}, {"total_uj", (pj_dram + pj_shader + pj_evu + pj_depth) * 1e-6}};
}

}  // namespace

SimOutput simulate(const trace::Frame& frame, const TilerConfig& config, const SimOptions& options) {
  SimOutput out;
  const auto t0 = std::chrono::steady_clock::now();
  setenv("SYSTEMC_DISABLE_COPYRIGHT_MESSAGE", "1", 1);
  g_reports = &out.systemc_reports;
  sc_core::sc_report_handler::set_handler(report_handler);

  FrameWorkConfig fc;
  fc.mode = config.sim.mode;
  fc.tile_w = config.sim.tile_width;
  fc.tile_h = config.sim.tile_height;
  fc.depth_bits = config.sim.depth_bits;
  fc.evu_triangle_entries = config.evu.triangle_list_entries;
  fc.evu_edge_entries = config.evu.edge_list_entries;
  fc.hybrid_pair_budget = config.evu.hybrid_pair_budget;
  fc.detection_bin = config.evu.detection_bin;
  fc.progress = options.progress;
  fc.sampled = config.sim.fidelity == Fidelity::automatic;
  std::unique_ptr<RtlEvu> rtl;
  if (config.sim.fidelity == Fidelity::rtl && uses_evu(config.sim.mode)) {
    rtl = make_rtl_evu(config.evu.reject.lanes, config.evu.triangle_list_entries, config.evu.edge_list_entries);
    fc.rtl = rtl.get();
  }
  // sim.functional_record: replay the file if it exists, else compute and write it at the end.
  // sim.functional_cache: the same with a file of the cache named by the record's key and the
  // parameter buffer's parameters (its segment plan is checked too); a sample is not added.
  std::filesystem::path record_path = config.sim.functional_record;
  std::unique_ptr<FunctionalRecord> replay;
  const char* functional = "computed";
  double record_seconds = 0;
  const bool cached = !config.sim.functional_cache.empty() && config.sim.fidelity != Fidelity::rtl;
  if (cached && !record_path.empty())
    throw std::invalid_argument("sim.functional_cache and sim.functional_record: give one or the other");
  FunctionalKey key;  // the record's, computed once here (FrameWork checks a replay against it)
  if (cached || !record_path.empty()) {
    key = functional_key(frame, fc);
    fc.key = &key;
  }
  if (cached) {
    const std::filesystem::path dir = config.sim.functional_cache;
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (!std::filesystem::is_directory(dir))
      throw std::invalid_argument("sim.functional_cache: " + dir.string() + ": not a folder and cannot be made");
    record_path = dir / cache_file_name(key, to_json(config).at("pb").dump());
    // A sample's record would hold its tiles only: without the file, the run keeps nothing.
    if (fc.sampled && !std::filesystem::exists(record_path)) record_path.clear();
  }
  if (!record_path.empty()) {
    if (config.sim.fidelity == Fidelity::rtl)
      throw std::invalid_argument("sim.functional_record: not at fidelity rtl (the Verilated EVU checks every tile "
                                  "against the computed one); run rtl without it");
    const auto r0 = std::chrono::steady_clock::now();
    if (std::filesystem::exists(record_path)) {
      replay = std::make_unique<FunctionalRecord>(FunctionalRecord::load(record_path));
      functional = "replayed";
    } else {
      // Written at the end: a folder that is not there fails now, not after the simulation.
      const std::filesystem::path dir = record_path.has_parent_path() ? record_path.parent_path() : ".";
      if (!std::filesystem::is_directory(dir))
        throw std::invalid_argument("sim.functional_record: " + record_path.string() + ": no folder " + dir.string());
      fc.record = true;
      functional = "recorded";
    }
    record_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - r0).count();
  }
  FrameWork work(frame, fc, std::move(replay));
  const bool event_driven = config.sim.fidelity != Fidelity::analytic;
  Tiler tiler("tiler", config, work, event_driven && !options.vcd.empty());
  tiler.prepare();
  out.host_prepare_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  if (event_driven) {
    sc_core::sc_trace_file* tf = nullptr;
    if (!options.vcd.empty()) {
      std::string base = options.vcd;
      if (base.size() > 4 && base.substr(base.size() - 4) == ".vcd") base.resize(base.size() - 4);
      tf = sc_core::sc_create_vcd_trace_file(base.c_str());
      tf->set_time_unit(1, sc_core::SC_PS);
      tiler.trace(tf);
    }
    sc_core::sc_start();
    if (tf) sc_core::sc_close_vcd_trace_file(tf);
    if (!work.failure().empty()) throw std::runtime_error(work.failure());
    if (!tiler.frame_done())
      throw std::logic_error("the simulation ran out of events before the frame was written (a deadlock in the model)");
    out.cycles = fc.sampled ? uint64_t(std::llround(tiler.scheduler().frame_estimate())) : tiler.simulated_cycles();
  } else {
    out.cycles = tiler.run_analytic();
  }
  tiler.memory().finish(out.cycles);
  work.finish();
  g_reports = nullptr;
  out.host_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (fc.record) {  // only a run that finished writes its record
    const auto r0 = std::chrono::steady_clock::now();
    work.record().save(record_path);
    record_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - r0).count();
  }

  outputs::Result& r = out.result;
  r.width = frame.width;
  r.height = frame.height;
  r.samples = uint32_t(frame.samples.size());
  r.ids = work.ids();
  r.visible_area = work.visible_area();
  r.tiles = work.tile_table();
  nlohmann::json totals = work.totals();
  totals["cycles"] = out.cycles;
  totals["param_buffer_bytes"] = tiler.param_buffer_bytes();
  totals["param_buffer_peak_bytes"] = tiler.param_buffer_peak();
  // Where each segment's geometry ended: measured at the event-driven levels but auto (whose
  // geometry estimate is in "sampling"); null at the closed form and at auto.
  totals["geometry_end_cycles"] = event_driven && !fc.sampled ? nlohmann::json(tiler.geometry_end_cycles()) : nlohmann::json(nullptr);
  totals["dram_bytes"] = tiler.dram_bytes();
  totals["evu_busy_cycles"] = tiler.evu_busy_cycles();
  totals["memory_bound_share"] = tiler.memory_bound_share(out.cycles);
  totals["dram_utilisation"] = tiler.memory().stats().value("utilisation");
  totals["energy"] = energy_json(config.energy, totals, tiler);
  const double seconds = double(out.cycles) / (config.sim.clock_mhz * 1e6);
  r.stats = {{"tool", "sim"},
             {"trace", options.trace_name},
             {"frame", options.frame_index},
             {"fidelity", to_string(config.sim.fidelity)},
             {"mode", to_string(config.sim.mode)},
             {"memory_model", tiler.memory().bandwidth_only() ? "bandwidth" : "detailed"},  // memory.model as resolved
             {"config", to_json(config)},
             {"totals", totals},
             {"frame_seconds_at_clock", seconds},
             {"units", units_json(tiler)},
             {"cores", tiler.cores_json()},
             {"triangles", work.triangle_accounts()},
             {"systemc_reports", out.systemc_reports},
             {"sampling", fc.sampled ? tiler.scheduler().sampling_json() : nlohmann::json(nullptr)},
             {"host_seconds", out.host_seconds},
             {"host_prepare_seconds", out.host_prepare_seconds},
             {"host_functional_seconds", work.host_functional_seconds()},
             {"host_rtl_seconds", work.host_rtl_seconds()},
             {"host_threads", vis::host_threads()},
             // sim.functional_record: "computed" (no record), "recorded" (computed and written) or
             // "replayed"; the seconds spent loading or writing the record (not in host_seconds
             // when written, at the end).
             {"functional", functional},
             // The record written or replayed (sim.functional_record, or sim.functional_cache's file).
             {"functional_record_file", std::string(functional) == "computed" ? nlohmann::json(nullptr)
                                                                              : nlohmann::json(record_path.string())},
             {"host_functional_record_seconds", record_seconds}};
  return out;
}

void write_sim_outputs(const SimOutput& out, const std::filesystem::path& dir) {
  std::filesystem::create_directories(dir);
  std::filesystem::remove(dir / "stats.json");
  {
    std::ofstream c(dir / "config.json");
    c << out.result.stats.at("config").dump(2) << '\n';
    if (!c) throw std::runtime_error((dir / "config.json").string() + ": write failed");
  }
  // Per-tile cycles heatmap: one pixel per tile, a FLOAT channel per cycles column.
  const outputs::TileTable& t = out.result.tiles;
  if (!t.rows.empty()) {
    std::vector<size_t> cols;
    for (size_t c = 0; c < t.columns.size(); ++c)
      if (t.columns[c].rfind("cycles_", 0) == 0 || t.columns[c] == "tile_cycles") cols.push_back(c);
    std::vector<std::vector<float>> planes(cols.size(), std::vector<float>(t.rows.size()));
    for (size_t i = 0; i < cols.size(); ++i)
      for (size_t r = 0; r < t.rows.size(); ++r) planes[i][r] = float(t.rows[r][cols[i]]);
    Imf::Header header(int(t.tiles_x), int(t.tiles_y));
    header.compression() = Imf::ZIP_COMPRESSION;
    Imf::FrameBuffer fb;
    for (size_t i = 0; i < cols.size(); ++i) {
      header.channels().insert(t.columns[cols[i]], Imf::Channel(Imf::FLOAT));
      fb.insert(t.columns[cols[i]], Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(planes[i].data()), sizeof(float),
                                               sizeof(float) * t.tiles_x));
    }
    const std::filesystem::path file = dir / "tile_cycles.exr", tmp = dir / "tile_cycles.exr.tmp";
    {
      Imf::OutputFile o(tmp.c_str(), header);
      o.setFrameBuffer(fb);
      o.writePixels(int(t.tiles_y));
    }
    std::filesystem::rename(tmp, file);
    // The same cycles as an image a person can open: whole-tile cycles, viridis, max in tEXt.
    const size_t total = t.column("tile_cycles");
    if (total != std::string::npos) {
      std::vector<double> v(t.rows.size());
      for (size_t r = 0; r < t.rows.size(); ++r) v[r] = double(t.rows[r][total]);
      write_heatmap_png(dir / "tile_cycles.png", v, t.tiles_x, t.tiles_y, "tile_cycles");
    }
  }
  outputs::write_result(out.result, dir);  // stats.json last: the directory is complete
}

}  // namespace tilevis::sim
