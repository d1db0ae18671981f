// Times the difference grid of `cloudviewer compare` (core::compare_steps: both sources read onto
// the common grid by the sampler, their maps derived, presence and differences) for two global
// ERA5-sized volumes made in memory: A at 0.25 degrees, B at 0.5 degrees (the common grid is B's),
// NLEV levels each. Prints figures; no pass/fail (docs/BENCHMARKS.md).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "analysis/compare.hpp"

namespace {
using namespace cv::core;

VolumeGrid global(double step_deg, int levels) {
  VolumeGrid g;
  g.lon_deg = {0.0, step_deg, static_cast<int>(std::lround(360.0 / step_deg))};
  g.lat_deg = {-90.0, step_deg, static_cast<int>(std::lround(180.0 / step_deg)) + 1};
  g.alt_m = {0.0, 16000.0 / (levels - 1), levels};
  return g;
}

// Smooth cloud bands: fraction and liquid extinction as functions of position.
TimeStepData field(const VolumeGrid& g, double phase) {
  TimeStepData d;
  auto& cf = d[Field::CloudFraction];
  auto& el = d[Field::ExtinctionLiquid];
  cf.resize(g.points());
  el.resize(g.points());
  for (int k = 0; k < g.alt_m.count; ++k)
    for (int j = 0; j < g.lat_deg.count; ++j)
      for (int i = 0; i < g.lon_deg.count; ++i) {
        const double s = std::sin(g.lon_deg.at(i) * 0.07 + phase) * std::cos(g.lat_deg.at(j) * 0.11) * std::sin(k * 0.4);
        const std::size_t p = g.index(i, j, k);
        cf[p] = static_cast<float>(s > 0.3 ? s : 0.0);
        el[p] = static_cast<float>(s > 0.3 ? 1e-3 * s : 0.0);
      }
  return d;
}
}  // namespace

int main(int argc, char** argv) {
  const int levels = argc > 1 ? std::atoi(argv[1]) : 37;
  const VolumeGrid ga = global(0.25, levels), gb = global(0.5, levels);
  const TimeStepData a = field(ga, 0.0), b = field(gb, 0.2);
  const auto t0 = std::chrono::steady_clock::now();
  const VolumeGrid common = common_grid(ga, gb, grid_overlap(ga, gb));
  const Comparison c = compare_steps(ga, a, gb, b, common);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::size_t only_a = 0;
  for (Presence p : c.columns) only_a += p == Presence::OnlyA;
  std::printf("A %d x %d x %d (0.25 deg), B %d x %d x %d (0.5 deg): common grid %d x %d x %d built and compared in %.2f s "
              "(%zu A-only columns)\n", ga.lon_deg.count, ga.lat_deg.count, ga.alt_m.count, gb.lon_deg.count, gb.lat_deg.count,
              gb.alt_m.count, common.lon_deg.count, common.lat_deg.count, common.alt_m.count, s, only_a);
  return 0;
}
