// Fewer sun steps where the volume is thin (march_control.glsl sun_march_steps): the rule itself,
// and what it costs against the unchanged march (CPU reference, double) on the standard scenes
// whose optical depths span 0.1 (thin cirrus) to ~600 (towering cell).
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "physics/physics.hpp"
#include "reference/raymarcher.hpp"
#include "scene/standard_scenes.hpp"

namespace {
using namespace cv::core;
namespace p64 = cv::physics::f64;

TEST(SunSteps, EachStepHoldsAtMostTheGivenOpticalDepth) {
  // 2e-4 /m over 7 km: optical depth 1.4 at most, 70 steps of 0.02 wanted, capped at 32.
  EXPECT_EQ(p64::sun_march_steps(2e-4, 7000.0, 0.02, 32), 32);
  EXPECT_EQ(p64::sun_march_steps(2e-4, 7000.0, 0.1, 32), 14);
  EXPECT_EQ(p64::sun_march_steps(2e-4, 50.0, 0.02, 32), 1);  // near the layer's top: one step
  EXPECT_EQ(p64::sun_march_steps(0.0, 7000.0, 0.02, 32), 1);
  EXPECT_EQ(p64::sun_march_steps(2e-4, 7000.0, 0.0, 32), 32);  // off
  for (double len : {10.0, 300.0, 2500.0, 9000.0}) {
    const int n = p64::sun_march_steps(3e-4, len, 0.05, 64);
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
    full.max_sun_step_optical_depth = 0.0;
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
                name, sc.march.max_sun_step_optical_depth, static_cast<unsigned long long>(a.stats.sun_samples),
                static_cast<unsigned long long>(b.stats.sun_samples), ta, tb, mean, worst);
    EXPECT_LE(b.stats.sun_samples, a.stats.sun_samples) << name;
    EXPECT_LT(worst, 1e-3) << name;
  }
}

}  // namespace
