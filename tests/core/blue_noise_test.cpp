// The blue-noise jitter mask (core/noise/blue_noise): a permutation of ranks, deterministic, little
// energy at low frequencies, points spread across the tile's seams; and the per-frame rotation
// (rng.glsl blue_noise_jitter) is the golden-ratio sequence, the same in float and double.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <complex>
#include <cstdio>
#include <random>
#include <stdexcept>

#include "noise/blue_noise.hpp"
#include "physics/physics.hpp"

namespace {
using namespace cv;
namespace p32 = cv::physics::f32;
namespace p64 = cv::physics::f64;

// Mean periodogram |DFT(v - mean)|^2 / n^2 per radial frequency band of width n/16 cycles per tile
// (band 0 excludes the DC term), divided by the values' variance: white noise gives 1 in every band.
std::vector<double> radial_spectrum(const std::vector<float>& v, int n) {
  double mean = 0.0, var = 0.0;
  for (float x : v) mean += x;
  mean /= static_cast<double>(v.size());
  for (float x : v) var += (x - mean) * (x - mean);
  var /= static_cast<double>(v.size());
  // Separable DFT: rows, then columns (O(n^3), a few ms at n = 64).
  const double two_pi = 6.283185307179586;
  std::vector<std::complex<double>> rows(v.size()), full(v.size());
  for (int y = 0; y < n; ++y)
    for (int k = 0; k < n; ++k) {
      std::complex<double> s = 0.0;
      for (int x = 0; x < n; ++x)
        s += (v[static_cast<std::size_t>(y * n + x)] - mean) * std::polar(1.0, -two_pi * k * x / n);
      rows[static_cast<std::size_t>(y * n + k)] = s;
    }
  for (int kx = 0; kx < n; ++kx)
    for (int ky = 0; ky < n; ++ky) {
      std::complex<double> s = 0.0;
      for (int y = 0; y < n; ++y)
        s += rows[static_cast<std::size_t>(y * n + kx)] * std::polar(1.0, -two_pi * ky * y / n);
      full[static_cast<std::size_t>(ky * n + kx)] = s;
    }
  const int bands = 8;
  const double width = n / 16.0;
  std::vector<double> sum(bands, 0.0), count(bands, 0.0);
  for (int ky = 0; ky < n; ++ky)
    for (int kx = 0; kx < n; ++kx) {
      if (kx == 0 && ky == 0) continue;
      const int fx = kx < n / 2 ? kx : kx - n, fy = ky < n / 2 ? ky : ky - n;
      const int b = static_cast<int>(std::sqrt(double(fx * fx + fy * fy)) / width);
      if (b >= bands) continue;
      sum[static_cast<std::size_t>(b)] += std::norm(full[static_cast<std::size_t>(ky * n + kx)]) / (n * n);
      count[static_cast<std::size_t>(b)] += 1.0;
    }
  for (int b = 0; b < bands; ++b)
    sum[static_cast<std::size_t>(b)] /= count[static_cast<std::size_t>(b)] * var;
  return sum;
}

TEST(BlueNoise, MaskIsAPermutationOfRanksAndDeterministic) {
  const auto t0 = std::chrono::steady_clock::now();
  const core::BlueNoiseMask m = core::make_blue_noise(64, 1);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  std::printf("void and cluster, 64 x 64: %.0f ms\n", ms);
  ASSERT_EQ(m.n, 64);
  ASSERT_EQ(m.values.size(), 4096u);
  std::vector<float> sorted = m.values;
  std::sort(sorted.begin(), sorted.end());
  for (int r = 0; r < 4096; ++r)
    ASSERT_EQ(sorted[static_cast<std::size_t>(r)], static_cast<float>(r) / 4096.0f) << r;
  EXPECT_EQ(core::make_blue_noise(64, 1).values, m.values);
  EXPECT_NE(core::make_blue_noise(64, 2).values, m.values);
  // The renderer's mask is this one, made once.
  EXPECT_EQ(core::step_jitter_mask().values, m.values);
  EXPECT_EQ(&core::step_jitter_mask(), &core::step_jitter_mask());
  // Pixels beyond the tile wrap.
  EXPECT_EQ(m.at(64 + 5, 3 * 64 + 7), m.at(5, 7));
  EXPECT_THROW(core::make_blue_noise(3), std::invalid_argument);
  EXPECT_THROW(core::make_blue_noise(16, 1, 0.0), std::invalid_argument);
}

TEST(BlueNoise, LittleEnergyAtLowFrequenciesUnlikeWhiteNoise) {
  const core::BlueNoiseMask& m = core::step_jitter_mask();
  // White noise with the same values: the mask's ranks shuffled.
  std::vector<float> white = m.values;
  std::shuffle(white.begin(), white.end(), std::mt19937(7));
  const auto blue_s = radial_spectrum(m.values, m.n), white_s = radial_spectrum(white, m.n);
  std::printf("mean periodogram / variance per radial band (4 cycles per tile each):\n  band ");
  for (std::size_t b = 0; b < blue_s.size(); ++b) std::printf(" %7zu", b);
  std::printf("\n  blue ");
  for (double v : blue_s) std::printf(" %7.4f", v);
  std::printf("\n  white");
  for (double v : white_s) std::printf(" %7.4f", v);
  std::printf("\n");
  // The shuffled mask is white: near 1 in the lowest band (which holds 48 frequencies).
  EXPECT_GT(white_s[0], 0.5);
  EXPECT_LT(white_s[0], 1.5);
  EXPECT_LT(blue_s[0], 0.25);
  EXPECT_LT(blue_s[0], 0.25 * white_s[0]);
  // Blue noise moves the energy up: the top band holds more than white noise's 1.
  EXPECT_GT(blue_s.back(), 1.0);
}

// The sparsest thresholds are evenly spread points, also across the tile's edges (the filter wraps):
// the closest pair of the 256 lowest ranks, measured on the torus, is far apart compared with the
// same number of random points.
TEST(BlueNoise, LowRanksAreEvenlySpreadAcrossTheSeams) {
  const core::BlueNoiseMask& m = core::step_jitter_mask();
  const int n = m.n, count = n * n / 16;
  auto closest_pair = [n](const std::vector<int>& pts) {
    double best = 1e9;
    for (std::size_t a = 0; a < pts.size(); ++a)
      for (std::size_t b = a + 1; b < pts.size(); ++b) {
        int dx = std::abs(pts[a] % n - pts[b] % n), dy = std::abs(pts[a] / n - pts[b] / n);
        dx = std::min(dx, n - dx), dy = std::min(dy, n - dy);
        best = std::min(best, std::sqrt(double(dx * dx + dy * dy)));
      }
    return best;
  };
  std::vector<int> low, random;
  for (int i = 0; i < n * n; ++i)
    if (m.values[static_cast<std::size_t>(i)] * n * n < count) low.push_back(i);
  ASSERT_EQ(static_cast<int>(low.size()), count);
  std::vector<int> all(static_cast<std::size_t>(n * n));
  for (int i = 0; i < n * n; ++i) all[static_cast<std::size_t>(i)] = i;
  std::shuffle(all.begin(), all.end(), std::mt19937(11));
  random.assign(all.begin(), all.begin() + count);
  const double blue_d = closest_pair(low), white_d = closest_pair(random);
  std::printf(
      "closest pair among the %d lowest ranks: %.2f px (random points: %.2f px; mean spacing %.1f px)\n",
      count, blue_d, white_d, std::sqrt(double(n * n) / count));
  EXPECT_GE(blue_d, 2.0);
  EXPECT_LT(white_d, blue_d);
}

TEST(BlueNoise, JitterIsTheGoldenRatioRotationAndTheSameInFloatAndDouble) {
  const core::BlueNoiseMask& m = core::step_jitter_mask();
  const double phi = 0.6180339887498949;
  double worst = 0.0;
  for (unsigned frame : {0u, 1u, 2u, 7u, 100u, 4095u, 65536u, 1000000u, 4000000000u}) {
    for (unsigned p = 0; p < 4096; p += 37) {
      const float v = m.values[p];
      const double j64 = p64::blue_noise_jitter(v, frame);
      const float j32 = p32::blue_noise_jitter(v, frame);
      ASSERT_EQ(static_cast<double>(j32), j64) << frame << " " << p;  // bit for bit: integer arithmetic
      ASSERT_GE(j64, 0.0);
      ASSERT_LT(j64, 1.0);
      if (frame <= 65536u) {
        // Against fract(v + frame phi) in double: phi is rounded to 2^-24, so the error grows by
        // 1.6e-8 per frame; a distance on the circle, since either side of 1 is the same offset.
        double d = std::abs(j64 - std::fmod(v + frame * phi, 1.0));
        d = std::min(d, 1.0 - d);
        worst = std::max(worst, d / (1.0 + frame));
      }
    }
  }
  EXPECT_LT(worst, 2e-8);
  EXPECT_EQ(p64::blue_noise_jitter(m.values[5], 0u), static_cast<double>(m.values[5]));
  // Over frames one pixel's offsets fill [0, 1) evenly: 16 frames put one in each sixteenth but
  // for the three-gap theorem's slack, i.e. no sixteenth holds more than 2.
  for (unsigned p = 0; p < 4096; p += 101) {
    int bins[16] = {};
    for (unsigned f = 0; f < 16; ++f) ++bins[static_cast<int>(p64::blue_noise_jitter(m.values[p], f) * 16.0)];
    for (int b : bins) EXPECT_LE(b, 2) << p;
  }
}

}  // namespace
