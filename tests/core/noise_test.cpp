// The erosion noise: tiling of the continuous noises and of the textures, the value range, the
// determinism, the wrapped sampling, the float-safe tile coordinates, and the erosion's bounds.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>

#include "noise/noise.hpp"
#include "physics/physics.hpp"

namespace {
using namespace cv;
namespace p32 = cv::physics::f32;
namespace p64 = cv::physics::f64;

TEST(Noise, ContinuousNoisesRepeatWithTheirPeriodAndTheGradientCrossesTheSeam) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-20.0, 20.0);
  for (int period : {4, 8, 16}) {
    double worst_p = 0.0, worst_w = 0.0, worst_grad = 0.0;
    for (int n = 0; n < 2000; ++n) {
      const glm::dvec3 p(u(rng), u(rng), u(rng));
      for (int axis = 0; axis < 3; ++axis) {
        glm::dvec3 q = p;
        q[axis] += period * (n % 2 ? 1.0 : -3.0);
        worst_p = std::max(worst_p, std::abs(core::perlin_periodic(p, period, 9) - core::perlin_periodic(q, period, 9)));
        worst_w = std::max(worst_w, std::abs(core::worley_periodic(p, period, 9) - core::worley_periodic(q, period, 9)));
        // One-sided slopes of Perlin noise left of the seam (x -> P) and right of it (x -> 0):
        // a smooth periodic function has the same slope on both sides.
        glm::dvec3 s = p;
        s[axis] = 0.0;
        glm::dvec3 sl = s, sr = s, e(0.0);
        sl[axis] = period;
        e[axis] = 1e-6;
        const double left = (core::perlin_periodic(sl, period, 9) - core::perlin_periodic(sl - e, period, 9)) / 1e-6;
        const double right = (core::perlin_periodic(sr + e, period, 9) - core::perlin_periodic(sr, period, 9)) / 1e-6;
        worst_grad = std::max(worst_grad, std::abs(left - right));
      }
    }
    std::printf("period %2d: |f(x) - f(x + P)| Perlin %.2g, Worley %.2g; slope jump at the seam %.2g\n", period, worst_p,
                worst_w, worst_grad);
    EXPECT_LT(worst_p, 1e-12);
    EXPECT_LT(worst_w, 1e-12);
    EXPECT_LT(worst_grad, 1e-4);  // the one-sided differences differ by O(h f''), h = 1e-6
  }
  // The check has power: a noise whose period is not the tile's does not repeat.
  double off = 0.0;
  for (int n = 0; n < 200; ++n) {
    const glm::dvec3 p(u(rng), u(rng), u(rng));
    off = std::max(off, std::abs(core::perlin_periodic(p, 5, 9) - core::perlin_periodic(p + glm::dvec3(4, 0, 0), 5, 9)));
  }
  EXPECT_GT(off, 0.1);
}

// The largest jump of the first and second differences along x, across the seam (texel n-1 to 0)
// and inside the tile.
struct SeamStats {
  double seam_d1 = 0, inner_d1 = 0, seam_d2 = 0, inner_d2 = 0;
};
template <class F>
SeamStats seam_stats(int n, F value) {  // value(i, line) for i in any integer (wrapped by the caller)
  SeamStats s;
  for (int line = 0; line < n * n; ++line) {
    for (int i = 0; i < n; ++i) {
      const double d1 = std::abs(value(i + 1, line) - value(i, line));
      const double d2 = std::abs(value(i + 1, line) - 2 * value(i, line) + value(i - 1, line));
      const bool seam1 = i == n - 1, seam2 = i == 0 || i == n - 1;
      (seam1 ? s.seam_d1 : s.inner_d1) = std::max(seam1 ? s.seam_d1 : s.inner_d1, d1);
      (seam2 ? s.seam_d2 : s.inner_d2) = std::max(seam2 ? s.seam_d2 : s.inner_d2, d2);
    }
  }
  return s;
}

