// The analysts' probes and sections (core/analysis) against the volume they read, the march
// kernel's own interpolation, the raw file's values after the documented conversions (a synthetic
// file the test writes, and the real ERA5 file), and closed forms for the view ray.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <string>

#include "analysis/column_probe.hpp"
#include "analysis/compare.hpp"
#include "analysis/section.hpp"
#include "geo/geodesy.hpp"
#include "importer.hpp"
#include "kernel/march_kernel.hpp"
#include "kernel/prepared_volume.hpp"
#include "nc_file.hpp"
#include "support/cf_writer.hpp"
#include "support/nc_builder.hpp"
#include "reference/raymarcher.hpp"
#include "scene/framing.hpp"
#include "support/real_data.hpp"
#include "volume/grid_mean.hpp"

namespace {
using namespace cv;

constexpr double kR = 6371000.0;
double level_alt(double hpa) {
  const double h = cv::test::isa_height_m(hpa * 100.0);
  return h * kR / (kR - h);
}
// The synthetic cloud by hand (docs/importers.md, "The conversion"): in-cloud water q / cf, air
// density p / (R_d T_v) with T_v = T (1 + 0.608 q_v), sigma = 3 rho q / (2 rho_w r_eff), r_eff 10 um.
double synthetic_extinction(double p_pa, double cf) {
  const double rho = p_pa / (287.05 * 260.0 * (1.0 + 0.608 * 1e-3));
  return 3.0 * rho * (2e-4 / cf) / (2.0 * 1000.0 * 10e-6);
}
double zero_nan(float v) { return std::isnan(v) ? 0.0 : double(v); }

class Analysis : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = cv::test::temp_dir(::testing::UnitTest::GetInstance()->current_test_info()->name());
    cv::test::SynthOptions o;
    o.packed = false;
    path_ = (dir_ / "synth.nc").string();
    cv::test::write_synth(path_, o);
    importers::ImportOptions io;
    io.dz_m = level_alt(700) - level_alt(1000);  // a node exactly on the 700 hPa level (index 1)
    vol_ = importers::import_file(path_, io);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::filesystem::path dir_;
  std::string path_;
  core::CloudVolume vol_;
};

TEST_F(Analysis, ProbeAtAGridColumnIsTheVolumesColumnAndMaps) {
  const core::TimeStepData& d = vol_.step(0);
  const core::PreparedVolume prep = core::prepare_volume(vol_.grid, d);
  const auto& g = vol_.grid;
  int cloudy_columns = 0;
  for (int j = 0; j < g.lat_deg.count; ++j) {
    for (int i = 0; i < g.lon_deg.count; ++i) {
      const core::ColumnProbe p = core::probe_column(vol_, d, prep.extinction, g.lat_deg.at(j), g.lon_deg.at(i));
      ASSERT_EQ(p.levels.size(), static_cast<std::size_t>(g.alt_m.count));
      for (int k = 0; k < g.alt_m.count; ++k) {
        const auto& l = p.levels[static_cast<std::size_t>(k)];
        const std::size_t n = g.index(i, j, k);
        EXPECT_DOUBLE_EQ(l.alt_m, g.alt_m.at(k));
        EXPECT_DOUBLE_EQ(l.cloud_fraction, zero_nan(d[core::Field::CloudFraction][n])) << i << " " << j << " " << k;
        EXPECT_DOUBLE_EQ(l.ext_liquid_per_m, zero_nan(d[core::Field::ExtinctionLiquid][n]));
        EXPECT_DOUBLE_EQ(l.march_liquid_per_m, double(prep.extinction.liquid_per_m[n]));
        const float t = d[core::Field::Temperature][n];
        if (std::isnan(t)) EXPECT_TRUE(std::isnan(l.temperature_k));
        else EXPECT_DOUBLE_EQ(l.temperature_k, double(t));
        const float pa = d[core::Field::Pressure][n];  // the file is on pressure levels: the volume holds it
        if (std::isnan(pa)) EXPECT_TRUE(std::isnan(l.pressure_pa));
        else EXPECT_DOUBLE_EQ(l.pressure_pa, double(pa));
      }
      const std::size_t col = g.column(i, j);
      EXPECT_NEAR(p.cover, d.maps.cloud_cover[col], 1e-6);
      if (std::isnan(d.maps.cloud_base_m[col])) {
        EXPECT_TRUE(std::isnan(p.base_m));
      } else {
        ++cloudy_columns;
        EXPECT_NEAR(p.base_m, d.maps.cloud_base_m[col], 1e-3);
        EXPECT_NEAR(p.top_m, d.maps.cloud_top_m[col], 1e-3);
      }
      // The march's optical depth: the prepared column map (float).
      EXPECT_NEAR(p.optical_depth, prep.columns.tau[col], 1e-6 * prep.columns.tau[col] + 1e-9);
    }
  }
  EXPECT_GT(cloudy_columns, 0);
}

