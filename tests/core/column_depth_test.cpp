// The octave gate's column optical depths (core/volume/column_depth): the trapezoid is the exact
// integral of the sampler's profile, and the horizontal lookup follows the 3-D sampler's wrap,
// pole and regional-edge rules.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "volume/column_depth.hpp"
#include "volume/sampler.hpp"

namespace {
using namespace cv::core;

VolumeGrid make_grid(double lon0, double dlon, int nlon, double lat0, double dlat, int nlat) {
  VolumeGrid g;
  g.lon_deg = {lon0, dlon, nlon};
  g.lat_deg = {lat0, dlat, nlat};
  g.alt_m = {500.0, 250.0, 9};  // 500..2500 m
  return g;
}

TEST(ColumnDepth, TrapezoidIsExactOnALinearProfile) {
  const VolumeGrid g = make_grid(0.0, 1.0, 3, 0.0, 1.0, 2);
  std::vector<float> liquid(g.points()), ice(g.points());
  const double s0 = 2e-3, s1 = 1e-6;  // 1/m and 1/m^2: liquid rises with altitude, ice is constant
  for (int k = 0; k < g.alt_m.count; ++k) {
    for (int y = 0; y < 2; ++y) {
      for (int x = 0; x < 3; ++x) {
        liquid[g.index(x, y, k)] = static_cast<float>(s0 + s1 * (g.alt_m.at(k) - g.alt_m.start));
        ice[g.index(x, y, k)] = 1e-4f;
      }
    }
  }
  const ColumnDepth c = column_depth(g, liquid, ice);
  const double h = g.alt_m.last() - g.alt_m.start;
  const double expect = s0 * h + 0.5 * s1 * h * h + 1e-4 * h;  // closed form: 6.2
  ASSERT_EQ(c.tau.size(), g.columns());
  for (float t : c.tau) EXPECT_NEAR(t, expect, 1e-6 * expect);
  // An empty field counts as none.
  const ColumnDepth only_ice = column_depth(g, {}, ice);
  EXPECT_NEAR(only_ice.tau[0], 1e-4 * h, 1e-6 * 1e-4 * h);  // the map is float
}

TEST(ColumnDepth, MatchesTheSamplersProfileIntegratedFinely) {
  // A random profile per column: the trapezoid against a fine midpoint sum of what the 3-D sampler
  // returns along the vertical (exact on each linear piece, up to the float storage).
  const VolumeGrid g = make_grid(10.0, 0.5, 4, 40.0, 0.5, 3);
  std::vector<float> liquid(g.points());
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0.0f, 0.01f);
  for (float& v : liquid) v = u(rng);
  const ColumnDepth c = column_depth(g, liquid, {});
  const VolumeSampler s(g, liquid);
  for (int y = 0; y < g.lat_deg.count; ++y) {
    for (int x = 0; x < g.lon_deg.count; ++x) {
      const int n = 4000;
      const double h = g.alt_m.last() - g.alt_m.start, dz = h / n;
      double sum = 0.0;
      for (int i = 0; i < n; ++i) sum += s.sample(g.lat_deg.at(y), g.lon_deg.at(x), g.alt_m.start + (i + 0.5) * dz, 0.0) * dz;
      EXPECT_NEAR(c.tau[static_cast<std::size_t>(y) * c.nx + x], sum, 1e-6 * sum) << x << " " << y;
      // At the node itself the lookup returns the column's value.
      EXPECT_NEAR(c.at(g, g.lat_deg.at(y), g.lon_deg.at(x)), c.tau[static_cast<std::size_t>(y) * c.nx + x], 1e-9);
    }
  }
}

// A map whose columns are given directly (the lookup does not care where they came from).
ColumnDepth ramp(const VolumeGrid& g) {
  ColumnDepth c;
  c.nx = g.lon_deg.count;
  c.ny = g.lat_deg.count;
  c.tau.resize(g.columns());
  for (std::size_t i = 0; i < c.tau.size(); ++i) c.tau[i] = 1.0f + static_cast<float>(i);
  return c;
}

TEST(ColumnDepth, WrapsAroundTheDateLineOnGlobalGrids) {
  const VolumeGrid g = make_grid(0.0, 10.0, 36, -90.0, 10.0, 19);  // global: wraps, rows at the poles
  ASSERT_TRUE(g.wraps_lon());
  const ColumnDepth c = ramp(g);
  const auto col = [&](int x, int y) { return double(c.tau[static_cast<std::size_t>(y) * c.nx + x]); };
  // Half way between the last column (350 E) and the first (0 E), in either longitude convention.
  EXPECT_NEAR(c.at(g, 0.0, 355.0), 0.5 * (col(35, 9) + col(0, 9)), 1e-9);
  EXPECT_NEAR(c.at(g, 0.0, -5.0), 0.5 * (col(35, 9) + col(0, 9)), 1e-9);
  EXPECT_NEAR(c.at(g, 0.0, 362.5), 0.75 * col(0, 9) + 0.25 * col(1, 9), 1e-9);
  // The pole rows clamp: at 90 N the last row, exactly.
  EXPECT_NEAR(c.at(g, 90.0, 20.0), col(2, 18), 1e-9);
}

TEST(ColumnDepth, RegionalEdgesFadeOverOneCell) {
  const VolumeGrid g = make_grid(10.0, 1.0, 11, 40.0, 1.0, 6);  // 10..20 E, 40..45 N
  ASSERT_FALSE(g.wraps_lon());
  const ColumnDepth c = ramp(g);
  const auto col = [&](int x, int y) { return double(c.tau[static_cast<std::size_t>(y) * c.nx + x]); };
  EXPECT_NEAR(c.at(g, 42.0, 20.0), col(10, 2), 1e-9);         // the edge column reads exactly
  EXPECT_NEAR(c.at(g, 42.0, 20.5), 0.5 * col(10, 2), 1e-9);   // half way to the border: half
  EXPECT_NEAR(c.at(g, 42.0, 9.25), 0.25 * col(0, 2), 1e-9);   // west side, a quarter cell in
  EXPECT_NEAR(c.at(g, 45.5, 12.0), 0.5 * col(2, 5), 1e-9);    // north side
  EXPECT_EQ(c.at(g, 42.0, 21.5), 0.0);                        // beyond the border: nothing
  EXPECT_EQ(c.at(g, 38.5, 12.0), 0.0);
  // The 3-D sampler fades the same way at the same place.
  std::vector<float> field(g.points(), 1.0f);
  const VolumeSampler s(g, field);
  EXPECT_NEAR(s.sample(42.0, 20.5, 1000.0, 0.0), 0.5, 1e-12);
}

}  // namespace
