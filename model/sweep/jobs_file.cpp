// The jobs file: one independent shell line per job not yet done, in three stages, for a
// scheduler of the user's choosing.
#include <fstream>
#include <sstream>

#include "sweep/detail.h"

namespace tilevis::sweep {

namespace fs = std::filesystem;
using namespace detail;

void write_jobs_file(const Sweep& sw, const Plan& plan, const std::map<std::string, Availability>& av,
                     const RunOptions& opt, const fs::path& file) {
  std::ostringstream o;
  const std::string sweep_file = fs::absolute(sw.file).lexically_normal().string();
  o << "# tilevis sweep " << sweep_file << " -o " << opt.out.string() << ": one command line per job not yet done.\n"
    << "# Lines within a stage are independent of each other; run the stages in order. A point is done when its\n"
    << "# stats.json exists (written last, atomically); afterwards make the report with:\n"
    << "#   " << shell_quote(opt.tilevis) << " sweep " << shell_quote(sweep_file) << " -o "
    << shell_quote(opt.out.string()) << " --report-only\n";
  size_t n = 0;
  o << "# stage 1: traces\n";
  for (const TraceJob& t : plan.traces)
    if (!trace_done(t, opt.out)) {
      o << "mkdir -p " << shell_quote((opt.out / t.file).parent_path().string()) << " && "
        << trace_command(sw, t, opt.tilevis, opt.out).shell() << '\n';
      ++n;
    }
  o << "# stage 2: points\n";
  for (const Point& p : plan.points) {
    if (point_done(p, opt.out)) continue;
    const Availability& a = av.at(p.producer);
    if (!a.available) {
      o << "# unavailable here (" << a.why << "): " << point_command(sw, p, opt.tilevis, opt.out).shell() << '\n';
      continue;
    }
    o << point_command(sw, p, opt.tilevis, opt.out).shell();
    if (const std::string& r = sw.producer(p.producer).exclusive; !r.empty())
      o << "  # exclusive: " << r << " (one such job at a time, for honest timings)";
    o << '\n';
    ++n;
  }
  o << "# stage 3: comparisons\n";
  for (const CompareJob& c : plan.compares) {
    if (compare_done(plan, c, opt.out) || !av.at(plan.points[c.a].producer).available ||
        !av.at(plan.points[c.b].producer).available)
      continue;
    o << compare_command(plan, c, opt.tilevis, opt.out).shell() << '\n';
    ++n;
  }
  o << "# " << n << " jobs\n";
  if (file.has_parent_path()) fs::create_directories(file.parent_path());
  std::ofstream f(file);
  f << o.str();
  if (!f) throw SweepError("cannot write " + file.string());
}

}  // namespace tilevis::sweep
