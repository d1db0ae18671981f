// The weather textures (issue 18 item 1; core/kernel/weather_textures, docs/physics.md "Weather
// textures"): cover per layer by maximum-random overlap, base and top, the cloud type from the
// layer's depth, cover, phase, base and lapse rate, the types' profiles, the maps following the
// time-interpolated medium, and the cover diagnosed from the water where a file gives none.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "kernel/prepared_volume.hpp"
#include "kernel/weather_textures.hpp"
#include "volume/grid_mean.hpp"
#include "volume/time_interpolation.hpp"

namespace cv::core {
namespace {

// 4 x 2 columns of 1 degree, 13 levels 1 km apart from sea level.
VolumeGrid grid() {
  VolumeGrid g;
  g.lon_deg = {0.0, 1.0, 4};
  g.lat_deg = {10.0, 1.0, 2};
  g.alt_m = {0.0, 1000.0, 13};
  return g;
}

struct Column {
  int i = 0, j = 0;
};

// A step of the grid: no cloud, temperatures falling at `lapse` K/km from 290 K at sea level.
TimeStepData empty_step(const VolumeGrid& g, double lapse) {
  TimeStepData d;
  d[Field::ExtinctionLiquid].assign(g.points(), 0.0f);
  d[Field::ExtinctionIce].assign(g.points(), 0.0f);
  d[Field::CloudFraction].assign(g.points(), 0.0f);
  d[Field::Temperature].assign(g.points(), 0.0f);
  for (int k = 0; k < g.alt_m.count; ++k)
    for (int j = 0; j < g.lat_deg.count; ++j)
      for (int i = 0; i < g.lon_deg.count; ++i) d[Field::Temperature][g.index(i, j, k)] = float(290.0 - lapse * k);
  return d;
}

// Cloud on levels k0..k1 of column (i, j): in-cloud extinction ext of the phase, fraction c.
void put(const VolumeGrid& g, TimeStepData& d, Column col, int k0, int k1, double c, double ext, bool ice) {
  for (int k = k0; k <= k1; ++k) {
    const std::size_t p = g.index(col.i, col.j, k);
    d[Field::CloudFraction][p] = float(c);
    d[ice ? Field::ExtinctionIce : Field::ExtinctionLiquid][p] = float(ext);
  }
}

// A column's own lapse rate: steeper or shallower than the rest.
void set_lapse(const VolumeGrid& g, TimeStepData& d, Column col, double lapse) {
  for (int k = 0; k < g.alt_m.count; ++k) d[Field::Temperature][g.index(col.i, col.j, k)] = float(290.0 - lapse * k);
}

TEST(WeatherTextures, TheClassifierReadsDepthCoverPhaseBaseAndLapseRate) {
  CloudLayerTraits stratus;  // a thin overcast deck under a stable lapse rate
  stratus.thickness_m = 600.0, stratus.base_above_ground_m = 500.0, stratus.mean_cover = 1.0, stratus.lapse_k_per_km = 4.0;
  CloudLayerTraits fair_cumulus = stratus;  // thin, broken, conditionally unstable
  fair_cumulus.thickness_m = 1200.0, fair_cumulus.mean_cover = 0.25, fair_cumulus.lapse_k_per_km = 8.0;
  CloudLayerTraits congestus = fair_cumulus;  // deep and broken
  congestus.thickness_m = 6000.0, congestus.mean_cover = 0.5;
  CloudLayerTraits nimbostratus = stratus;  // deep but overcast and stable: stratiform
  nimbostratus.thickness_m = 5000.0, nimbostratus.ice_share = 0.4;
  CloudLayerTraits cirrus;  // ice, based 8 km above the ground
  cirrus.thickness_m = 1500.0, cirrus.base_above_ground_m = 8000.0, cirrus.ice_share = 1.0, cirrus.mean_cover = 0.6;
  CloudLayerTraits low_ice = cirrus;  // ice near the ground (ice fog, a snowing deck): not cirriform
  low_ice.base_above_ground_m = 300.0, low_ice.mean_cover = 1.0;
  struct Case {
    const char* name;
    CloudLayerTraits t;
    CloudType want;
  } cases[] = {{"stratus", stratus, CloudType::Stratiform},         {"fair-weather cumulus", fair_cumulus, CloudType::Cumuliform},
               {"congestus", congestus, CloudType::Cumuliform},     {"nimbostratus", nimbostratus, CloudType::Stratiform},
               {"cirrus", cirrus, CloudType::Cirriform},            {"ice near the ground", low_ice, CloudType::Stratiform}};
  for (const Case& c : cases) {
    const auto m = cloud_type_memberships(c.t);
    std::printf("%s: stratiform %.2f, cumuliform %.2f, cirriform %.2f\n", c.name, m[0], m[1], m[2]);
    EXPECT_NEAR(m[0] + m[1] + m[2], 1.0, 1e-12) << c.name;
    for (double v : m) EXPECT_TRUE(v >= 0.0 && v <= 1.0) << c.name;
    EXPECT_EQ(dominant_type(m), c.want) << c.name;
  }
  // Without temperatures the cover alone gives the convective signal: broken cloud is cumuliform.
  CloudLayerTraits no_t = fair_cumulus;
  no_t.lapse_k_per_km = std::nan("");
  EXPECT_EQ(dominant_type(cloud_type_memberships(no_t)), CloudType::Cumuliform);
  // Continuous: a small change of any input moves the memberships a little (the maps interpolate).
  for (double cover = 0.0; cover <= 1.0; cover += 0.01) {
    CloudLayerTraits a = congestus, b = congestus;
    a.mean_cover = cover, b.mean_cover = cover + 0.001;
    const auto ma = cloud_type_memberships(a), mb = cloud_type_memberships(b);
    for (int t = 0; t < 3; ++t) EXPECT_LT(std::abs(ma[std::size_t(t)] - mb[std::size_t(t)]), 0.01) << cover;
  }
}

TEST(WeatherTextures, ProfilesAreBoundedAndShapedByType) {
  const CloudType types[] = {CloudType::Stratiform, CloudType::Cumuliform, CloudType::Cirriform};
  for (CloudType t : types) {
    double best = -1.0, at = 0.0;
    for (int q = 0; q <= 1000; ++q) {
      const double eta = q / 1000.0, p = type_profile(t, eta);
      EXPECT_TRUE(p >= 0.0 && p <= 1.0) << cloud_type_name(t) << " " << eta;
      if (p > best) best = p, at = eta;
    }
    std::printf("%s: densest at eta %.3f (%.3f)\n", cloud_type_name(t), at, best);
    if (t == CloudType::Stratiform) {
      EXPECT_GT(at, 0.6) << "a deck's water grows with height to near its top";
    }
    if (t == CloudType::Cumuliform) {
      EXPECT_LT(at, 0.5) << "a cumulus is densest low, over its flat base";
    }
    if (t == CloudType::Cirriform) {
      EXPECT_NEAR(at, 0.5, 0.01) << "a cirrus sheet is densest in its middle";
    }
    EXPECT_LT(type_profile(t, 0.0), 0.05 * best + 1e-12) << "the edges are thin";
  }
}

TEST(WeatherTextures, CoverBaseTopAndTypePerColumn) {
  const VolumeGrid g = grid();
  TimeStepData d = empty_step(g, 5.0);
  put(g, d, {0, 0}, 1, 1, 1.0, 0.03, false);  // a stratus deck at 1 km
  set_lapse(g, d, {0, 0}, 3.0);
  put(g, d, {1, 0}, 1, 3, 0.3, 0.02, false);  // broken cumulus 1-3 km, unstable
  set_lapse(g, d, {1, 0}, 8.5);
  put(g, d, {2, 0}, 8, 9, 0.6, 5e-4, true);   // cirrus 8-9 km
  put(g, d, {3, 0}, 1, 1, 0.5, 0.03, false);  // a deck at 1 km (c 0.5) and cirrus at 9 km (c 0.4)
  put(g, d, {3, 0}, 9, 9, 0.4, 2e-4, true);
  // Column (0, 1): terrain at 3 km, cloud 500 m above it: low cloud, not mid.
  d.ground_m.assign(g.columns(), 0.0f);
  d.ground_m[g.column(0, 1)] = 3000.0f;
  put(g, d, {0, 1}, 3, 3, 0.8, 0.03, false);
  // The lapse rate reads from the lowest level above the ground.
  const PreparedVolume v = prepare_volume(g, d);
  const WeatherTextures& w = v.weather;
  ASSERT_EQ(w.cover.size(), g.columns());
  EXPECT_FALSE(w.cover_from_water);
  EXPECT_TRUE(w.heights_above_ground);
  EXPECT_TRUE(w.has_lapse_rate);
  const auto at = [&](const std::vector<float>& m, int i, int j) { return double(m[g.column(i, j)]); };
  EXPECT_NEAR(at(v.extinction.lapse_k_per_km, 0, 0), 3.0, 1e-4);
  EXPECT_NEAR(at(v.extinction.lapse_k_per_km, 1, 0), 8.5, 1e-4);

  EXPECT_EQ(w.type[g.column(0, 0)], CloudType::Stratiform);
  EXPECT_EQ(w.type[g.column(1, 0)], CloudType::Cumuliform);
  EXPECT_EQ(w.type[g.column(2, 0)], CloudType::Cirriform);
  EXPECT_EQ(w.type[g.column(3, 0)], CloudType::Stratiform) << "the main layer is the thicker in optical depth: the deck";
  EXPECT_EQ(w.type[g.column(1, 1)], CloudType::None);
  // Covers: one layer each; adjacent levels overlap maximally; separated layers randomly.
  EXPECT_NEAR(at(w.cover, 0, 0), 1.0, 1e-6);
  EXPECT_NEAR(at(w.cover, 1, 0), 0.3, 1e-6);
  EXPECT_NEAR(at(w.cover, 3, 0), 1.0 - 0.5 * 0.6, 1e-6);
  EXPECT_NEAR(at(w.cover_low, 3, 0), 0.5, 1e-6);
  EXPECT_NEAR(at(w.cover_mid, 3, 0), 0.0, 1e-6);
  EXPECT_NEAR(at(w.cover_high, 3, 0), 0.4, 1e-6);
  EXPECT_NEAR(at(w.cover_high, 2, 0), 0.6, 1e-6);
  EXPECT_NEAR(at(w.cover_low, 0, 1), 0.8, 1e-6) << "500 m above the plateau is low cloud";
  EXPECT_NEAR(at(w.cover_mid, 0, 1), 0.0, 1e-6);
  EXPECT_EQ(at(w.cover, 1, 1), 0.0);
  // Base and top: the lowest and highest cloudy levels, NaN in a clear column.
  EXPECT_EQ(at(w.base_m, 1, 0), 1000.0);
  EXPECT_EQ(at(w.top_m, 1, 0), 3000.0);
  EXPECT_EQ(at(w.base_m, 3, 0), 1000.0);
  EXPECT_EQ(at(w.top_m, 3, 0), 9000.0);
  EXPECT_TRUE(std::isnan(at(w.base_m, 1, 1)));
  // Ice's share of the column's optical depth: the deck 0.5 x 0.03 x 1 km against cirrus 0.4 x 2e-4 x 1 km.
  EXPECT_NEAR(at(w.ice_share, 3, 0), 0.4 * 2e-4 / (0.4 * 2e-4 + 0.5 * 0.03), 1e-5);
  EXPECT_EQ(w.columns_of_type[1] + w.columns_of_type[2] + w.columns_of_type[3], 5u);
  const std::string note = weather_textures_note(w);
  std::printf("%s\n", note.c_str());
  EXPECT_NE(note.find("5 cloudy columns"), std::string::npos);
}

// Between two steps the textures are made from the interpolated medium: a column whose cover goes
// from 0.2 to 0.8 reads 0.5 half-way, and its lapse rate is the steps' mean.
TEST(WeatherTextures, FollowTheTimeInterpolatedMedium) {
  const VolumeGrid g = grid();
  TimeStepData d0 = empty_step(g, 4.0), d1 = empty_step(g, 8.0);
  put(g, d0, {1, 1}, 2, 3, 0.2, 0.02, false);
  put(g, d1, {1, 1}, 2, 3, 0.8, 0.02, false);
  const GridMeanExtinction e0 = grid_mean_extinction(g, d0), e1 = grid_mean_extinction(g, d1);
  const StepWinds w0 = step_winds(d0), w1 = step_winds(d1);
  for (double f : {0.25, 0.5, 0.75}) {
    const PreparedVolume v = prepare_volume(g, interpolate_extinction(g, e0, e1, w0, w1, 3600.0, f, TimeInterpolation::Linear));
    EXPECT_NEAR(v.weather.cover[g.column(1, 1)], 0.2 + 0.6 * f, 1e-6) << f;
    EXPECT_NEAR(v.extinction.lapse_k_per_km[g.column(1, 1)], 4.0 + 4.0 * f, 1e-4) << f;
  }
}

// A file without cloud fraction: the cover is diagnosed from the water, at the typical in-cloud
// extinction shaped by the layer's profile, and never below what the water needs.
TEST(WeatherTextures, CoverDiagnosedFromTheWaterWhereTheFileHasNone) {
  const VolumeGrid g = grid();
  TimeStepData d = empty_step(g, 5.0);
  put(g, d, {0, 0}, 1, 1, 1.0, 0.06, false);    // thick: the whole box
  put(g, d, {1, 0}, 1, 3, 1.0, 0.002, false);   // a tenth of the typical liquid: broken
  put(g, d, {2, 0}, 8, 9, 1.0, 1e-4, true);     // thin ice
  d[Field::CloudFraction].clear();
  const PreparedVolume v = prepare_volume(g, d);
  ASSERT_EQ(v.extinction.fraction.size(), g.points());
  EXPECT_TRUE(v.weather.cover_from_water);
  const auto c = [&](int i, int j, int k) { return double(v.extinction.fraction[g.index(i, j, k)]); };
  EXPECT_EQ(c(0, 0, 1), 1.0);
  for (int k = 1; k <= 3; ++k) {
    EXPECT_GE(c(1, 0, k), 0.1 - 1e-6) << "at least the plain share at the typical extinction, level " << k;
    EXPECT_LE(c(1, 0, k), 0.4 + 1e-6) << "at most that share at a quarter of it, level " << k;
  }
  EXPECT_GT(c(2, 0, 8), 0.2 - 1e-6);
  EXPECT_LT(c(2, 0, 8), 0.8 + 1e-6);
  EXPECT_EQ(c(3, 0, 5), 0.0) << "no water, no cover";
  for (std::size_t p = 0; p < g.points(); ++p) {
    const double s = double(v.extinction.liquid_per_m[p]) + double(v.extinction.ice_per_m[p]);
    if (s > 0.0) {
      EXPECT_GT(v.extinction.fraction[p], 0.0f) << "water gets some cover at node " << p;
    }
    EXPECT_LE(v.extinction.fraction[p], 1.0f);
  }
  EXPECT_NE(weather_textures_note(v.weather).find("diagnosed from the water"), std::string::npos);
}

// The data mode's volumes leave the textures out (only the modelled cloud reads them).
TEST(WeatherTextures, LeftOutWhereNothingReadsThem) {
  const VolumeGrid g = grid();
  TimeStepData d = empty_step(g, 5.0);
  put(g, d, {1, 0}, 1, 3, 0.3, 0.02, false);
  set_lapse(g, d, {1, 0}, 8.5);
  const PreparedVolume with = prepare_volume(g, grid_mean_extinction(g, d), true);
  const PreparedVolume without = prepare_volume(g, grid_mean_extinction(g, d), false);
  EXPECT_EQ(with.weather.nx, 4);
  EXPECT_EQ(without.weather.nx, 0);
  EXPECT_TRUE(without.weather.type.empty());
  EXPECT_GT(with.column_maps[kColumnMapChannels * g.column(1, 0) + 2], 0.5f) << "the cumulus column's type reaches the kernel";
  EXPECT_EQ(without.column_maps[kColumnMapChannels * g.column(1, 0) + 2], 0.0f);
  d[Field::CloudFraction].clear();
  EXPECT_TRUE(prepare_volume(g, grid_mean_extinction(g, d), false).extinction.fraction.empty()) << "no cover diagnosed";
}

}  // namespace
}  // namespace cv::core