TEST_F(Analysis, ProbeBetweenColumnsIsTheMarchKernelsInterpolation) {
  const core::TimeStepData& d = vol_.step(1);
  const core::PreparedVolume prep = core::prepare_volume(vol_.grid, d);
  // The kernel the GPU runs, in double, over the same prepared texels.
  kernel::f64::MarchKernel k;
  core::Camera cam;
  static_cast<kernel::MarchParams&>(k) = core::march_params(prep, cam, core::Sun{}, core::MarchSettings{});
  const auto& g = vol_.grid;
  const glm::ivec3 n(g.lon_deg.count, g.lat_deg.count, g.alt_m.count);
  k.u_liquid = {prep.extinction.liquid_per_m.data(), n};
  k.u_ice = {prep.extinction.ice_per_m.data(), n};
  const double lat = 47.3, lon = 181.7;  // between columns (5-degree grid)
  const core::ColumnProbe p = core::probe_column(vol_, d, prep.extinction, lat, lon);
  bool some_cloud = false;
  for (const auto& l : p.levels) {
    double sl = 0.0, si = 0.0;
    k.medium_in(glm::dvec3(0.0), glm::dvec3(lat * M_PI / 180.0, lon * M_PI / 180.0, l.alt_m), l.alt_m, sl, si);
    EXPECT_NEAR(l.march_liquid_per_m, sl, 1e-12 + 1e-9 * sl) << l.alt_m;
    EXPECT_NEAR(l.march_ice_per_m, si, 1e-12 + 1e-9 * si);
    some_cloud |= sl > 0.0;
  }
  EXPECT_TRUE(some_cloud);
  // Cloud fraction bilinear by hand from the four columns around (45..50 N, 180..185 E).
  const int i0 = 2, j0 = 1;  // lon 180, lat 45
  ASSERT_DOUBLE_EQ(g.lon_deg.at(i0), 180.0);
  ASSERT_DOUBLE_EQ(g.lat_deg.at(j0), 45.0);
  const double wx = (lon - 180.0) / 5.0, wy = (lat - 45.0) / 5.0;
  const auto& cf = d[core::Field::CloudFraction];
  const double by_hand = (1 - wy) * ((1 - wx) * cf[g.index(i0, j0, 1)] + wx * cf[g.index(i0 + 1, j0, 1)]) +
                         wy * ((1 - wx) * cf[g.index(i0, j0 + 1, 1)] + wx * cf[g.index(i0 + 1, j0 + 1, 1)]);
  EXPECT_NEAR(p.levels[1].cloud_fraction, by_hand, 1e-12);
  // The optical depth is the march's column map read as its column_tau reads it.
  EXPECT_NEAR(p.optical_depth, prep.columns.at(g, lat, lon), 1e-5 * p.optical_depth);
}

TEST_F(Analysis, ProbeGivesTheRawFilesValuesAfterTheConversions) {
  const core::TimeStepData& d = vol_.step(0);
  const core::PreparedVolume prep = core::prepare_volume(vol_.grid, d);
  // 45 N 180 E at 700 hPa (node 1): cloud fraction 0.5, 2e-4 kg/kg of liquid, 260 K, u = 10 + lat / 10,
  // v = lon (in -180..180) / 100, as write_synth writes them.
  const core::ColumnProbe p = core::probe_column(vol_, d, prep.extinction, 45.0, 180.0);
  const auto& l = p.levels[1];
  EXPECT_NEAR(l.alt_m, level_alt(700), 0.5);
  EXPECT_NEAR(l.cloud_fraction, 0.5, 1e-6);
  EXPECT_NEAR(l.ext_liquid_per_m, synthetic_extinction(70000.0, 0.5), 1e-6 * synthetic_extinction(70000.0, 0.5));
  EXPECT_NEAR(l.march_liquid_per_m, 0.5 * synthetic_extinction(70000.0, 0.5), 1e-6 * synthetic_extinction(70000.0, 0.5));
  EXPECT_NEAR(l.temperature_k, 260.0, 1e-3);
  ASSERT_TRUE(vol_.has_field[static_cast<int>(core::Field::Pressure)]);
  EXPECT_NEAR(l.pressure_pa, 70000.0, 10.0);  // the level's altitude is the node's within 0.5 m: ~6 Pa
  EXPECT_NEAR(l.wind_u_m_s, 14.5, 1e-4);
  EXPECT_NEAR(l.wind_v_m_s, -1.8, 1e-4);
  EXPECT_EQ(p.levels[0].ext_liquid_per_m, 0.0);  // clear at 1000 hPa
  EXPECT_NEAR(p.base_m, l.alt_m, 1e-6);
  EXPECT_NEAR(p.top_m, l.alt_m, 1e-6);
  EXPECT_NEAR(p.cover, 0.5, 1e-6);
  EXPECT_TRUE(std::isnan(l.wind_w_m_s));  // the file has no vertical wind
}

TEST_F(Analysis, ProbeOutsideTheDataIsRefusedNamingTheExtent) {
  const core::TimeStepData& d = vol_.step(0);
  const auto medium = core::grid_mean_extinction(vol_.grid, d);
  EXPECT_FALSE(core::grid_holds(vol_.grid, 60.0, 180.0));
  EXPECT_FALSE(core::grid_holds(vol_.grid, 45.0, 160.0));
  EXPECT_TRUE(core::grid_holds(vol_.grid, 45.0, -170.0));  // 190 E in the other convention
  try {
    core::probe_column(vol_, d, medium, 60.0, 180.0);
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("lat 40..55, lon 170..195"), std::string::npos) << e.what();
  }
}

