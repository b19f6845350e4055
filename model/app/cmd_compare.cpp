// tilevis compare A B: sample agreement, mismatches, per-triangle area error and
// per-tile counter differences between two producers' canonical outputs.
#include <cmath>
#include <fstream>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "commands.h"
#include "tilevis/outputs.h"
#include "tilevis/trace.h"
#include "visibility/explain.h"
#include "visibility/setup.h"

namespace tilevis::app {

Command add_compare_command(CLI::App& app) {
  struct Args {
    std::string a, b, out, explain;
  };
  auto args = std::make_shared<Args>();
  auto* cmd = app.add_subcommand("compare", "Compare two result directories (golden, truth, sim, cuda)");
  cmd->add_option("a", args->a, "First result directory")->required()->check(CLI::ExistingDirectory);
  cmd->add_option("b", args->b, "Second result directory")->required()->check(CLI::ExistingDirectory);
  cmd->add_option("-o,--output", args->out, "Directory for compare.json (default: the first result directory)");
  cmd->add_option("--explain", args->explain,
                  "Trace both results were made from: classify every mismatched sample by its cause")
      ->check(CLI::ExistingFile);
  return {cmd, [args]() {
            auto a = outputs::read_result(args->a);
            auto b = outputs::read_result(args->b);
            auto c = outputs::compare(a, b);
            std::filesystem::path out = args->out.empty() ? std::filesystem::path(args->a) : std::filesystem::path(args->out);
            std::filesystem::create_directories(out);
            nlohmann::json j = c.to_json();
            j["a"] = args->a;
            j["b"] = args->b;
            // Results of different traces (or frames) compare as noise: say so.
            const std::string ha = a.stats.value("trace_fnv1a64", ""), hb = b.stats.value("trace_fnv1a64", "");
            const bool same_frame = a.stats.value("frame", 0u) == b.stats.value("frame", 0u);
            if (!ha.empty() && !hb.empty()) j["same_trace"] = ha == hb && same_frame;
            if ((!ha.empty() && !hb.empty() && ha != hb) || !same_frame)
              fmt::print(stderr, "compare: warning: {} and {} were made from different traces or frames ({} frame {}, "
                                 "{} frame {}): the agreement below compares unrelated images\n",
                         args->a, args->b, a.stats.value("trace", "?"), a.stats.value("frame", 0u),
                         b.stats.value("trace", "?"), b.stats.value("frame", 0u));
            std::ofstream(out / "compare.json") << j.dump(2) << '\n';
            fmt::print("compare {} ({}) vs {} ({})\n", args->a, a.stats.value("tool", "?"), args->b,
                       b.stats.value("tool", "?"));
            fmt::print("  sample agreement     {:.6f} %  ({} of {} covered samples differ)\n", 100 * c.sample_agreement,
                       c.mismatched_samples, c.samples_compared);
            if (std::isnan(c.max_area_rel_error))
              fmt::print("  max area rel. error  n/a (visible areas missing in one result)\n");
            else
              fmt::print("  max area rel. error  {:.3g}  ({} triangles over 1e-9)\n", c.max_area_rel_error,
                         c.area_mismatches);
            fmt::print("  tile counter cells that differ: {} (columns: {})\n", c.tile_counter_mismatches,
                       fmt::join(c.compared_columns, ", "));
            if (!args->explain.empty()) {
              uint32_t frame = a.stats.value("frame", 0u);
              trace::Trace t = trace::read(args->explain);
              if (frame >= t.frames.size()) throw std::runtime_error(args->explain + ": no frame " + std::to_string(frame));
              trace::Frame f = std::move(t.frames[frame]);
              // The trace must be the one the results come from: same size and triangle count (the
              // sample count may have been overridden with --samples).
              const uint64_t tris = a.stats.contains("totals") ? a.stats["totals"].value("triangles_in", uint64_t{0}) : 0;
              if (f.width != a.width || f.height != a.height || (tris && tris != f.triangle_count()))
                throw std::runtime_error(fmt::format(
                    "--explain {}: frame {} is {}x{} with {} triangles, but {} holds a {}x{} result of {} triangles "
                    "({}): explain needs the trace the results were made from",
                    args->explain, frame, f.width, f.height, f.triangle_count(), args->a, a.width, a.height, tris,
                    a.stats.value("trace", "?")));
              f.samples = trace::standard_samples(a.samples, f.subpixel_bits);
              vis::SetupConfig sc;
              sc.depth_bits = a.stats["config"].value("depth_bits", 24u);
              vis::MismatchReport m = vis::explain_mismatches(vis::primitive_setup(f, sc), a.ids, b.ids);
              nlohmann::json kinds = m.kinds;
              j["mismatch_causes"] = kinds;
              std::ofstream(out / "compare.json") << j.dump(2) << '\n';
              for (const auto& [kind, count] : m.kinds) fmt::print("  cause: {:>8} samples: {}\n", count, kind);
              for (const auto& e : m.examples) fmt::print("    e.g. {}\n", e);
            }
            fmt::print("  wrote {}\n", (out / "compare.json").string());
            return 0;
          }};
}

}  // namespace tilevis::app
