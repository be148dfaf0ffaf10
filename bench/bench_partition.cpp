// bench_partition TRIANGLES — generates a level-set design of about TRIANGLES triangles
// (a row of arches on keep-in feet, scenes.h) and prints seconds and peak memory per
// stage of the pipeline. Run by bench/run for 10k, 100k and 1M triangles.
// bench_partition netN — the same for a net of N × N cells (genus N², scenes.h) at h 0.12.
#include <sys/resource.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <map>
#include <string>

#include "pipeline/pipeline.h"
#include "scenes.h"

using namespace genbrep;

namespace {

double resident_mib() {
  std::ifstream statm("/proc/self/statm");
  long pages = 0, resident = 0;
  statm >> pages >> resident;
  return resident * (sysconf(_SC_PAGESIZE) / 1048576.0);
}

}  // namespace

int main(int argc, char** argv) {
  const std::string what = argc > 1 ? argv[1] : "50000";
  const bool net = what.rfind("net", 0) == 0;
  double h = 0.12;
  if (!net) {
    // Triangle count scales with 1/h²: calibrate on a coarse grid, then scale.
    const double target = std::stod(what);
    const double h0 = 0.1;
    const double t0 = static_cast<double>(testing::arch_row_scene(h0, 2).design.triangles.rows());
    h = h0 * std::sqrt(t0 / target);
  }
  const auto start = std::chrono::steady_clock::now();
  testing::Scene scene = net ? testing::net_scene(h, std::stoi(what.substr(3)))
                             : testing::arch_row_scene(h, 2);
  const std::chrono::duration<double> generation = std::chrono::steady_clock::now() - start;
  const double base_mib = resident_mib();

  Inputs inputs;
  inputs.design = {scene.name, std::move(scene.design)};
  inputs.solids = std::move(scene.solids);
  std::map<std::string, double> peak;
  Context context([&](const std::string& stage, double) {
    peak[stage] = std::max(peak[stage], resident_mib());
    return true;
  });
  Options options;
  options.incidence.tolerance = h;
  const Result result = convert(inputs, options, context);
  std::printf("design: %ld triangles (h = %.4f, generated in %.2f s), %d organic components, %zu loops\n",
              static_cast<long>(result.design.triangles.rows()), h, generation.count(),
              result.partition.organic_components, result.partition.loops.size());
  int fallback = 0, quads = 0;
  for (const QuadStats& q : result.quads.stats) fallback += q.fallback, quads += q.quads;
  std::printf("cages: %zu (%d quads; %d of them the fallback), composed: %s (contact %.1f s, "
              "Booleans %.1f s)\n",
              result.quads.cages.size(), quads, fallback,
              result.composed.report.ok ? "ok" : "NOT ok", result.composed.report.seconds_contact,
              result.composed.report.seconds_boolean);
  for (size_t c = 0; c < result.quads.stats.size(); ++c) {
    const QuadStats& q = result.quads.stats[c];
    std::printf("  cage %zu: %d quads (%.2fx what the size field asks), interior valence 4 %.1f%%, "
                "boundary valence 3 %.1f%%, mean corner deviation %.1f deg (%d quads over 45 deg), "
                "%d irregular (%d away from singularities)%s\n",
                c, q.quads, q.size_field_quads > 0 ? q.quads / q.size_field_quads : 0.0,
                100 * q.interior_valence4_fraction(), 100 * q.boundary_valence3_fraction(),
                q.mean_angle_deviation_deg, q.skewed_quads, q.irregular_vertices,
                q.irregular_off_singularities,
                q.fallback ? ", FALLBACK" : "");
  }
  if (net) {  // why a net's cage is what it is, and how its solid was composed
    for (const std::string& d : result.quads.notes)
      if (d.find("layout") != std::string::npos || d.find("squared") != std::string::npos)
        std::printf("  quad: %s\n", d.c_str());
    for (const std::string& d : result.quads.diagnostics) std::printf("  quad: warning: %s\n", d.c_str());
    for (const Fitted& f : result.fitted) {
      const FitReport& r = f.report;
      std::printf("  fit %d: %d quads, %d rounds, %d refinements, max design->limit %.4f, "
                  "limit->design %.4f, boundary %.4f (delta %.4f)%s\n",
                  r.component, r.quads, r.rounds, r.refinements, r.max_design_to_limit,
                  r.max_limit_to_design, r.max_boundary_distance, r.delta,
                  r.kept_initial ? ", kept the initial cage" : "");
      for (const std::string& d : r.diagnostics) std::printf("  fit: %s\n", d.c_str());
    }
    for (const std::string& d : result.composed.report.diagnostics) std::printf("  compose: %s\n", d.c_str());
  }
  std::printf("%-10s %10s %16s\n", "stage", "seconds", "peak RSS (MiB)");
  double total = 0;
  for (const auto& t : result.timings) {
    std::printf("%-10s %10.3f %16.1f\n", t.stage.c_str(), t.seconds, peak[t.stage]);
    total += t.seconds;
  }
  struct rusage usage {};
  getrusage(RUSAGE_SELF, &usage);
  std::printf("%-10s %10.3f %16.1f  (input arrays alone: %.1f MiB; process peak %.1f MiB)\n", "total", total,
              resident_mib(), base_mib, usage.ru_maxrss / 1024.0);
  return 0;
}