TEST(Noise, TexturesTileInEveryAxisAndFillTheUnitRange) {
  const auto t0 = std::chrono::steady_clock::now();
  const core::ErosionNoise noise = core::make_erosion_noise(64, 32, 1);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  std::printf("generated 64^3 Perlin-Worley + 32^3 Worley fBm in %.0f ms\n", ms);
  for (const core::NoiseTexture* t : {&noise.low, &noise.high}) {
    const int n = t->n;
    ASSERT_EQ(t->texels.size(), static_cast<std::size_t>(n) * n * n);
    const auto [lo, hi] = std::minmax_element(t->texels.begin(), t->texels.end());
    EXPECT_GE(*lo, 0.0f);
    EXPECT_LE(*hi, 1.0f);
    EXPECT_LT(*lo, 0.05f);  // the range is used, not a sliver of it
    EXPECT_GT(*hi, 0.95f);
    for (int axis = 0; axis < 3; ++axis) {
      const SeamStats s = seam_stats(n, [&](int i, int line) {
        int c[3] = {line % n, line / n, 0};
        const int a = (i % n + n) % n;
        const int idx[3] = {axis == 0 ? a : c[0], axis == 1 ? a : (axis == 0 ? c[0] : c[1]), axis == 2 ? a : c[1]};
        return double(t->at(idx[0], idx[1], idx[2]));
      });
      std::printf("%d^3, axis %d: step across the seam %.3f (inside at most %.3f), curvature %.3f (%.3f)\n", n, axis,
                  s.seam_d1, s.inner_d1, s.seam_d2, s.inner_d2);
      EXPECT_LE(s.seam_d1, s.inner_d1) << axis;
      EXPECT_LE(s.seam_d2, s.inner_d2) << axis;
    }
  }
  // The seam statistic has power: a line of noise whose period is not the tile's jumps at the seam.
  const SeamStats bad = seam_stats(64, [](int i, int line) {
    const int a = (i % 64 + 64) % 64;
    return core::perlin_periodic(glm::dvec3(a * 4.0 / 64.0, line * 0.37, 0.5), 5, 3);
  });
  EXPECT_GT(bad.seam_d2, bad.inner_d2);
}

TEST(Noise, GenerationIsDeterministicWhateverTheThreads) {
  const core::ErosionNoise a = core::make_erosion_noise(16, 16, 5, 1);
  const core::ErosionNoise b = core::make_erosion_noise(16, 16, 5, 3);
  const core::ErosionNoise c = core::make_erosion_noise(16, 16, 6, 1);
  EXPECT_EQ(a.low.texels, b.low.texels);
  EXPECT_EQ(a.high.texels, b.high.texels);
  EXPECT_NE(a.low.texels, c.low.texels);
}

TEST(Noise, SamplingWrapsAndInterpolatesBetweenTexels) {
  const core::ErosionNoise noise = core::make_erosion_noise(16, 8, 2);
  const core::NoiseTexture& t = noise.low;
  EXPECT_EQ(t.sample(glm::dvec3(3, 5, 7) / 16.0), t.at(3, 5, 7));
  EXPECT_EQ(t.sample(glm::dvec3(15, 0, 0) / 16.0), t.at(15, 0, 0));
  // Halfway between the last texel and the first (through the seam) is their mean.
  EXPECT_NEAR(t.sample(glm::dvec3(15.5, 0, 0) / 16.0), 0.5 * (t.at(15, 0, 0) + t.at(0, 0, 0)), 1e-7);
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int n = 0; n < 200; ++n) {
    const glm::dvec3 p(u(rng), u(rng), u(rng));
    EXPECT_NEAR(t.sample(p), t.sample(p + glm::dvec3(1, -2, 3)), 1e-12);
  }
}

