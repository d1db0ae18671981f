// Benchmark (not a test): does the Monte Carlo reference converge as 1/sqrt(N)? For each standard
// scene named, the clouds-only reference at N and then 4N samples per pixel, and the ratio of the
// mean relative standard errors (2 for 1/sqrt(N) convergence; about 1 where heavy tails dominate).
// With --gpu the GPU path tracer's (headless OpenGL: llvmpipe here) instead of the CPU's.
// usage: bench_mc_convergence [--size WxH] [--spp N] [--threads T] [--no-peak-mis] [--gpu [--branch-slots K]] [--globe]
//        SCENE...
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "bench/bench_args.hpp"
#include "bench/standard_scenes.hpp"
#include "reference/monte_carlo.hpp"
#include "render/context.hpp"
#include "render/raymarcher.hpp"
#include "render/shader_loader.hpp"
#include "volume/grid_mean.hpp"

int main(int argc, char** argv) {
  int w = 48, h = 27, spp = 64, threads = 0, slots = cv::render::PathTraceSettings{}.branch_slots;
  bool no_peak_mis = false, gpu = false, globe = false;
  std::vector<std::string> scenes;
  namespace ba = cv::bench_args;
  const int code = ba::parse("bench_mc_convergence",
                             "usage: bench_mc_convergence [--size WxH] [--spp N] [--threads T] [--no-peak-mis] [--gpu [--branch-slots K]] [--globe] SCENE...\n"
                             "  the clouds-only Monte Carlo reference of each standard scene at N and 4N samples per pixel;\n"
                             "  prints the mean relative standard errors and their ratio (2: 1/sqrt(N) convergence)\n"
                             "  --gpu             the GPU path tracer (headless OpenGL) instead of the CPU reference\n"
                             "  --branch-slots K  with --gpu: branches of the droplets' peak a pixel's stack holds (default 16)\n"
                             "  --globe           with the scene's ground under the clouds (its constant albedo), not clouds alone\n",
                             argc, argv,
                             {ba::size("--size", w, h), ba::integer("--spp", spp), ba::integer("--threads", threads, 0, 1024),
                              ba::flag("--no-peak-mis", no_peak_mis), ba::flag("--gpu", gpu), ba::integer("--branch-slots", slots, 0, 64), ba::flag("--globe", globe)},
                             &scenes);
  if (code >= 0) return code;
  const bool peak_mis = !no_peak_mis;
  if (scenes.empty()) scenes = {"stratocumulus", "cumulus_field"};
  std::unique_ptr<cv::render::GlContext> ctx;
  std::unique_ptr<cv::render::ShaderLoader> loader;
  std::unique_ptr<cv::render::GpuRaymarcher> tracer;
  if (gpu) {
    try {
      ctx = cv::render::make_headless_context();
      loader = std::make_unique<cv::render::ShaderLoader>(std::vector<std::filesystem::path>{cv::render::ShaderLoader::default_shader_dir()});
      tracer = std::make_unique<cv::render::GpuRaymarcher>(*loader);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "bench_mc_convergence: --gpu: %s\n", e.what());
      return 1;
    }
  }
  std::printf("%-20s %8s %10s %8s %10s %8s %7s %11s%s\n", "scene", "N", "rel.s.e.", "s", "4N rel.s.e.", "s", "ratio", "mean at 4N",
              gpu ? "  slots  full-stack vertices" : "");
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
    m.features.atmosphere = false;
    m.features.globe = globe;
    m.medium.ambient = 0.0, m.medium.noise_amount = 0.0;
    if (!(m.medium.droplet_diameter_um > 0.0)) m.medium.droplet_diameter_um = 20.0;
    cv::core::MonteCarloSettings mc;
    mc.threads = static_cast<unsigned>(threads);
    mc.peak_mis = peak_mis;
    const cv::core::MonteCarloRenderer r(sc.grid, ext, sc.camera, sc.sun, m, mc);
    cv::render::PathTraceSettings pt;
    pt.peak_mis = peak_mis;
    pt.branch_slots = slots;
    cv::render::PathTraceStats extra;
    if (gpu) tracer->upload(sc.grid, ext);
    cv::core::MonteCarloImage img = gpu ? cv::core::MonteCarloImage{} : r.start();
    auto add = [&](int n) {
      if (gpu) {
        tracer->trace_paths(img, sc.camera, sc.sun, m, n, pt, &extra);
      } else {
        r.add_samples(img, n);
      }
    };
    using clock = std::chrono::steady_clock;
    auto t0 = clock::now();
    add(spp);
    const double s1 = std::chrono::duration<double>(clock::now() - t0).count();
    const double e1 = img.mean_relative_standard_error();
    t0 = clock::now();
    add(3 * spp);
    const double s4 = s1 + std::chrono::duration<double>(clock::now() - t0).count();
    const double e4 = img.mean_relative_standard_error();
    double mean = 0.0;  // the image's mean luminance
    for (std::size_t i = 0; i < img.lum_sum.size(); ++i) mean += img.luminance(i) / static_cast<double>(img.lum_sum.size());
    std::printf("%-20s %8d %10.4g %8.1f %10.4g %8.1f %7.3f %11.5g", name.c_str(), spp, e1, s1, e4, s4, e1 / e4, mean);
    if (gpu) {
      std::printf("  %5d  %.3g per path", extra.branch_slots,
                  double(extra.splits_without_room) / double(std::max<std::uint64_t>(img.stats.paths, 1)));
      if (extra.near_loop_budget) std::printf(" (%llu walks near llvmpipe's loop budget)", static_cast<unsigned long long>(extra.near_loop_budget));
    }
    std::printf("\n");
    std::fflush(stdout);
  }
  return 0;
}
