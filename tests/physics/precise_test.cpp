// The error-free transformations that let float32 intersections carry ~48 bits.
#include <gtest/gtest.h>

#include <cmath>

#include "physics/physics.hpp"

namespace {
using namespace cv::physics;

TEST(Precise, TwoSumAndTwoProductAreExactInFloat) {
  f32::uint rng = 1u;
  for (int i = 0; i < 100000; ++i) {
    const float a = (f32::rng_next(rng) - 0.5f) * std::pow(2.0f, static_cast<float>(i % 60 - 30));
    const float b = (f32::rng_next(rng) - 0.5f) * std::pow(2.0f, static_cast<float>((i * 7) % 60 - 30));
    const auto s = f32::two_sum(a, b);
    ASSERT_EQ(static_cast<double>(s.x) + static_cast<double>(s.y), static_cast<double>(a) + static_cast<double>(b));
    const auto p = f32::two_prod(a, b);
    ASSERT_EQ(static_cast<double>(p.x) + static_cast<double>(p.y), static_cast<double>(a) * static_cast<double>(b));
  }
}

TEST(Precise, TwoProductIsExactInDouble) {
  const double a = 6371000.123456789, b = 0.999999876543;
  const auto p = f64::two_prod(a, b);
  EXPECT_EQ(static_cast<long double>(p.x) + static_cast<long double>(p.y),
            static_cast<long double>(a) * static_cast<long double>(b));
}

}  // namespace
