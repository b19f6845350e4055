// Comparisons: which point of producer b each point of producer a is compared with, the
// `tilevis compare` command line, and when a comparison is done.
#include <algorithm>
#include <optional>

#include "sweep/detail.h"

namespace tilevis::sweep {

namespace fs = std::filesystem;

namespace {

// The point of rule.b with a's scene (or workload and frame), resolution and samples, preferring the same tile, mode
// and configuration.
std::optional<size_t> partner(const Plan& plan, const CompareRule& r, const Point& a) {
  std::optional<size_t> best;
  int best_score = -1;
  for (size_t j = 0; j < plan.points.size(); ++j) {
    const Point& b = plan.points[j];
    if (b.producer != r.b || b.scene != a.scene || b.frame != a.frame || b.resolution != a.resolution ||
        b.samples != a.samples)
      continue;
    int score = 4 * (b.tile == a.tile) + 2 * (b.mode == a.mode || b.mode.empty()) + (b.config == a.config);
    if (score > best_score) best_score = score, best = j;
  }
  return best;
}

bool listed(const std::vector<std::string>& list, const std::string& item) {
  return list.empty() || std::find(list.begin(), list.end(), item) != list.end();
}

}  // namespace

namespace detail {

void plan_compares(const Sweep& sw, Plan& plan) {
  for (const CompareRule& r : sw.compares)
    for (size_t i = 0; i < plan.points.size(); ++i) {
      const Point& a = plan.points[i];
      if (a.producer != r.a || !listed(r.grids, a.grid) || !listed(r.modes, a.mode)) continue;
      if (std::optional<size_t> b = partner(plan, r, a))
        plan.compares.push_back({i, *b, r.explain, a.dir / ("vs-" + r.b)});
    }
}

}  // namespace detail

Command compare_command(const Plan& plan, const CompareJob& job, const std::string& tilevis, const fs::path& out) {
  const Point& a = plan.points[job.a];
  const Point& b = plan.points[job.b];
  const fs::path dir = out / job.dir, part = dir / ".part";
  Command c;
  c.argv = {tilevis, "compare", (out / a.dir).string(), (out / b.dir).string(), "-o", part.string()};
  if (job.explain) {
    c.argv.push_back("--explain");
    c.argv.push_back((out / a.trace).string());
  }
  c.renames = {{part / "compare.json", dir / "compare.json"}};
  return c;
}


bool compare_done(const Plan& plan, const CompareJob& job, const fs::path& out) {
  std::error_code ec;
  const fs::path c = out / job.dir / "compare.json";
  const fs::path a = out / plan.points[job.a].dir / "stats.json", b = out / plan.points[job.b].dir / "stats.json";
  if (!fs::is_regular_file(c, ec) || !fs::is_regular_file(a, ec) || !fs::is_regular_file(b, ec)) return false;
  auto tc = fs::last_write_time(c, ec);
  return tc >= fs::last_write_time(a, ec) && tc >= fs::last_write_time(b, ec);
}

}  // namespace tilevis::sweep