TEST_F(Analysis, ViewRayDepthsAgreeWithTheColumnByHand) {
  const core::TimeStepData& d = vol_.step(0);
  const core::PreparedVolume prep = core::prepare_volume(vol_.grid, d);
  const double lat = 45.0, lon = 180.0, cam_alt = 20000.0, step = 5.0;
  // Straight down onto the ground below.
  const core::ViewRayProbe r = core::probe_view_ray(prep, lat, lon, cam_alt, lat, lon, 0.0, step);
  const core::ColumnProbe p = core::probe_column(vol_, d, prep.extinction, lat, lon);
  // The profile is linear between levels: 0 at level 2, sigma at level 1 (the 700 hPa cloud).
  const double z_up = p.levels[2].alt_m, z_mid = p.levels[1].alt_m;
  const double sigma = p.levels[1].march_liquid_per_m;
  ASSERT_EQ(p.levels[2].march_liquid_per_m, 0.0);
  ASSERT_GT(sigma, 0.0);
  // tau(s) = sigma s^2 / (2 L) below z_up reaches ln 2 at s = sqrt(2 L ln 2 / sigma).
  const double s_half = std::sqrt(2.0 * (z_up - z_mid) * std::log(2.0) / sigma);
  ASSERT_LT(s_half, z_up - z_mid);
  EXPECT_NEAR(r.half_transmittance_m, cam_alt - z_up + s_half, step);
  EXPECT_NEAR(r.first_cloud_m, cam_alt - z_up, step);
  EXPECT_NEAR(r.distance_to_target_m, cam_alt, 1e-6);
  // The whole column: exp(-tau), tau the column's optical depth (thick: compare the logarithm).
  EXPECT_NEAR(-std::log(r.transmittance), p.optical_depth, 1e-3 * p.optical_depth);
  // A ray that meets no cloud: no first cloud, transmittance 1.
  const core::ViewRayProbe up = core::probe_view_ray(prep, lat, lon, 100.0, lat, lon, 90000.0, step);
  (void)up;
  const core::ViewRayProbe clear = core::probe_view_ray(prep, lat, lon, cam_alt, lat, lon, cam_alt + 10000.0, step);
  EXPECT_LT(clear.first_cloud_m, 0.0);
  EXPECT_LT(clear.half_transmittance_m, 0.0);
  EXPECT_DOUBLE_EQ(clear.transmittance, 1.0);
}

TEST_F(Analysis, SectionAlongAMeridianReadsTheGridsNodes) {
  const core::TimeStepData& d = vol_.step(0);
  const auto medium = core::grid_mean_extinction(vol_.grid, d);
  const auto& g = vol_.grid;
  std::vector<double> z;
  for (int k = 0; k < g.alt_m.count; ++k) z.push_back(g.alt_m.at(k));
  const core::SectionField f = core::section_field(vol_, "cloud_fraction");
  // 40 N to 55 N along 185 E: four columns land on the grid's rows.
  const core::Section s = core::vertical_section(vol_, d, medium, f, 40.0, 185.0, 55.0, 185.0, 4, z);
  EXPECT_NEAR(s.length_m, 15.0 * M_PI / 180.0 * g.earth_radius_m, 1e-6);
  ASSERT_EQ(s.path.size(), 4u);
  const int i = 3;
  ASSERT_DOUBLE_EQ(g.lon_deg.at(i), 185.0);
  int cloudy = 0;
  for (int c = 0; c < 4; ++c) {
    EXPECT_NEAR(s.path[static_cast<std::size_t>(c)].lat_deg, 40.0 + 5.0 * c, 1e-9);
    for (int k = 0; k < g.alt_m.count; ++k) {
      const double want = d[core::Field::CloudFraction][g.index(i, c, k)];
      const double got = s.value[static_cast<std::size_t>(c) * s.rows() + k];
      if (std::isnan(want)) EXPECT_TRUE(std::isnan(got));
      else EXPECT_NEAR(got, want, 1e-9) << c << " " << k;
      const bool hand = core::map_cloudy(zero_nan(d[core::Field::CloudFraction][g.index(i, c, k)]),
                                         zero_nan(d[core::Field::ExtinctionLiquid][g.index(i, c, k)]), core::MapOptions{});
      EXPECT_EQ(s.cloudy[static_cast<std::size_t>(c) * s.rows() + k] != 0, hand);
      cloudy += hand;
    }
  }
  EXPECT_EQ(cloudy, 4);  // the 700 hPa level of each column
  // The march's extinction as a field.
  const core::Section e = core::vertical_section(vol_, d, medium, core::section_field(vol_, "extinction"), 40.0, 185.0, 55.0, 185.0, 4, z);
  EXPECT_NEAR(e.value[1 * e.rows() + 1], medium.liquid_per_m[g.index(i, 1, 1)], 1e-9);
}

TEST_F(Analysis, SectionBadInputNamesWhatIsWrong) {
  const core::TimeStepData& d = vol_.step(0);
  const auto medium = core::grid_mean_extinction(vol_.grid, d);
  const std::vector<double> z{vol_.grid.alt_m.start};
  try {
    core::section_field(vol_, "rain");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("found \"rain\", expected extinction or a field the volume holds: extinction_liquid"), std::string::npos)
        << e.what();
  }
  const core::SectionField f = core::section_field(vol_, "temperature");
  // Shorter than a cell (5 degrees of latitude, and of longitude at 55 N about 319 km).
  EXPECT_NEAR(core::smallest_cell_m(vol_.grid), 5.0 * M_PI / 180.0 * kR * std::cos(55.0 * M_PI / 180.0), 1e-6);
  EXPECT_THROW(core::vertical_section(vol_, d, medium, f, 45.0, 180.0, 46.0, 180.0, 8, z), std::invalid_argument);
  EXPECT_THROW(core::vertical_section(vol_, d, medium, f, 45.0, 180.0, 70.0, 180.0, 8, z), std::invalid_argument);
  EXPECT_NO_THROW(core::vertical_section(vol_, d, medium, f, 40.0, 180.0, 55.0, 180.0, 8, z));
}

