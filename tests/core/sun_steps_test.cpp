// The sun march's step count (march_control.glsl sun_march_steps): fewer steps where the volume is
// thin, and what that costs against the unchanged march (CPU reference, double) on the standard
// scenes whose optical depths span 0.1 (thin cirrus) to ~600 (towering cell); more steps where a
// low sun's segments are long, and what that fixes on the sunset scene.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "physics/physics.hpp"
#include "reference/raymarcher.hpp"
#include "bench/standard_scenes.hpp"

namespace {
using namespace cv::core;
using namespace cv::bench;
namespace p64 = cv::physics::f64;

TEST(SunSteps, EachStepHoldsAtMostTheGivenOpticalDepth) {
  // 2e-4 /m over 7 km: optical depth 1.4 at most, 70 steps of 0.02 wanted, capped at 32.
  EXPECT_EQ(p64::sun_march_steps(2e-4, 7000.0, 0.02, 32, 0.0), 32);
  EXPECT_EQ(p64::sun_march_steps(2e-4, 7000.0, 0.1, 32, 0.0), 14);
  EXPECT_EQ(p64::sun_march_steps(2e-4, 50.0, 0.02, 32, 0.0), 1);  // near the layer's top: one step
  EXPECT_EQ(p64::sun_march_steps(0.0, 7000.0, 0.02, 32, 0.0), 1);
  EXPECT_EQ(p64::sun_march_steps(2e-4, 7000.0, 0.0, 32, 0.0), 32);  // off
  for (double len : {10.0, 300.0, 2500.0, 9000.0}) {
    const int n = p64::sun_march_steps(3e-4, len, 0.05, 64, 0.0);
    EXPECT_TRUE(n == 64 || 3e-4 * len / n <= 0.05 + 1e-12) << len;
  }
}

// The error the rule adds, of the brightest pixel (the GPU-vs-CPU tests' unit), and the sun
// samples it saves. Asserted below the GPU-vs-CPU tolerance (1e-3), and printed for the docs.
TEST(SunSteps, ThinCloudTakesFewerSunSamplesForASmallError) {
  for (const char* name : {"thin_cirrus", "cumulus_field", "stratocumulus", "towering_cell"}) {
    const StandardScene sc = standard_scene(name, 48, 27);
    const GridMeanExtinction ext = grid_mean_extinction(sc.grid, sc.data);
    MarchSettings full = sc.march;
    full.quality.max_sun_step_optical_depth = 0.0;
    using clock = std::chrono::steady_clock;
    auto t0 = clock::now();
    const ReferenceImage a = render_reference(sc.grid, ext, sc.camera, sc.sun, full);
    const double ta = std::chrono::duration<double>(clock::now() - t0).count();
    t0 = clock::now();
    const ReferenceImage b = render_reference(sc.grid, ext, sc.camera, sc.sun, sc.march);
    const double tb = std::chrono::duration<double>(clock::now() - t0).count();
    double brightest = 0.0, worst = 0.0, mean = 0.0;
    for (const auto& l : a.radiance) brightest = std::max({brightest, l.x, l.y, l.z});
    ASSERT_GT(brightest, 0.0) << name;
    for (std::size_t i = 0; i < a.radiance.size(); ++i) {
      for (int k = 0; k < 3; ++k) {
        const double e = std::abs(a.radiance[i][k] - b.radiance[i][k]) / brightest;
        worst = std::max(worst, e);
        mean += e / (3.0 * a.radiance.size());
      }
    }
    std::printf("%-14s max sun step optical depth %.3g: sun samples %llu -> %llu, CPU %.2f -> %.2f s; error of the "
                "brightest pixel mean %.2g, worst %.2g\n",
                name, sc.march.quality.max_sun_step_optical_depth, static_cast<unsigned long long>(a.stats.sun_samples),
                static_cast<unsigned long long>(b.stats.sun_samples), ta, tb, mean, worst);
    EXPECT_LE(b.stats.sun_samples, a.stats.sun_samples) << name;
    EXPECT_LT(worst, 1e-3) << name;
  }
}

TEST(SunSteps, LongSegmentsTakeStepsNoLongerThanTheLimit) {
  // No optical-depth rule: sun_steps, or len / max_step where that is more, at most the cap.
  EXPECT_EQ(p64::sun_march_steps(1e-3, 5000.0, 0.0, 16, 1112.0), 16);  // a high sun: unchanged
  EXPECT_EQ(p64::sun_march_steps(1e-3, 160000.0, 0.0, 16, 1112.0), 144);  // ceil(143.9)
  EXPECT_EQ(p64::sun_march_steps(1e-3, 160000.0, 0.0, 200, 1112.0), 200);  // sun_steps is a floor
  EXPECT_EQ(p64::sun_march_steps(1e-3, 4.0e5, 0.0, 16, 100.0), p64::CV_SUN_SEGMENT_STEPS_MAX);
  EXPECT_EQ(p64::sun_march_steps(1e-3, 160000.0, 0.0, 16, 0.0), 16);  // no limit
  // The optical-depth rule still lowers it where no step can hold more than max_step_tau:
  // 1e-6 /m over 160 km is 0.16 at most, 4 steps of 0.05.
  EXPECT_EQ(p64::sun_march_steps(1e-6, 160000.0, 0.05, 16, 1112.0), 4);
  EXPECT_EQ(p64::sun_march_steps(1e-3, 160000.0, 0.05, 16, 1112.0), 144);  // thick: the length rules
  for (double len : {10.0, 3000.0, 50000.0, 211000.0}) {
    const int n = p64::sun_march_steps(1e-3, len, 0.0, 16, 1112.0);
    EXPECT_TRUE(n == 16 || len / n <= 1112.0) << len;
  }
}

TEST(SunSteps, TheDefaultLimitIsTheGridsHorizontalCell) {
  const double r = 6371000.0 + 500.0;
  // 0.01 deg of longitude at the floor and at the grid's highest latitude, 0.5 deg: 1112 m.
  const double cell_m = 0.01 * 3.14159265358979323846 / 180.0 * r * std::cos(0.5 * 3.14159265358979323846 / 180.0);
  EXPECT_NEAR(p64::sun_step_limit_m(0.0, {-0.5, -0.5, 500.0}, {0.01, 0.01, 125.0}, {101, 101, 29}, r), cell_m, 1e-6 * cell_m);
  EXPECT_EQ(p64::sun_step_limit_m(750.0, {-0.5, -0.5, 500.0}, {0.01, 0.01, 125.0}, {101, 101, 29}, r), 750.0);
  // At 60 deg the longitude spacing is half the latitude spacing; to the pole it stays at half.
  const glm::dvec3 step(1.0, 1.0, 500.0);
  const double deg_m = 3.14159265358979323846 / 180.0 * r;
  EXPECT_NEAR(p64::sun_step_limit_m(0.0, {0.0, 50.0, 0.0}, step, {10, 11, 5}, r), 0.5 * deg_m, 1e-6 * deg_m);
  EXPECT_NEAR(p64::sun_step_limit_m(0.0, {0.0, -90.0, 0.0}, step, {360, 181, 5}, r), 0.5 * deg_m, 1e-6 * deg_m);
  EXPECT_NEAR(p64::sun_step_limit_m(0.0, {0.0, 0.0, 0.0}, {2.0, 1.0, 500.0}, {10, 11, 5}, r), deg_m * 1.0, 1e-6 * deg_m);
}

// max_sun_march_steps bounds the steps of every sun march through a shell (it sizes llvmpipe's
// dispatches): marches from every height in the shell, in directions dense around the horizon.
TEST(SunSteps, TheBoundCoversEverySunMarch) {
  const double r0 = 6371000.0;
  struct Case {
    double hb, ht, max_step;
    int sun_steps;
  };
  for (const Case c : {Case{500.0, 4000.0, 1112.0, 16}, Case{0.0, 18000.0, 25000.0, 16}, Case{1000.0, 12000.0, 300.0, 8},
                       Case{1000.0, 1200.0, 50.0, 64}}) {
    const int bound = max_sun_march_steps(c.sun_steps, c.max_step, r0, c.hb, c.ht);
    int worst = 0;
    for (double h = c.hb; h <= c.ht; h += (c.ht - c.hb) / 16.0) {
      for (int i = 0; i <= 20000; ++i) {
        const double u = -1.0 + 2.0 * i / 20000.0;
        const double mu = u * u * u, nu = std::sqrt(std::max(0.0, 1.0 - mu * mu));
        glm::dvec4 seg;
        const int n = p64::ray_shell_rel_nu(r0, h, mu, nu, c.hb, c.ht, seg);
        int steps = 0;
        for (int q = 0; q < n; ++q) steps += p64::sun_march_steps(1.0, seg[2 * q + 1] - seg[2 * q], 0.0, c.sun_steps, c.max_step);
        worst = std::max(worst, steps);
      }
    }
    std::printf("shell %.0f-%.0f m, steps <= %.0f m: the most sun steps %d, bound %d\n", c.hb, c.ht, c.max_step, worst, bound);
    EXPECT_LE(worst, bound);
    EXPECT_GE(worst, bound / 2);  // the bound is not loose by more than the cap's pairing of segments
  }
}

// With the sun at least mu_min above every sample's horizon, one segment up through the top: the
// bound follows it and is far below the grazing (chord) bound when the sun is high.
TEST(SunSteps, AHighSunsBoundCoversItsMarchesAndIsTighter) {
  const double r0 = 6371000.0, hb = 500.0, ht = 4000.0, max_step = 1112.0;
  const int sun_steps = 16;
  const int grazing = max_sun_march_steps(sun_steps, max_step, r0, hb, ht);
  for (double mu_min : {0.02, 0.1, 0.42, 0.9}) {
    const int bound = max_sun_march_steps(sun_steps, max_step, r0, hb, ht, mu_min);
    int worst = 0;
    for (double h = hb; h <= ht; h += (ht - hb) / 16.0) {
      for (int i = 0; i <= 4000; ++i) {
        const double mu = mu_min + (1.0 - mu_min) * i / 4000.0, nu = std::sqrt(std::max(0.0, 1.0 - mu * mu));
        glm::dvec4 seg;
        const int n = p64::ray_shell_rel_nu(r0, h, mu, nu, hb, ht, seg);
        ASSERT_EQ(n, 1) << "a sun above the horizon leaves through the top";
        worst = std::max(worst, p64::sun_march_steps(1.0, seg[1] - seg[0], 0.0, sun_steps, max_step));
      }
    }
    std::printf("sun at least %.2f (cosine) above the horizon: the most sun steps %d, bound %d (grazing bound %d)\n", mu_min,
                worst, bound, grazing);
    EXPECT_LE(worst, bound);
    EXPECT_LE(bound, worst + 3);
    EXPECT_LE(bound, grazing);
  }
  // mu_min 0.42 (the sun 25 degrees up): a 3.5 km layer is at most 8.3 km long on its sun ray, 16 steps.
  EXPECT_EQ(max_sun_march_steps(sun_steps, max_step, r0, hb, ht, 0.42), 18);
}

// The sunset scene (sun on the horizon, looking toward it): with a fixed 16 steps per segment a
// grazing sun segment (~160 km through the 3.5 km layer) took ~10 km steps over 2 km cumuli, and the
// single-scattered image was 29x too bright (mean luminance 0.196 against 0.00681 with 1024 steps).
// 128 steps (~1.25 km) came within 0.7 % of 1024 (0.00676), so steps no longer than the grid's
// 1.1 km cell, with the default optical-depth rule, are held to 2 %.
TEST(SunSteps, AGrazingSunMatchesTheFineMarch) {
  const StandardScene sc = standard_scene("sunset", 64, 36);
  const GridMeanExtinction ext = grid_mean_extinction(sc.grid, sc.data);
  MarchSettings m = sc.march;
  m.quality.octaves = 1;
  MarchSettings fine = m;
  fine.quality.sun_steps = 1024;
  fine.quality.max_sun_step_optical_depth = 0.0;
  auto mean_luminance = [&](const MarchSettings& s, ReferenceImage& img) {
    img = render_reference(sc.grid, ext, sc.camera, sc.sun, s);
    double sum = 0.0;
    for (const auto& l : img.radiance) sum += 0.2126 * l.x + 0.7152 * l.y + 0.0722 * l.z;
    return sum / static_cast<double>(img.radiance.size());
  };
  MarchSettings fixed = m;  // the march before the length limit: 16 steps per segment however long
  fixed.quality.max_sun_step_m = 1e7;
  ReferenceImage a, b, c;
  const double l_default = mean_luminance(m, a), l_fine = mean_luminance(fine, b), l_fixed = mean_luminance(fixed, c);
  std::printf("sunset 64x36, 1 octave: mean luminance %.5f at %d sun steps (steps <= %.0f m), %.5f at 1024 (%+.2f %%); "
              "sun samples %llu against %llu\n",
              l_default, m.quality.sun_steps, sun_step_limit_m(sc.grid, cloud_layer(sc.grid, ext), m), l_fine,
              100.0 * (l_default / l_fine - 1.0), static_cast<unsigned long long>(a.stats.sun_samples),
              static_cast<unsigned long long>(b.stats.sun_samples));
  std::printf("without the length limit (16 steps per segment): mean luminance %.5f (%.1fx), sun samples %llu\n", l_fixed,
              l_fixed / l_fine, static_cast<unsigned long long>(c.stats.sun_samples));
  ASSERT_GT(l_fine, 0.0);
  EXPECT_NEAR(l_default / l_fine, 1.0, 0.02);
  EXPECT_GT(l_fixed / l_fine, 2.0);  // the scene does show the fault the limit removes
}

// Where the sun is high, every segment's sun_steps are already shorter than the grid's cell: the
// image is the one without the limit, bit for bit (cumulus_field: sun 65 deg up, 3.5 km layer).
TEST(SunSteps, AHighSunsImageIsUnchanged) {
  const StandardScene sc = standard_scene("cumulus_field", 48, 27);
  const GridMeanExtinction ext = grid_mean_extinction(sc.grid, sc.data);
  MarchSettings off = sc.march;
  off.quality.max_sun_step_m = 1e7;
  const ReferenceImage a = render_reference(sc.grid, ext, sc.camera, sc.sun, sc.march);
  const ReferenceImage b = render_reference(sc.grid, ext, sc.camera, sc.sun, off);
  ASSERT_EQ(a.radiance.size(), b.radiance.size());
  double brightest = 0.0;
  for (std::size_t i = 0; i < a.radiance.size(); ++i) {
    brightest = std::max({brightest, a.radiance[i].x, a.radiance[i].y, a.radiance[i].z});
    ASSERT_EQ(a.radiance[i], b.radiance[i]) << "pixel " << i;
  }
  EXPECT_GT(brightest, 0.0);  // there is cloud in the image
  EXPECT_EQ(a.stats.sun_samples, b.stats.sun_samples);
}

}  // namespace
