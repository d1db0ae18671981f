// What the GPU raymarcher leaves out must not show: with the whole cloud layer in the Earth's
// shadow it skips every sun march and octave sum (u_sun_down), and the image is bit for bit the
// one its per-sample test gives, and matches the CPU reference.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "reference/raymarcher.hpp"
#include "render/context.hpp"
#include "render/raymarcher.hpp"
#include "bench/standard_scenes.hpp"

#include "../core/night_sun.hpp"

namespace {
using namespace cv;

TEST(LeaveOut, NightOnTheGpuIsThePerSampleImage) {
  bench::StandardScene sc = bench::standard_scene("cumulus_field", 32, 18);
  sc.sun = test::sun_just_down(sc);
  sc.march.features.atmosphere = sc.march.features.globe = true;
  sc.march.medium.ambient = 1.0;
  auto ctx = render::make_headless_context();
  render::ShaderLoader loader({render::ShaderLoader::default_shader_dir()});
  render::GpuRaymarcher gpu(loader);
  const core::GridMeanExtinction medium = core::grid_mean_extinction(sc.grid, sc.data);
  gpu.upload(sc.grid, medium);
  using clock = std::chrono::steady_clock;
  sc.march.features.leave_out_night = false;
  gpu.render(sc.camera, sc.sun, sc.march);  // warm-up: the first render's timing is not the march's
  auto t0 = clock::now();
  const auto per_sample = gpu.render(sc.camera, sc.sun, sc.march);
  const double t_per_sample = std::chrono::duration<double>(clock::now() - t0).count();
  EXPECT_FALSE(gpu.last_stats().sun_down);
  sc.march.features.leave_out_night = true;
  t0 = clock::now();
  const auto night = gpu.render(sc.camera, sc.sun, sc.march);
  const double t_night = std::chrono::duration<double>(clock::now() - t0).count();
  EXPECT_TRUE(gpu.last_stats().sun_down);
  EXPECT_EQ(gpu.last_stats().sun_samples, 0u);
  const core::ReferenceImage cpu = core::render_reference(sc.grid, medium, sc.camera, sc.sun, sc.march);
  EXPECT_TRUE(cpu.stats.sun_down);
  double max_l = 0.0, worst = 0.0;
  for (const auto& l : cpu.radiance) max_l = std::max({max_l, l.x, l.y, l.z});
  ASSERT_GT(max_l, 0.0) << "the twilight sky should show";
  for (std::size_t i = 0; i < night.size(); ++i) {
    ASSERT_EQ(night[i], per_sample[i]) << "pixel " << i;
    for (int k = 0; k < 3; ++k) worst = std::max(worst, std::abs(night[i][k] - cpu.radiance[i][k]) / max_l);
  }
  EXPECT_LT(worst, 2e-3);  // the sky-and-globe tests' bound (scenes_test.cpp)
  std::printf("cumulus_field at night, 32x18 on this GPU: per sample %.3f s, sun left out %.3f s (after a warm-up "
              "render); GPU vs CPU worst %.3g of the brightest pixel\n",
              t_per_sample, t_night, worst);
}

// Fewer sun steps in thin cloud on the GPU: fewer sun samples counted, the image within the
// GPU-vs-CPU tolerance of the all-steps one, and the time of both taken in turns (the machine is
// shared: interleaved repeats, the fastest of each kept) for thin cirrus and the towering cell.
TEST(LeaveOut, ThinCloudTakesFewerSunStepsOnTheGpu) {
  auto ctx = render::make_headless_context();
  render::ShaderLoader loader({render::ShaderLoader::default_shader_dir()});
  render::GpuRaymarcher gpu(loader);
  for (const char* name : {"thin_cirrus", "towering_cell"}) {
    const bench::StandardScene sc = bench::standard_scene(name, 96, 54);
    gpu.upload(sc.grid, core::grid_mean_extinction(sc.grid, sc.data));
    core::MarchSettings all = sc.march;
    all.quality.max_sun_step_optical_depth = 0.0;
    gpu.render(sc.camera, sc.sun, all);  // warm-up
    double best[2] = {1e30, 1e30};
    std::uint64_t samples[2] = {0, 0};
    std::vector<glm::vec4> img[2];
    for (int r = 0; r < 3; ++r) {
      for (int k = 0; k < 2; ++k) {
        const auto t0 = std::chrono::steady_clock::now();
        img[k] = gpu.render(sc.camera, sc.sun, k == 0 ? all : sc.march);
        best[k] = std::min(best[k], std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
        samples[k] = gpu.last_stats().sun_samples;
      }
    }
    double brightest = 0.0, worst = 0.0;
    for (const auto& p : img[0]) brightest = std::max({brightest, double(p.x), double(p.y), double(p.z)});
    for (std::size_t i = 0; i < img[0].size(); ++i) {
      for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(double(img[0][i][c]) - img[1][i][c]) / brightest);
    }
    std::printf("%-14s 96x54 on this GPU: all sun steps %.1f ms (%llu sun samples), fewer %.1f ms (%llu); difference "
                "worst %.2g of the brightest pixel\n",
                name, 1e3 * best[0], static_cast<unsigned long long>(samples[0]), 1e3 * best[1],
                static_cast<unsigned long long>(samples[1]), worst);
    EXPECT_LE(samples[1], samples[0]) << name;
    EXPECT_LT(worst, 1e-3) << name;
  }
}

}  // namespace