TEST(GreatCircle, DistancesAndPointsOnTheSphere) {
  // A quarter of the equator, and a meridian, by hand.
  EXPECT_NEAR(geo::great_circle_distance_m(0, 0, 0, 90, kR), 0.5 * M_PI * kR, 1e-6);
  const auto pts = geo::great_circle_points(0, -10, 0, 30, 5, kR);
  ASSERT_EQ(pts.size(), 5u);
  for (int i = 0; i < 5; ++i) {
    EXPECT_NEAR(pts[static_cast<std::size_t>(i)].lat_deg, 0.0, 1e-9);
    EXPECT_NEAR(pts[static_cast<std::size_t>(i)].lon_deg, -10.0 + 10.0 * i, 1e-9);
  }
  // The haversine distance between two general points.
  const double la1 = 30 * M_PI / 180, lo1 = 170 * M_PI / 180, la2 = 50 * M_PI / 180, lo2 = -160 * M_PI / 180;
  const double h = std::pow(std::sin((la2 - la1) / 2), 2) + std::cos(la1) * std::cos(la2) * std::pow(std::sin((lo2 - lo1) / 2), 2);
  EXPECT_NEAR(geo::great_circle_distance_m(30, 170, 50, -160, kR), 2 * kR * std::asin(std::sqrt(h)), 1e-6);
}

// The real ERA5 file at its cloudiest column: the probe's levels are the file's values unpacked and
// converted as docs/importers.md says (geometric height from geopotential, box-mean ice extinction
// 3 rho q / (2 rho_ice r_eff) with rho = p / (R_d T (1 + 0.608 q_v)) and r_eff = 50 + 0.5 T[C] um in
// 20..50, no water where the fraction is below 1e-4), linear in altitude between the file's levels.
TEST(AnalysisReal, Era5ProbeIsTheFilesValuesAfterTheConversions) {
  REAL_FILE(path, "met-era5-cocip1.nc");
  core::CloudVolume vol = importers::import_file(path);
  importers::NcFile f(path);
  // (longitude, latitude, level, time): 16 x 8 x 4 x 13, read whole at time 0.
  auto field = [&](const char* name) { return f.read(f.var(name), {0, 0, 0, 0}, {16, 8, 4, 1}); };
  const auto z = field("geopotential"), t = field("air_temperature"), cc = field("fraction_of_cloud_cover"),
             qi = field("specific_cloud_ice_water_content"), qv = field("specific_humidity");
  const auto lons = f.read(f.var("longitude"), {0}, {16});
  const auto lats = f.read(f.var("latitude"), {0}, {8});
  const auto levels = f.read(f.var("level"), {0}, {4});
  auto at = [](int i, int j, int k) { return static_cast<std::size_t>((i * 8 + j) * 4 + k); };
  int bi = 0, bj = 0;
  double most = -1.0;
  for (int i = 0; i < 16; ++i)
    for (int j = 0; j < 8; ++j)
      for (int k = 0; k < 4; ++k)
        if (cc[at(i, j, k)] * qi[at(i, j, k)] > most) most = cc[at(i, j, k)] * qi[at(i, j, k)], bi = i, bj = j;
  ASSERT_GT(most, 0.0);
  // The column by hand: each level's height and box-mean ice extinction.
  std::vector<double> h(4), mean(4), frac(4);
  for (int k = 0; k < 4; ++k) {
    const std::size_t n = at(bi, bj, k);
    h[static_cast<std::size_t>(k)] = z[n] * kR / (9.80665 * kR - z[n]);
    const double rho = levels[static_cast<std::size_t>(k)] * 100.0 / (287.05 * t[n] * (1.0 + 0.608 * qv[n]));
    const double r_eff_um = std::clamp(50.0 + 0.5 * (t[n] - 273.15), 20.0, 50.0);
    frac[static_cast<std::size_t>(k)] = cc[n];
    mean[static_cast<std::size_t>(k)] = cc[n] < 1e-4 ? 0.0 : 3.0 * rho * std::max(qi[n], 0.0) / (2.0 * 917.0 * r_eff_um * 1e-6);
  }
  const core::TimeStepData& d = vol.step(0);
  const core::PreparedVolume prep = core::prepare_volume(vol.grid, d);
  const core::ColumnProbe p = core::probe_column(vol, d, prep.extinction, lats[static_cast<std::size_t>(bj)], lons[static_cast<std::size_t>(bi)]);
  int checked = 0, cloudy = 0;
  for (const auto& l : p.levels) {
    for (int k = 0; k + 1 < 4; ++k) {
      const auto a = static_cast<std::size_t>(k), b = a + 1;
      const double lo = std::min(h[a], h[b]), hi = std::max(h[a], h[b]);
      if (!(l.alt_m >= lo && l.alt_m <= hi)) continue;
      const double w = (l.alt_m - h[a]) / (h[b] - h[a]);
      const double want = (1 - w) * mean[a] + w * mean[b];
      EXPECT_NEAR(l.march_ice_per_m, want, 1e-4 * want + 1e-9) << l.alt_m;
      EXPECT_NEAR(l.cloud_fraction, (1 - w) * frac[a] + w * frac[b], 1e-4) << l.alt_m;
      ++checked;
      cloudy += want > 0.0;
      break;
    }
  }
  EXPECT_GE(checked, 3);
  EXPECT_GE(cloudy, 1);
}

