// Unit cases at the edges for the shared physics, in float (the GPU's precision) and double: the
// segment integral at optical depths 0 to 1e4 per step, the octave sum at |g| = 0.999 and the Mie
// fit at its branch boundaries. Finite, non-negative and within the bounds the renderer relies on.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "physics/physics.hpp"
#include "support/numeric.hpp"

namespace {
using namespace cv::physics;

// integral_0^dt s exp(-sigma t) dt <= s / sigma and <= s dt: each step adds at most what the light
// it takes out of the view could carry. Also at sigma = 1e-30 and 0, where 1 - exp(-x) is 0 in float.
template <class Real, class F>
void expect_segment_integral_bounded(F segment_integral) {
  for (double sigma : {0.0, 1e-30, 1e-10, 1e-3, 1.0, 1e2, 1e6}) {
    for (double dt : {1e-3, 1.0, 100.0, 1e4}) {
      const Real v = segment_integral(Real(1), Real(sigma), Real(dt));
      ASSERT_TRUE(std::isfinite(static_cast<double>(v))) << sigma << " " << dt;
      EXPECT_GT(v, Real(0)) << sigma << " " << dt;
      // The exact value is (1 - exp(-x)) / sigma = dt E(x): within float's rounding of it.
      const double x = sigma * dt;
      const double exact = x > 0.0 ? -std::expm1(-x) / sigma : dt;
      EXPECT_NEAR(static_cast<double>(v) / exact, 1.0, sizeof(Real) == 4 ? 1e-6 : 1e-14) << sigma << " " << dt;
    }
  }
}

TEST(StabilityPhysics, SegmentIntegralFromNoExtinctionToOpticalDepth1e10) {
  expect_segment_integral_bounded<double>([](double s, double sg, double dt) { return f64::segment_integral(s, sg, dt); });
  expect_segment_integral_bounded<float>([](float s, float sg, float dt) { return f32::segment_integral(s, sg, dt); });
}

// The octave sum per unit extinction at |g| = 0.999 with no shadow: sum_i b^i p(mu; c^i g), largest
// at the lobe's peak, where HG is (1 + g) / (4 pi (1 - g)^2). Float and double agree there.
TEST(StabilityPhysics, OctavesAtAsymmetry0999StayFiniteAndBounded) {
  for (double g : {0.999, -0.999}) {
    const double peak_mu = g > 0 ? 1.0 : -1.0;
    double bound = 0.0, bi = 1.0, ci = 1.0;
    for (int i = 0; i < 8; ++i, bi *= 0.5, ci *= 0.5) bound += bi * (1.0 + std::abs(ci * g)) / (4.0 * M_PI * std::pow(1.0 - std::abs(ci * g), 2));
    for (int k = 0; k <= 2000; ++k) {
      const double mu = std::cos(M_PI * k / 2000.0);
      const double d = f64::ms_octaves_hg(1.0, mu, g, 0.0, 8, 0.5, 0.5, 0.5);
      const float f = f32::ms_octaves_hg(1.0f, static_cast<float>(mu), static_cast<float>(g), 0.0f, 8, 0.5f, 0.5f, 0.5f);
      ASSERT_TRUE(std::isfinite(d) && std::isfinite(f)) << g << " " << mu;
      EXPECT_GE(f, 0.0f);
      EXPECT_LE(d, bound * (1.0 + 1e-12)) << g << " " << mu;
      EXPECT_LE(f, bound * (1.0 + 1e-4)) << g << " " << mu;
    }
    // At the peak the sum reaches the bound: it is tight (a doubled phase would break it).
    EXPECT_NEAR(f64::ms_octaves_hg(1.0, peak_mu, g, 0.0, 8, 0.5, 0.5, 0.5) / bound, 1.0, 1e-12);
    const float fp = f32::ms_octaves_hg(1.0f, static_cast<float>(peak_mu), static_cast<float>(g), 0.0f, 8, 0.5f, 0.5f, 0.5f);
    std::printf("g %+.3f: octave sum at the peak %.6g (bound %.6g), float %.6g\n", g,
                f64::ms_octaves_hg(1.0, peak_mu, g, 0.0, 8, 0.5, 0.5, 0.5), bound, fp);
    EXPECT_NEAR(fp / bound, 1.0, 1e-3);
    // An optical depth of 1e4 toward the sun: the last octave (a^7 = 1/128) still sees exp(-78), so
    // the sum is tiny but not 0; finite, not negative, within the bound with that factor (float's
    // denormals would flush it to 0 on some GPUs, which is within the bound too).
    const float shadowed = f32::ms_octaves_hg(1.0f, static_cast<float>(peak_mu), static_cast<float>(g), 1e4f, 8, 0.5f, 0.5f, 0.5f);
    EXPECT_TRUE(std::isfinite(shadowed));
    EXPECT_GE(shadowed, 0.0f);
    EXPECT_LE(shadowed, bound * std::exp(-1e4 / 128.0) * 1.01);
  }
}

// The Mie fit just either side of each branch boundary: the phase is finite, positive everywhere,
// normalised in double and float.
TEST(StabilityPhysics, MieFitAtItsBranchBoundaries) {
  for (double d : {0.0999, 0.1, 0.1001, 1.4999, 1.5, 1.5001, 4.999, 5.0, 5.001, 49.99, 50.0, 50.01}) {
    const f64::MieParams p = f64::mie_params(d);
    const f32::MieParams q = f32::mie_params(static_cast<float>(d));
    double peak = 0.0;
    for (int k = 0; k <= 20000; ++k) {
      const double mu = std::cos(M_PI * k / 20000.0);
      const double v = f64::phase_mie(mu, p);
      const float vf = f32::phase_mie(static_cast<float>(mu), q);
      ASSERT_TRUE(std::isfinite(v) && std::isfinite(vf)) << d << " " << mu;
      ASSERT_GT(v, 0.0) << d;
      ASSERT_GT(vf, 0.0f) << d;
      peak = std::max(peak, v);
    }
    const double norm = cv::test::sphere_integral([&](double mu) { return f64::phase_mie(mu, p); });
    EXPECT_NEAR(norm, 1.0, 1e-6) << d;
    const double at1 = f64::phase_mie(1.0, p), at1f = f32::phase_mie(1.0f, q);
    EXPECT_NEAR(at1f / at1, 1.0, 1e-3) << d;
    std::printf("d %-7.5g um: integral %.5f, forward peak %.5g (float %.5g), largest %.5g\n", d, norm, at1, at1f, peak);
  }
}

}  // namespace
