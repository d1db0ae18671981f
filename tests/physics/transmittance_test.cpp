// Transmittance and the energy-conserving segment integral against their closed forms, from
// x = 0 to x = 1e6, in double and float; never NaN or Inf.
#include <gtest/gtest.h>

#include <cmath>

#include "physics/physics.hpp"

namespace {
using namespace cv::physics;

// E(x) = (1 - exp(-x)) / x in long double via expm1, the closed form the tests trust.
long double closed_form(long double x) { return x == 0.0L ? 1.0L : -std::expm1(-x) / x; }

const double kXs[] = {0.0, 1e-30, 1e-12, 1e-8, 1e-4, 1e-2, 1.0, 10.0, 100.0, 1e4, 1e6};

TEST(SegmentIntegral, DoubleWithinOneInAMillion) {
  for (double x : kXs) {
    const double e = f64::segment_factor(x);
    ASSERT_TRUE(std::isfinite(e)) << "x=" << x;
    EXPECT_LT(std::abs(e - closed_form(x)) / closed_form(x), 1e-6) << "x=" << x;
  }
}

TEST(SegmentIntegral, FloatWithinOneInAHundredThousand) {
  for (double x : kXs) {
    const float xf = static_cast<float>(x);
    const float e = f32::segment_factor(xf);
    ASSERT_TRUE(std::isfinite(e)) << "x=" << x;
    const long double ref = closed_form(static_cast<long double>(xf));
    EXPECT_LT(std::abs(e - ref) / ref, 1e-5) << "x=" << x;
  }
}

TEST(SegmentIntegral, DenseSweepAcrossTheSeriesSwitch) {
  // Every x from 1e-30 to 1e6 on a fine log grid, and both sides of the switch at 0.1.
  double worst_d = 0.0, worst_f = 0.0;
  for (int i = 0; i <= 3600; ++i) {
    const double x = std::pow(10.0, -30.0 + 36.0 * i / 3600.0);
    const float xf = static_cast<float>(x);
    worst_d = std::max(worst_d, double(std::abs(f64::segment_factor(x) - closed_form(x)) / closed_form(x)));
    const long double rf = closed_form(static_cast<long double>(xf));
    worst_f = std::max(worst_f, double(std::abs(f32::segment_factor(xf) - rf) / rf));
  }
  for (double x : {std::nextafter(0.1, 0.0), 0.1, std::nextafter(0.1, 1.0)}) {
    worst_d = std::max(worst_d, double(std::abs(f64::segment_factor(x) - closed_form(x)) / closed_form(x)));
  }
  EXPECT_LT(worst_d, 1e-6);
  EXPECT_LT(worst_f, 1e-5);
  std::printf("segment factor worst relative error: double %.3g, float %.3g\n", worst_d, worst_f);
}

TEST(SegmentIntegral, LimitsAndScaling) {
  // No extinction: the whole step contributes s dt.
  EXPECT_DOUBLE_EQ(f64::segment_integral(2.0, 0.0, 3.0), 6.0);
  // Very thick step: tends to s / sigma_t, never more.
  EXPECT_NEAR(f64::segment_integral(2.0, 1e3, 1e3), 2.0 / 1e3, 1e-15);
  // Integral equals the closed form s (1 - exp(-sigma dt)) / sigma.
  EXPECT_NEAR(f64::segment_integral(1.5, 0.02, 40.0), 1.5 * (1 - std::exp(-0.8)) / 0.02, 1e-12);
  // Vector overload matches the scalar one per channel.
  const auto v = f64::segment_integral(glm::dvec3(1.0, 2.0, 3.0), 0.5, 2.0);
  EXPECT_DOUBLE_EQ(v.y, f64::segment_integral(2.0, 0.5, 2.0));
  // Splitting a step in two with the transmittance of the first half gives the same energy.
  const double whole = f64::segment_integral(1.0, 0.3, 10.0);
  const double halves = f64::segment_integral(1.0, 0.3, 5.0) +
                        f64::transmittance(0.3 * 5.0) * f64::segment_integral(1.0, 0.3, 5.0);
  EXPECT_NEAR(whole, halves, 1e-14);
}

TEST(Transmittance, ExponentialLawAndExtremes) {
  EXPECT_DOUBLE_EQ(f64::transmittance(0.0), 1.0);
  EXPECT_NEAR(f64::transmittance(1.0), std::exp(-1.0), 1e-16);
  EXPECT_EQ(f32::transmittance(1e6f), 0.0f);
  EXPECT_TRUE(std::isfinite(f32::transmittance(1e30f)));
  // A constant slab: T multiplies over sub-slabs.
  EXPECT_NEAR(f64::transmittance(0.4) * f64::transmittance(0.6), f64::transmittance(1.0), 1e-16);
}

}  // namespace
