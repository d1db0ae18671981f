// Benchmark (not a test): the multiple-scattering models against the Monte Carlo reference on the
// standard scenes, clouds only, with the CPU kernel (the GPU runs the same kernel). For each scene:
// the reference's mean luminance and its noise, then per model the image-mean bias and the
// noise-corrected relative RMSE (app/bench/metrics image_error), and the two-stream source's build
// time. usage: bench_ms_model [--size WxH] [--spp N] [SCENE...]
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "bench/metrics.hpp"
#include "bench/standard_scenes.hpp"
#include "kernel/ms_source.hpp"
#include "reference/monte_carlo.hpp"
#include "reference/raymarcher.hpp"
#include "volume/grid_mean.hpp"

int main(int argc, char** argv) {
  int w = 32, h = 18, spp = 256;
  std::vector<std::string> scenes;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") {
      std::printf("usage: bench_ms_model [--size WxH] [--spp N] [SCENE...]\n"
                  "  octave sum and two-stream source against the Monte Carlo reference, clouds only\n");
      return 0;
    } else if (a == "--size" && i + 1 < argc) {
      if (std::sscanf(argv[++i], "%dx%d", &w, &h) != 2 || w < 1 || h < 1) {
        std::fprintf(stderr, "bench_ms_model: --size: found %s, expected WxH\n", argv[i]);
        return 2;
      }
    } else if (a == "--spp" && i + 1 < argc) {
      spp = std::atoi(argv[++i]);
      if (spp < 1) {
        std::fprintf(stderr, "bench_ms_model: --spp: found %s, expected an integer >= 1\n", argv[i]);
        return 2;
      }
    } else if (!a.empty() && a[0] != '-') {
      scenes.push_back(a);
    } else {
      std::fprintf(stderr, "bench_ms_model: unknown option %s (see --help)\n", a.c_str());
      return 2;
    }
  }
  if (scenes.empty()) {
    for (const auto& n : cv::bench::standard_scene_names()) if (n != "clear_sky") scenes.push_back(n);
  }
  using clock = std::chrono::steady_clock;
  std::printf("%-14s %10s %7s | %-18s | %-18s | %s\n", "scene", "MC lum", "noise", "octaves: bias rmse",
              "two-stream: bias rmse", "source ms");
  for (const std::string& name : scenes) {
    cv::bench::StandardScene sc;
    try {
      sc = cv::bench::standard_scene(name, w, h);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "bench_ms_model: %s\n", e.what());
      return 2;
    }
    const cv::core::GridMeanExtinction ext = cv::core::grid_mean_extinction(sc.grid, sc.data);
    cv::core::MarchSettings m = sc.march;
    m.features.atmosphere = m.features.globe = false;
    m.medium.ambient = 0.0, m.medium.noise_amount = 0.0;
    if (!(m.medium.droplet_diameter_um > 0.0)) m.medium.droplet_diameter_um = 20.0;
    cv::core::MonteCarloSettings mc;
    const cv::core::MonteCarloImage img = cv::core::render_monte_carlo(sc.grid, ext, sc.camera, sc.sun, m, mc, spp);
    const std::vector<glm::dvec3> ref = img.radiance();
    std::vector<double> var(ref.size());
    double lum = 0.0, nvar = 0.0;
    for (std::size_t i = 0; i < ref.size(); ++i) {
      const double se = img.luminance_standard_error(i);
      var[i] = std::isfinite(se) ? se * se : 0.0;
      lum += img.luminance(i);
      nvar += var[i];
    }
    std::printf("%-14s %10.4g %6.1f%% |", name.c_str(), lum / ref.size(), 100.0 * std::sqrt(nvar) / lum);
    for (bool two : {false, true}) {
      cv::core::MarchSettings mm = m;
      mm.medium.ms_two_stream = two;
      const cv::core::ReferenceImage r = cv::core::render_reference(sc.grid, ext, sc.camera, sc.sun, mm);
      const cv::bench::ImageError e = cv::bench::image_error(r.radiance, ref, var);
      std::printf(" %+7.1f%% %7.1f%% |", 100.0 * e.rel_bias, 100.0 * e.rel_rmse);
    }
    const auto prepared = cv::core::prepare_volume(sc.grid, ext);
    const auto t0 = clock::now();
    const cv::core::MsSource src = cv::core::build_ms_source(
        prepared, cv::core::ms_source_key(m, glm::dvec3(0.0, 0.0, 1.0)));
    std::printf(" %.2f\n", std::chrono::duration<double, std::milli>(clock::now() - t0).count());
    (void)src;
    std::fflush(stdout);
  }
  return 0;
}