// Layer masks in the march kernel (march_settings.def, layer_bottom_m), on the real WRF file over
// the Tibetan Plateau (terrain 4.5-5.5 km), where bands above sea level would put low cloud in "mid".
class LayerMask : public ::testing::Test {
 protected:
  void SetUp() override {
    path_ = cv::test::real_file("wrf_d01_allvars_cropped.nc");
    if (path_.empty()) GTEST_SKIP() << "wrf_d01_allvars_cropped.nc not found beside the checkout";
    vol_ = importers::import_file(path_);
    ASSERT_TRUE(vol_.has_ground);
    prep_ = core::prepare_volume(vol_.grid, vol_.step(1));
  }
  // The kernel over the prepared volume with the march settings `s`.
  kernel::f64::MarchKernel kernel(const core::MarchSettings& s) const {
    kernel::f64::MarchKernel k;
    static_cast<kernel::MarchParams&>(k) = core::march_params(prep_, core::Camera{}, core::Sun{}, s);
    const auto& g = prep_.grid;
    const glm::ivec3 n(g.lon_deg.count, g.lat_deg.count, g.alt_m.count);
    k.u_liquid = {prep_.extinction.liquid_per_m.data(), n};
    k.u_ice = {prep_.extinction.ice_per_m.data(), n};
    k.u_column_tau = {prep_.column_maps.data(), {prep_.columns.nx, prep_.columns.ny, int(core::kColumnMapLayers)}, int(core::kColumnMapChannels)};
    return k;
  }
  static core::MarchSettings band(const std::string& name, bool sea_level = false) {
    core::MarchSettings s;
    core::LayerBand b;
    EXPECT_TRUE(core::named_layer_band(name, b));
    s.medium.layer_bottom_m = b.bottom_m;
    s.medium.layer_top_m = b.top_m;
    s.medium.layer_sea_level = sea_level;
    return s;
  }
  std::string path_;
  core::CloudVolume vol_;
  core::PreparedVolume prep_;
};

TEST_F(LayerMask, LowMidHighPartitionTheCloudAboveTheGround) {
  const auto& g = prep_.grid;
  auto all = kernel(core::MarchSettings{});
  auto low = kernel(band("low")), mid = kernel(band("mid")), high = kernel(band("high"));
  auto mid_sea = kernel(band("mid", true));
  int cloudy = 0, low_cloudy = 0, low_but_mid_above_sea = 0;
  // Points between the nodes (and on them) across the whole grid.
  for (double fx = 0.0; fx <= g.lon_deg.count - 1; fx += 0.37) {
    for (double fy = 0.0; fy <= g.lat_deg.count - 1; fy += 0.41) {
      for (double fz = 0.0; fz <= g.alt_m.count - 1; fz += 0.23) {
        const double lat = g.lat_deg.start + fy * g.lat_deg.step, lon = g.lon_deg.start + fx * g.lon_deg.step;
        const double alt = g.alt_m.start + fz * g.alt_m.step;
        const glm::dvec3 geo(lat * M_PI / 180.0, lon * M_PI / 180.0, alt);
        double l0, i0, l[3], ic[3];
        all.medium_in(glm::dvec3(0.0), geo, alt, l0, i0);
        low.medium_in(glm::dvec3(0.0), geo, alt, l[0], ic[0]);
        mid.medium_in(glm::dvec3(0.0), geo, alt, l[1], ic[1]);
        high.medium_in(glm::dvec3(0.0), geo, alt, l[2], ic[2]);
        if (!(l0 + i0 > 0.0)) {
          for (int b = 0; b < 3; ++b) EXPECT_EQ(l[b] + ic[b], 0.0);
          continue;
        }
        ++cloudy;
        // Exactly one band holds the point, with the whole medium.
        int holding = 0;
        for (int b = 0; b < 3; ++b) {
          if (l[b] + ic[b] > 0.0) {
            ++holding;
            EXPECT_EQ(l[b], l0);
            EXPECT_EQ(ic[b], i0);
          }
        }
        EXPECT_EQ(holding, 1) << lat << " " << lon << " " << alt;
        if (l[0] + ic[0] > 0.0) {
          ++low_cloudy;
          double ls, is;
          mid_sea.medium_in(glm::dvec3(0.0), geo, alt, ls, is);
          low_but_mid_above_sea += ls + is > 0.0;
        }
      }
    }
  }
  EXPECT_GT(cloudy, 100);
  EXPECT_GT(low_cloudy, 0);
  // Over 4.5-5.5 km of terrain the low cloud lies 4.5-7.5 km above sea level: bands from sea level
  // would call some of it mid.
  EXPECT_GT(low_but_mid_above_sea, 0);
}

TEST_F(LayerMask, BandsAddUpPixelByPixelAndPhasesSplitTheCloud) {
  // The view optical depths of the three bands add up to the whole cloud's at every pixel: the
  // same samples, each point in one band.
  const auto& g = prep_.grid;
  core::Camera cam;
  cam.lat_deg = g.lat_deg.start - 1.0;
  cam.lon_deg = 0.5 * (g.lon_deg.start + g.lon_deg.last());
  cam.alt_m = 9000.0;
  cam.pitch_deg = -8.0;
  cam.fov_deg = 50.0;
  cam.width = 24;
  cam.height = 14;
  auto settings = [](core::MarchSettings s) {
    s.quality.view_step_m = 500.0;
    s.quality.min_transmittance = 0.0;
    return s;
  };
  const auto tau = [&](const core::MarchSettings& s) {
    const core::ReferenceImage img = core::render_reference(prep_, cam, core::Sun{}, settings(s));
    std::vector<double> t;
    for (double x : img.transmittance) t.push_back(-std::log(x));
    return t;
  };
  core::MarchSettings liquid_only, ice_only;
  liquid_only.medium.hide_ice = true;
  ice_only.medium.hide_liquid = true;
  const auto all = tau(core::MarchSettings{}), low = tau(band("low")), mid = tau(band("mid")), high = tau(band("high"));
  const auto liquid = tau(liquid_only), ice = tau(ice_only);
  double most = 0.0;
  for (std::size_t p = 0; p < all.size(); ++p) {
    most = std::max(most, all[p]);
    EXPECT_NEAR(low[p] + mid[p] + high[p], all[p], 1e-9 * all[p] + 1e-12) << p;
    EXPECT_NEAR(liquid[p] + ice[p], all[p], 1e-9 * all[p] + 1e-12) << p;
  }
  EXPECT_GT(most, 0.1);  // the camera sees cloud
}

