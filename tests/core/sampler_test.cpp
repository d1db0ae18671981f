// The volume sampler: exact at nodes, exact for fields linear in each axis, wrapping across the
// date line, clamping at the poles of global grids, and no data outside.
#include <gtest/gtest.h>

#include <cmath>

#include "volume/sampler.hpp"

namespace {
using namespace cv::core;

// A field linear in longitude index, latitude and altitude: trilinear sampling reproduces it.
std::vector<float> linear_field(const VolumeGrid& g) {
  std::vector<float> f(g.points());
  for (int k = 0; k < g.alt_m.count; ++k)
    for (int j = 0; j < g.lat_deg.count; ++j)
      for (int i = 0; i < g.lon_deg.count; ++i) f[g.index(i, j, k)] = static_cast<float>(i + 10.0 * j + 100.0 * k);
  return f;
}

TEST(Sampler, NodesAndLinearFieldsAreExact) {
  VolumeGrid g;
  g.lon_deg = {10.0, 2.0, 5};
  g.lat_deg = {-10.0, 5.0, 4};
  g.alt_m = {0.0, 1000.0, 3};
  const auto f = linear_field(g);
  const VolumeSampler s(g, f);
  EXPECT_DOUBLE_EQ(s.sample(-5.0, 14.0, 1000.0, NAN), 2 + 10 + 100);
  // Midway in every axis: i = 1.5, j = 0.5, k = 0.25.
  EXPECT_NEAR(s.sample(-7.5, 13.0, 250.0, NAN), 1.5 + 5.0 + 25.0, 1e-9);
  // Outside the regional grid, or above and below it: no data.
  EXPECT_TRUE(std::isnan(s.sample(-7.5, 19.0, 250.0, NAN)));
  EXPECT_TRUE(std::isnan(s.sample(20.0, 13.0, 250.0, NAN)));
  EXPECT_TRUE(std::isnan(s.sample(-7.5, 13.0, 2500.0, NAN)));
  EXPECT_EQ(s.sample(-7.5, 13.0, -1.0, 0.0), 0.0);
}

TEST(Sampler, GlobalGridWrapsAcrossTheSeamAndClampsAtThePoles) {
  VolumeGrid g;
  g.lon_deg = {0.0, 90.0, 4};  // 0, 90, 180, 270: wraps
  g.lat_deg = {-60.0, 60.0, 3};  // -60, 0, 60: the pole rows are one step beyond
  g.alt_m = {0.0, 1000.0, 2};
  ASSERT_TRUE(g.wraps_lon());
  const auto f = linear_field(g);
  const VolumeSampler s(g, f);
  // Between 270 and 360 (= column 0): the value runs from 3 back to 0, whatever the convention.
  EXPECT_NEAR(s.sample(0.0, 315.0, 0.0, NAN), 10.0 + 1.5, 1e-9);
  EXPECT_NEAR(s.sample(0.0, -45.0, 0.0, NAN), 10.0 + 1.5, 1e-9);
  EXPECT_NEAR(s.sample(0.0, 675.0, 0.0, NAN), 10.0 + 1.5, 1e-9);
  // Beyond the last row, towards the pole, the edge row holds.
  EXPECT_NEAR(s.sample(85.0, 90.0, 0.0, NAN), 1.0 + 20.0, 1e-9);
  EXPECT_NEAR(s.sample(-90.0, 90.0, 0.0, NAN), 1.0, 1e-9);
}

TEST(Sampler, RegionalGridAcrossTheDateLine) {
  VolumeGrid g;
  g.lon_deg = {170.0, 5.0, 5};  // 170 .. 190
  g.lat_deg = {40.0, 5.0, 2};
  g.alt_m = {0.0, 500.0, 2};
  const auto f = linear_field(g);
  const VolumeSampler s(g, f);
  EXPECT_NEAR(s.sample(40.0, -175.0, 0.0, NAN), 3.0, 1e-9);  // -175 is 185
  EXPECT_NEAR(s.sample(40.0, 182.5, 0.0, NAN), 2.5, 1e-9);
  EXPECT_TRUE(std::isnan(s.sample(40.0, -165.0, 0.0, NAN)));  // 195: beyond the east edge
  EXPECT_TRUE(std::isnan(s.sample(40.0, 160.0, 0.0, NAN)));
}

TEST(Sampler, NoDataCornersTakeTheGivenValue) {
  VolumeGrid g;
  g.lon_deg = {0.0, 1.0, 2};
  g.lat_deg = {0.0, 1.0, 2};
  g.alt_m = {0.0, 1.0, 2};
  std::vector<float> f(g.points(), 1.0f);
  f[g.index(1, 1, 1)] = NAN;
  const VolumeSampler s(g, f);
  EXPECT_NEAR(s.sample(0.5, 0.5, 0.5, 0.0), 7.0 / 8.0, 1e-12);  // one corner of eight counts as 0
  EXPECT_DOUBLE_EQ(s.sample(0.0, 0.0, 0.0, 0.0), 1.0);
  const std::vector<float> empty;
  EXPECT_EQ(VolumeSampler(g, empty).sample(0.5, 0.5, 0.5, -1.0), -1.0);  // an absent field
}

}  // namespace

namespace {
// A regional grid's sides fade to nothing over one grid cell, as though bordered by empty nodes:
// a ray grazing the data's edge sees a ramp, not a cliff that float rounding decides.
TEST(Sampler, RegionalEdgesFadeOverOneCell) {
  VolumeGrid g;
  g.lon_deg = {10.0, 1.0, 3};
  g.lat_deg = {20.0, 1.0, 3};
  g.alt_m = {0.0, 1000.0, 2};
  const std::vector<float> f(g.points(), 2.0f);
  const VolumeSampler s(g, f);
  EXPECT_DOUBLE_EQ(s.sample(21.0, 12.0, 500.0, 0.0), 2.0);    // on the east edge column
  EXPECT_NEAR(s.sample(21.0, 12.25, 500.0, 0.0), 1.5, 1e-12);  // a quarter cell beyond it
  EXPECT_NEAR(s.sample(21.0, 9.5, 500.0, 0.0), 1.0, 1e-12);    // half a cell west
  EXPECT_NEAR(s.sample(19.25, 11.0, 500.0, 0.0), 0.5, 1e-12);  // three quarters south
  EXPECT_NEAR(s.sample(23.0, 11.0, 500.0, 0.0), 0.0, 1e-12);   // a whole cell north: nothing
  EXPECT_TRUE(std::isnan(s.sample(23.5, 11.0, 500.0, NAN)));   // beyond the border
  EXPECT_TRUE(std::isnan(s.sample(21.0, 8.5, 500.0, NAN)));
}
}  // namespace