TEST(Noise, TileCoordinatesKeepTheirDigitsAtPlanetaryScale) {
  // A point on the Earth's surface, the anchor at a nearby float-exact point: the tile coordinate
  // from (p - anchor) in float agrees with fract(p / P) in long double to the float's 0.5 m.
  const double period = 20000.0;
  const glm::dvec3 centre(4.1e6, 3.3e6, 3.6e6);
  const core::NoiseAnchor a = core::noise_anchor(centre, period);
  EXPECT_EQ(glm::dvec3(glm::vec3(a.ecef_m)), a.ecef_m);
  double worst_f = 0.0, worst_naive = 0.0, worst_d = 0.0;
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(-3e5, 3e5);
  for (int n = 0; n < 2000; ++n) {
    const glm::vec3 pf = glm::vec3(centre + glm::dvec3(u(rng), u(rng), u(rng)));  // a float sample position
    const glm::dvec3 p(pf);
    const glm::vec3 tf = p32::noise_tile_coords(pf - glm::vec3(a.ecef_m), glm::vec3(a.frac), float(period));
    const glm::dvec3 td = p64::noise_tile_coords(p - a.ecef_m, a.frac, period);
    const glm::vec3 naive = glm::fract(pf / float(period));
    for (int k = 0; k < 3; ++k) {
      const long double x = static_cast<long double>(p[k]) / period;
      const double exact = static_cast<double>(x - std::floor(x));
      auto wrapped = [](double d) { return std::abs(d - std::round(d)); };  // 0.9999 vs 0.0001 is close
      worst_f = std::max(worst_f, wrapped(tf[k] - exact) * period);
      worst_d = std::max(worst_d, wrapped(td[k] - exact) * period);
      worst_naive = std::max(worst_naive, wrapped(naive[k] - exact) * period);
    }
  }
  std::printf("tile position error: float with anchor %.3g m, double %.3g m, float fract(p / P) %.3g m\n", worst_f, worst_d,
              worst_naive);
  EXPECT_LT(worst_d, 1e-6);
  EXPECT_LT(worst_f, 0.02);  // a few float ulps of (p - anchor) and of the [0, 1) coordinate
  EXPECT_GT(worst_naive, worst_f);
}

TEST(Erosion, NeverAddsExtinctionAndIsExactlyTheDataWithoutNoise) {
  int eroded_to_zero = 0, partly = 0;
  for (double lg = -12.0; lg <= 3.0; lg += 0.25) {
    const double sigma = std::pow(10.0, lg);
    for (double feature : {1.0, 300.0, 2500.0, 1e6}) {
      EXPECT_EQ(p64::erode_extinction(sigma, 0.0, feature), sigma);
      EXPECT_EQ(p32::erode_extinction(float(sigma), 0.0f, float(feature)), float(sigma));
      double prev = sigma;
      for (double t = 0.0; t <= 1.0; t += 1.0 / 64) {
        const double e = p64::erode_extinction(sigma, t, feature);
        const float ef = p32::erode_extinction(float(sigma), float(t), float(feature));
        ASSERT_TRUE(std::isfinite(e) && std::isfinite(ef)) << sigma << " " << t;
        ASSERT_GE(e, 0.0);
        ASSERT_LE(e, sigma);
        ASSERT_GE(ef, 0.0f);
        ASSERT_LE(ef, float(sigma));
        ASSERT_LE(e, prev);  // more noise never gives more cloud
        prev = e;
        eroded_to_zero += e == 0.0;
        partly += e > 0.0 && e < sigma;
      }
    }
  }
  EXPECT_GT(eroded_to_zero, 100);
  EXPECT_GT(partly, 100);
  // Thin edges erode before thick cores: at the same threshold, a larger extinction keeps a larger
  // fraction of itself.
  const double f = 2500.0, t = 0.3;
  EXPECT_EQ(p64::erode_extinction(1e-4, t, f), 0.0);  // opacity 0.22 over 2.5 km: below the threshold
  EXPECT_GT(p64::erode_extinction(4e-4, t, f) / 4e-4, 0.0);
  EXPECT_LT(p64::erode_extinction(4e-4, t, f) / 4e-4, p64::erode_extinction(4e-3, t, f) / 4e-3);
  EXPECT_GT(p64::erode_extinction(4e-2, t, f) / 4e-2, 0.999);
  // The threshold stays within [0, amount] for noise in [0, 1].
  EXPECT_EQ(p64::erosion_threshold(1.0, 1.0, 0.8), 0.0);
  EXPECT_DOUBLE_EQ(p64::erosion_threshold(0.0, 0.0, 0.8), 0.8);
  EXPECT_DOUBLE_EQ(p64::erosion_threshold(0.0, 0.0, 5.0), 1.0);
}

}  // namespace