// Two clouds at 700 hPa on a 2-degree grid (columns 1-2 x rows 1-2, and columns 6-7 x rows 3-4);
// `second` false leaves the second out. The fields as write_synth names them.
void write_two_clouds(const std::string& path, bool second, double lon0 = 0.0) {
  using cv::test::CfAxis;
  using cv::test::CfVar;
  std::vector<double> lons, lats{40, 42, 44, 46, 48, 50};
  for (int i = 0; i < 10; ++i) lons.push_back(lon0 + 2.0 * i);
  const std::vector<double> hpa{1000, 850, 700, 500};
  const std::vector<CfAxis> axes = {{"time", {0.0}, {{"units", "hours since 2024-01-15 00:00:00"}, {"calendar", "gregorian"}}},
                                    {"level", hpa, {{"units", "hPa"}}},
                                    {"latitude", lats, {{"units", "degrees_north"}}},
                                    {"longitude", lons, {{"units", "degrees_east"}}}};
  const std::vector<std::string> dims{"time", "level", "latitude", "longitude"};
  auto in_cloud = [second](const std::vector<int>& x) {
    const int k = x[1], j = x[2], i = x[3];
    if (k != 2) return false;
    return (i >= 1 && i <= 2 && j >= 1 && j <= 2) || (second && i >= 6 && i <= 7 && j >= 3 && j <= 4);
  };
  const std::vector<CfVar> vars = {
      {"z", dims, {{"units", "m**2 s**-2"}, {"standard_name", "geopotential"}}, {},
       [&](const std::vector<int>& x) { return 9.80665 * cv::test::isa_height_m(hpa[static_cast<std::size_t>(x[1])] * 100.0); }},
      {"t", dims, {{"units", "K"}, {"standard_name", "air_temperature"}}, {}, [](const std::vector<int>&) { return 260.0; }},
      {"q", dims, {{"units", "kg kg**-1"}, {"standard_name", "specific_humidity"}}, {}, [](const std::vector<int>&) { return 1e-3; }},
      {"cc", dims, {{"units", "(0 - 1)"}}, {}, [&](const std::vector<int>& x) { return in_cloud(x) ? 0.6 : 0.0; }},
      {"clwc", dims, {{"units", "kg kg**-1"}}, {}, [&](const std::vector<int>& x) { return in_cloud(x) ? 2e-4 : 0.0; }},
  };
  cv::test::write_cf(path, axes, vars);
}

class Compare : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = cv::test::temp_dir(::testing::UnitTest::GetInstance()->current_test_info()->name()); }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  core::CloudVolume import(bool second, double lon0 = 0.0) {
    const std::string p = (dir_ / (std::string(second ? "two" : "one") + std::to_string(int(lon0)) + ".nc")).string();
    write_two_clouds(p, second, lon0);
    importers::ImportOptions o;
    o.dz_m = level_alt(850) - level_alt(1000);
    return importers::import_file(p, o);
  }
  std::filesystem::path dir_;
};

TEST_F(Compare, AFileAgainstItselfIsZeroEverywhereAndAllBoth) {
  core::CloudVolume a = import(true);
  const core::Overlap o = core::grid_overlap(a.grid, a.grid);
  ASSERT_FALSE(o.empty);
  const core::VolumeGrid g = core::common_grid(a.grid, a.grid, o);
  EXPECT_EQ(g.lon_deg.count, a.grid.lon_deg.count);
  EXPECT_EQ(g.lat_deg.count, a.grid.lat_deg.count);
  EXPECT_EQ(g.alt_m.count, a.grid.alt_m.count);
  const core::Comparison c = core::compare_steps(a.grid, a.step(0), a.grid, a.step(0), g);
  int both = 0;
  for (std::size_t i = 0; i < c.columns.size(); ++i) {
    EXPECT_TRUE(c.columns[i] == core::Presence::Both || c.columns[i] == core::Presence::None) << i;
    both += c.columns[i] == core::Presence::Both;
    EXPECT_EQ(c.d_cover[i], 0.0f);
    EXPECT_EQ(c.d_optical_depth[i], 0.0f);
    if (c.columns[i] == core::Presence::Both) {
      EXPECT_EQ(c.d_base_m[i], 0.0f);
      EXPECT_EQ(c.d_top_m[i], 0.0f);
    }
  }
  EXPECT_EQ(both, 8);  // the two clouds' 2 x 2 columns each
  int points_both = 0;
  for (core::Presence p : c.points) {
    EXPECT_TRUE(p == core::Presence::Both || p == core::Presence::None);
    points_both += p == core::Presence::Both;
  }
  EXPECT_GT(points_both, 0);
}

