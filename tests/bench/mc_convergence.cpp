// Benchmark (not a test): does the Monte Carlo reference converge as 1/sqrt(N)? For each standard
// scene named, the clouds-only reference at N and then 4N samples per pixel, and the ratio of the
// mean relative standard errors (2 for 1/sqrt(N) convergence; about 1 where heavy tails dominate).
// usage: bench_mc_convergence [--size WxH] [--spp N] [--threads T] [--no-peak-mis] SCENE...
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "bench/bench_args.hpp"
#include "bench/standard_scenes.hpp"
#include "reference/monte_carlo.hpp"
#include "volume/grid_mean.hpp"

int main(int argc, char** argv) {
  int w = 48, h = 27, spp = 64, threads = 0;
  bool no_peak_mis = false;
  std::vector<std::string> scenes;
  namespace ba = cv::bench_args;
  const int code = ba::parse("bench_mc_convergence",
                             "usage: bench_mc_convergence [--size WxH] [--spp N] [--threads T] [--no-peak-mis] SCENE...\n"
                             "  the clouds-only Monte Carlo reference of each standard scene at N and 4N samples per pixel;\n"
                             "  prints the mean relative standard errors and their ratio (2: 1/sqrt(N) convergence)\n",
                             argc, argv,
                             {ba::size("--size", w, h), ba::integer("--spp", spp), ba::integer("--threads", threads, 0, 1024),
                              ba::flag("--no-peak-mis", no_peak_mis)},
                             &scenes);
  if (code >= 0) return code;
  const bool peak_mis = !no_peak_mis;
  if (scenes.empty()) scenes = {"stratocumulus", "cumulus_field"};
  std::printf("%-20s %8s %10s %8s %10s %8s %7s\n", "scene", "N", "rel.s.e.", "s", "4N rel.s.e.", "s", "ratio");
  for (const std::string& name : scenes) {
    cv::bench::StandardScene sc;
    try {
      sc = cv::bench::standard_scene(name, w, h);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "bench_mc_convergence: %s\n", e.what());
      return 2;
    }
    const cv::core::GridMeanExtinction ext = cv::core::grid_mean_extinction(sc.grid, sc.data);
    cv::core::MarchSettings m = sc.march;  // clouds only, as the bench's references
    m.features.atmosphere = m.features.globe = false;
    m.medium.ambient = 0.0, m.medium.noise_amount = 0.0;
    if (!(m.medium.droplet_diameter_um > 0.0)) m.medium.droplet_diameter_um = 20.0;
    cv::core::MonteCarloSettings mc;
    mc.threads = static_cast<unsigned>(threads);
    mc.peak_mis = peak_mis;
    const cv::core::MonteCarloRenderer r(sc.grid, ext, sc.camera, sc.sun, m, mc);
    cv::core::MonteCarloImage img = r.start();
    using clock = std::chrono::steady_clock;
    auto t0 = clock::now();
    r.add_samples(img, spp);
    const double s1 = std::chrono::duration<double>(clock::now() - t0).count();
    const double e1 = img.mean_relative_standard_error();
    t0 = clock::now();
    r.add_samples(img, 3 * spp);
    const double s4 = s1 + std::chrono::duration<double>(clock::now() - t0).count();
    const double e4 = img.mean_relative_standard_error();
    std::printf("%-20s %8d %10.4g %8.1f %10.4g %8.1f %7.3f\n", name.c_str(), spp, e1, s1, e4, s4, e1 / e4);
    std::fflush(stdout);
  }
  return 0;
}