namespace {
// The octave gate's leave-out is counted: on thin cirrus the GPU evaluates fewer octave terms than
// the classic sum would (the count is the CPU reference's, to the few samples float rounding tips),
// and with the gate off it evaluates them all.
TEST(LeaveOut, TheGateCountsTheOctaveTermsItLeavesOut) {
  bench::StandardScene sc = bench::standard_scene("thin_cirrus", 32, 18);
  sc.march.quality.octaves = 4;
  auto ctx = render::make_headless_context();
  render::ShaderLoader loader({render::ShaderLoader::default_shader_dir()});
  render::GpuRaymarcher gpu(loader);
  const core::GridMeanExtinction medium = core::grid_mean_extinction(sc.grid, sc.data);
  gpu.upload(sc.grid, medium);
  sc.march.features.octave_gate = true;
  gpu.render(sc.camera, sc.sun, sc.march);
  const core::MarchStats gated = gpu.last_stats();
  const core::ReferenceImage cpu = core::render_reference(sc.grid, medium, sc.camera, sc.sun, sc.march);
  std::printf("thin cirrus 32x18, 4 octaves: GPU %llu of %llu octave terms, CPU %llu of %llu\n",
              static_cast<unsigned long long>(gated.octave_terms), static_cast<unsigned long long>(gated.octave_terms_full),
              static_cast<unsigned long long>(cpu.stats.octave_terms),
              static_cast<unsigned long long>(cpu.stats.octave_terms_full));
  ASSERT_GT(gated.octave_terms_full, 0u);
  EXPECT_LT(gated.octave_terms, gated.octave_terms_full);  // optical depth 0.1-0.25: fewer than 4 per sample
  EXPECT_GE(gated.octave_terms * 4, gated.octave_terms_full);  // never fewer than the first octave
  EXPECT_NEAR(double(gated.octave_terms), double(cpu.stats.octave_terms), 1e-3 * double(cpu.stats.octave_terms));
  EXPECT_NEAR(double(gated.octave_terms_full), double(cpu.stats.octave_terms_full), 1e-3 * double(cpu.stats.octave_terms_full));
  sc.march.features.octave_gate = false;
  gpu.render(sc.camera, sc.sun, sc.march);
  const core::MarchStats classic = gpu.last_stats();
  EXPECT_EQ(classic.octave_terms, classic.octave_terms_full);
  EXPECT_EQ(classic.octave_terms_full, gated.octave_terms_full);  // the same sunlit samples
}
}  // namespace