TEST_F(Compare, ACloudRemovedFromTheCopyIsExactlyTheAOnlyCloud) {
  core::CloudVolume a = import(true), b = import(false);
  const core::VolumeGrid g = core::common_grid(a.grid, b.grid, core::grid_overlap(a.grid, b.grid));
  const core::Comparison c = core::compare_steps(a.grid, a.step(0), b.grid, b.step(0), g);
  for (int j = 0; j < g.lat_deg.count; ++j) {
    for (int i = 0; i < g.lon_deg.count; ++i) {
      const bool first = i >= 1 && i <= 2 && j >= 1 && j <= 2, second = i >= 6 && i <= 7 && j >= 3 && j <= 4;
      const std::size_t col = g.column(i, j);
      const core::Presence want = first ? core::Presence::Both : second ? core::Presence::OnlyA : core::Presence::None;
      EXPECT_EQ(static_cast<int>(c.columns[col]), static_cast<int>(want)) << i << " " << j;
      if (second) EXPECT_FLOAT_EQ(c.d_cover[col], -c.a.maps.cloud_cover[col]);
      else EXPECT_EQ(c.d_cover[col], 0.0f);
    }
  }
  for (std::size_t p = 0; p < c.points.size(); ++p) EXPECT_NE(static_cast<int>(c.points[p]), static_cast<int>(core::Presence::OnlyB));
}

// The rendered difference view (compare --render): its medium and its false colour, on the CPU
// kernel. Without the air the light of a sample is grey, so its colour is its tint's hue alone.
core::ReferenceImage difference_view(const core::Comparison& c, core::MarchSettings& s) {
  const core::PreparedVolume pv = core::prepare_volume(c.grid, core::presence_medium(c));
  core::Camera cam = core::auto_camera(c.grid, 48, 27);
  core::Sun sun;
  sun.subsolar_lat_deg = 45.0, sun.subsolar_lon_deg = 9.0;  // noon over the clouds
  s.quality.view_step_m = 500.0;
  s.quality.sun_steps = 8;
  s.medium.tint_liquid = {1.0, 0.525, 0.05};  // compare's orange (A only) and blue (B only)
  s.medium.tint_ice = {0.05, 0.525, 1.0};
  return core::render_reference(pv, cam, sun, s);
}

double luminance(const glm::dvec3& c) { return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z; }

TEST_F(Compare, TheDifferenceViewOfAFileWithItselfIsAllBothAndRendersWhite) {
  core::CloudVolume a = import(true);
  const core::VolumeGrid g = core::common_grid(a.grid, a.grid, core::grid_overlap(a.grid, a.grid));
  const core::Comparison c = core::compare_steps(a.grid, a.step(0), a.grid, a.step(0), g);
  const core::TimeStepData m = core::presence_medium(c);
  const core::GridMeanExtinction own = core::grid_mean_extinction(g, c.a);
  int cloudy = 0;
  for (std::size_t p = 0; p < g.points(); ++p) {
    const float l = m[core::Field::ExtinctionLiquid][p], i = m[core::Field::ExtinctionIce][p];
    EXPECT_EQ(l, i) << p;  // both: half in each component
    if (c.points[p] == core::Presence::Both) {
      ++cloudy;
      EXPECT_FLOAT_EQ(l + i, own.liquid_per_m[p] + own.ice_per_m[p]) << p;
    } else {
      EXPECT_EQ(l, 0.0f) << p;
    }
  }
  EXPECT_GT(cloudy, 0);
  core::MarchSettings s;
  ASSERT_FALSE(s.features.atmosphere);
  const core::ReferenceImage img = difference_view(c, s);
  double max_l = 0.0;
  for (const auto& r : img.radiance) max_l = std::max(max_l, luminance(r));
  ASSERT_GT(max_l, 0.0);
  for (const auto& r : img.radiance) {  // white: the tints' mean is grey
    EXPECT_NEAR(r.x, r.y, 1e-9 * max_l);
    EXPECT_NEAR(r.z, r.y, 1e-9 * max_l);
  }
}

TEST_F(Compare, TheDifferenceViewShowsTheRemovedCloudOrangeAndNothingBlue) {
  core::CloudVolume a = import(true), b = import(false);
  const core::VolumeGrid g = core::common_grid(a.grid, b.grid, core::grid_overlap(a.grid, b.grid));
  const core::Comparison c = core::compare_steps(a.grid, a.step(0), b.grid, b.step(0), g);
  const core::TimeStepData m = core::presence_medium(c);
  int only_a = 0;
  for (std::size_t p = 0; p < g.points(); ++p) {
    const float l = m[core::Field::ExtinctionLiquid][p], i = m[core::Field::ExtinctionIce][p];
    if (c.points[p] == core::Presence::OnlyA) {
      ++only_a;
      EXPECT_GT(l, 0.0f) << p;
      EXPECT_EQ(i, 0.0f) << p;  // A only: liquid, the orange component, alone
    } else {
      EXPECT_EQ(l, i) << p;
    }
  }
  EXPECT_GT(only_a, 0);
  core::MarchSettings s;
  const core::ReferenceImage img = difference_view(c, s);
  double max_l = 0.0, orange = 0.0;
  for (const auto& r : img.radiance) max_l = std::max(max_l, luminance(r));
  ASSERT_GT(max_l, 0.0);
  for (const auto& r : img.radiance) {
    EXPECT_LE(r.z, r.x + 1e-9 * max_l);  // no pixel bluer than it is red: nothing is in B only
    if (luminance(r) > 1e-3 * max_l) orange = std::max(orange, (r.x - r.z) / luminance(r));
  }
  EXPECT_GT(orange, 0.5);  // the removed cloud shows orange
}

TEST_F(Compare, TheCommonGridIsTheCoarserOverTheOverlapAndDisjointGridsHaveNone) {
  core::CloudVolume a = import(true);
  core::VolumeGrid coarse = a.grid;
  coarse.lon_deg.step = 5.0;
  coarse.lon_deg.count = 3;  // 0..10 E
  coarse.lat_deg.start = 44.0;
  const core::Overlap o = core::grid_overlap(a.grid, coarse);
  ASSERT_FALSE(o.empty);
  EXPECT_DOUBLE_EQ(o.lon_lo, 0.0);
  EXPECT_DOUBLE_EQ(o.lon_hi, 10.0);
  EXPECT_DOUBLE_EQ(o.lat_lo, 44.0);
  const core::VolumeGrid g = core::common_grid(a.grid, coarse, o);
  EXPECT_DOUBLE_EQ(g.lon_deg.step, 5.0);
  EXPECT_EQ(g.lon_deg.count, 3);
  EXPECT_DOUBLE_EQ(g.lat_deg.step, 2.0);
  EXPECT_NE(core::common_grid_text(g, a.grid, coarse).find("the coarser of A's 2/2 deg"), std::string::npos)
      << core::common_grid_text(g, a.grid, coarse);
  core::CloudVolume far = import(true, 100.0);
  EXPECT_TRUE(core::grid_overlap(a.grid, far.grid).empty);
  // The same region in the other longitude convention overlaps.
  core::CloudVolume west = import(true, -360.0);
  EXPECT_FALSE(core::grid_overlap(a.grid, west.grid).empty);
}

}  // namespace

// The column map's second layer holds the ice's part of each column's optical depth, so the
// two-stream's sky light under a column takes each phase's mean cosine: (1 - g_l) tau_l +
// (1 - g_i) tau_i, not the droplets' g for all of it (which let through 1.5 times the sky's light
// under ice of optical depth 10). Hidden ice and layer masks take it out as they take out the total.
TEST(ColumnMap, TheSkysDepthTakesEachPhasesMeanCosine) {
  core::VolumeGrid g;
  g.lon_deg = {10.0, 1.0, 4};
  g.lat_deg = {20.0, 1.0, 3};
  g.alt_m = {1000.0, 500.0, 5};
  core::GridMeanExtinction e;
  e.liquid_per_m.assign(g.points(), 0.0f);
  e.ice_per_m.assign(g.points(), 0.0f);
  for (int k = 0; k < 5; ++k) {
    e.ice_per_m[g.index(1, 1, k)] = 2.5e-3f;     // ice alone: optical depth 4 x 500 m x 2.5e-3 = 5
    e.liquid_per_m[g.index(2, 1, k)] = 2.5e-3f;  // liquid alone: 5
    e.ice_per_m[g.index(3, 1, k)] = 1.0e-3f;     // both: ice 2, liquid 3
    e.liquid_per_m[g.index(3, 1, k)] = 1.5e-3f;
  }
  const core::PreparedVolume v = core::prepare_volume(g, e);
  const std::size_t columns = static_cast<std::size_t>(g.columns());
  ASSERT_EQ(v.column_maps.size(), core::kColumnMapLayers * core::kColumnMapChannels * columns);
  auto ice_depth = [&](const std::vector<float>& maps, int x, int y) { return maps[core::kColumnMapChannels * (columns + g.column(x, y))]; };
  EXPECT_NEAR(ice_depth(v.column_maps, 1, 1), 5.0, 1e-5);
  EXPECT_EQ(ice_depth(v.column_maps, 2, 1), 0.0f);
  EXPECT_NEAR(ice_depth(v.column_maps, 3, 1), 2.0, 1e-5);
  EXPECT_EQ(ice_depth(v.column_maps, 0, 1), 0.0f);
  // The kernel's depth for the sky at the ground under each column.
  core::MarchSettings s;
  kernel::f64::MarchKernel k;
  static_cast<kernel::MarchParams&>(k) = core::march_params(v, core::Camera{}, core::Sun{}, s);
  k.u_column_tau = {v.column_maps.data(), {v.columns.nx, v.columns.ny, int(core::kColumnMapLayers)}, int(core::kColumnMapChannels)};
  const double gl = 0.88, gi = 0.75;
  auto depth_at = [&](int x) {
    const glm::dvec3 p = geo::sphere_to_ecef({g.lat_deg.at(1), g.lon_deg.at(x), 0.0}, g.earth_radius_m);
    return k.column_diffusion_depth(p, gl, gi);
  };
  EXPECT_NEAR(depth_at(1), (1.0 - gi) * 5.0, 1e-5);
  EXPECT_NEAR(depth_at(2), (1.0 - gl) * 5.0, 1e-5);
  EXPECT_NEAR(depth_at(3), (1.0 - gl) * 3.0 + (1.0 - gi) * 2.0, 1e-5);
  EXPECT_NEAR(depth_at(0), 0.0, 1e-9);  // a clear column (its neighbour's weight is rounding)
  // Under ice of optical depth 5 the sky's share is that of ice's g: 1 / (1 + 0.75 x 0.25 x 5).
  EXPECT_NEAR(cv::physics::f64::sky_share_of_depth(depth_at(1)), 1.0 / (1.0 + 0.75 * 0.25 * 5.0), 1e-6);
  // Hidden ice: no ice depth; a band above the cloud: none of either.
  core::MediumMask no_ice;
  no_ice.hide_ice = true;
  const std::vector<float> hidden = core::column_maps_for(v, no_ice);
  EXPECT_EQ(ice_depth(hidden, 1, 1), 0.0f);
  EXPECT_EQ(ice_depth(hidden, 3, 1), 0.0f);
  EXPECT_NEAR(hidden[core::kColumnMapChannels * g.column(3, 1)], 3.0, 1e-5);  // the liquid's part stays
  core::MediumMask above;
  above.band = true;
  above.sea_level = true;
  above.bottom_m = 5000.0;
  above.top_m = 9000.0;
  const std::vector<float> high = core::column_maps_for(v, above);
  EXPECT_EQ(ice_depth(high, 1, 1), 0.0f);
  EXPECT_EQ(high[core::kColumnMapChannels * g.column(1, 1)], 0.0f);
}
