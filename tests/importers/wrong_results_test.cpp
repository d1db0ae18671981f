// Issue 12: each wrong importer result an independent check found on real files, reproduced by a
// file the test writes, and the misleading messages. Expected values come from the formulas, by
// hand, never from the importer.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <vector>

#include "cf_layout.hpp"
#include "column.hpp"
#include "diagnosed_cloud.hpp"
#include "importer.hpp"
#include "support/cf_writer.hpp"
#include "support/nc_builder.hpp"
#include "volume/volume_io.hpp"

namespace {
using namespace cv;
using cv::test::CfAxis;
using cv::test::CfVar;
using Idx = std::vector<int>;

constexpr double kR = 6371000.0;
constexpr double kG0 = 9.80665;
double geometric(double gpm) { return gpm * kR / (kR - gpm); }
double level_alt(double hpa) { return geometric(cv::test::isa_height_m(hpa * 100.0)); }
double liquid_sigma(double rho, double q) { return 3.0 * rho * q / (2.0 * 1000.0 * 10e-6); }
double ice_sigma(double rho, double q, double t_k) {
  const double r_um = std::clamp(50.0 + 0.5 * (t_k - 273.15), 20.0, 50.0);
  return 3.0 * rho * q / (2.0 * 917.0 * r_um * 1e-6);
}

class CfImportFixes : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = cv::test::temp_dir(::testing::UnitTest::GetInstance()->current_test_info()->name()); }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string path(const std::string& name) { return (dir_ / name).string(); }
  std::filesystem::path dir_;
};

std::string expect_import_error(const std::string& p, const importers::ImportOptions& o = {}) {
  try {
    importers::import_file(p, o);
  } catch (const importers::ImportError& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected an ImportError from " << p;
  return "";
}

bool any_contains(const std::vector<std::string>& lines, const std::string& what) {
  for (const auto& l : lines) {
    if (l.find(what) != std::string::npos) return true;
  }
  return false;
}

// ERA5-style axes: longitude, latitude, pressure levels in hPa, one time.
std::vector<CfAxis> era5_axes(std::vector<double> lons, std::vector<double> lats, std::vector<double> hpa) {
  return {{"time", {0.0}, {{"units", "hours since 2024-01-15 00:00:00"}}},
          {"level", hpa, {{"units", "hPa"}}},
          {"latitude", lats, {{"units", "degrees_north"}}},
          {"longitude", lons, {{"units", "degrees_east"}}}};
}
const std::vector<std::string> kDims = {"time", "level", "latitude", "longitude"};
CfVar geopotential(const std::vector<double>& hpa) {
  return {"z", kDims, {{"units", "m**2 s**-2"}, {"standard_name", "geopotential"}}, {},
          [hpa](const Idx& i) { return kG0 * cv::test::isa_height_m(hpa[static_cast<std::size_t>(i[1])] * 100.0); }};
}
CfVar constant(const std::string& name, const std::string& units, const std::string& sn, double v) {
  return {name, kDims, {{"units", units}, {"standard_name", sn}}, {}, [v](const Idx&) { return v; }};
}

// 1. A global grid whose wrap gap (350 -> 360) is shorter than its 25-degree step: cut at the wrap,
// imported, every region works, and `info` agrees with `import`.
TEST_F(CfImportFixes, GlobalGridWithAShortWrapGapIsCutAtTheWrap) {
  std::vector<double> lons;
  for (int k = 0; k <= 14; ++k) lons.push_back(25.0 * k);  // 0 .. 350
  const std::vector<double> hpa = {1000, 700, 500};
  const std::string p = path("wrap.nc");
  cv::test::write_cf(p, era5_axes(lons, {-10, 0, 10}, hpa),
                     {geopotential(hpa), constant("t", "K", "air_temperature", 260.0),
                      {"cc", kDims, {{"units", "(0 - 1)"}}, {}, [](const Idx& i) { return i[1] == 1 ? 0.5 : 0.0; }},
                      {"clwc", kDims, {{"units", "kg kg**-1"}}, {}, [](const Idx& i) { return i[1] == 1 ? 2e-4 : 0.0; }}});
  auto v = importers::import_file(p);
  EXPECT_DOUBLE_EQ(v.grid.lon_deg.start, 0.0);
  EXPECT_DOUBLE_EQ(v.grid.lon_deg.step, 25.0);
  EXPECT_EQ(v.grid.lon_deg.count, 15);
  EXPECT_FALSE(v.grid.wraps_lon());  // 15 x 25 = 375: not a closed circle
  EXPECT_TRUE(any_contains(v.report.notes, "do not close the circle evenly")) << v.report.to_text();
  importers::ImportOptions o;
  o.region = importers::Region{20.0, 130.0, -90.0, 90.0};
  auto r = importers::import_file(p, o);
  EXPECT_DOUBLE_EQ(r.grid.lon_deg.start, 25.0);
  EXPECT_EQ(r.grid.lon_deg.count, 5);  // 25 .. 125
  const std::string info = importers::describe_file(p);
  EXPECT_NE(info.find("importable: yes"), std::string::npos) << info;
  // A grid that really is uneven: import refuses, and info says the same.
  const std::string q = path("uneven.nc");
  cv::test::write_cf(q, era5_axes({0, 25, 50, 100, 125, 150}, {-10, 0, 10}, hpa),
                     {geopotential(hpa), {"cc", kDims, {{"units", "(0 - 1)"}}, {}, [](const Idx&) { return 0.5; }}});
  const std::string why = expect_import_error(q);
  EXPECT_NE(why.find("not evenly spaced"), std::string::npos) << why;
  const std::string info2 = importers::describe_file(q);
  EXPECT_NE(info2.find("importable: no: " + why), std::string::npos) << info2;
}

// A GFS file as netCDF-Java writes it: one time, the isobaric levels 1000, 700 and 500 hPa in Pa,
// 2 x 3 points; the standard atmosphere's height at each level.
const std::vector<std::string> kGfsJavaDims = {"time1", "isobaric3", "lat", "lon"};
std::vector<CfAxis> gfs_java_axes() {
  return {{"time1", {0.0}, {{"units", "Hour since 2021-01-30T12:00:00Z"}}},
          {"isobaric3", {100000, 70000, 50000}, {{"units", "Pa"}, {"positive", "down"}}},
          {"lat", {0, 10}, {{"units", "degrees_north"}}},
          {"lon", {0, 10, 20}, {{"units", "degrees_east"}}}};
}
double gfs_java_height(const Idx& i) {
  static const double kHpa[] = {1000, 700, 500};
  return cv::test::isa_height_m(kHpa[static_cast<std::size_t>(i[1])] * 100.0);
}

// 2. GFS/NCEP names: netCDF-Java's "<Name>_isobaric" with Grib2_Parameter, a cloud cover in %,
// "u-component_of_wind_isobaric"; and plain "ice_water_mixing_ratio" with uppercase T/U/V.
TEST_F(CfImportFixes, GribToNetcdfNamesAreRecognised) {
  const std::vector<std::string> d = kGfsJavaDims;
  const std::vector<CfAxis> axes = gfs_java_axes();
  auto gh = gfs_java_height;
  const std::string a = path("gfs_java.nc");
  cv::test::write_cf(a, axes,
                     {{"Geopotential_height_isobaric", d, {{"units", "gpm"}}, {{"Grib2_Parameter", {0, 3, 5}}}, gh},
                      {"Temperature_isobaric", d, {{"units", "K"}}, {{"Grib2_Parameter", {0, 0, 0}}}, [](const Idx&) { return 250.0; }},
                      {"Ice_water_mixing_ratio_isobaric", d, {{"units", "kg/kg"}, {"abbreviation", "ICMR"}}, {{"Grib2_Parameter", {0, 1, 23}}},
                       [](const Idx& i) { return i[1] == 1 ? 1e-5 : 0.0; }},
                      {"Total_cloud_cover_isobaric", d, {{"units", "%"}}, {{"Grib2_Parameter", {0, 6, 1}}},
                       [](const Idx& i) { return i[1] == 1 ? 40.0 : 0.0; }},
                      {"u-component_of_wind_isobaric", d, {{"units", "m/s"}}, {}, [](const Idx&) { return 7.0; }},
                      {"v-component_of_wind_isobaric", d, {{"units", "m/s"}}, {}, [](const Idx&) { return -3.0; }}});
  importers::ImportOptions o;
  o.dz_m = level_alt(700) - level_alt(1000);  // node 1 on the 700 hPa level
  auto v = importers::import_file(a, o);
  ASSERT_TRUE(v.has_field[static_cast<int>(core::Field::ExtinctionIce)]);
  ASSERT_TRUE(v.has_field[static_cast<int>(core::Field::CloudFraction)]);
  const auto& s = v.step(0);
  const std::size_t p = v.grid.index(1, 0, 1);
  EXPECT_NEAR(s[core::Field::CloudFraction][p], 0.4, 1e-6);  // 40 % as a fraction
  const double rho = 70000.0 / (287.05 * 250.0);
  EXPECT_NEAR(s[core::Field::ExtinctionIce][p], ice_sigma(rho, 1e-5 / 0.4, 250.0), 1e-6 * ice_sigma(rho, 1e-5 / 0.4, 250.0));
  EXPECT_NEAR(s[core::Field::WindU][p], 7.0, 1e-5);
  EXPECT_NEAR(s[core::Field::WindV][p], -3.0, 1e-5);
  EXPECT_NEAR(s[core::Field::Temperature][p], 250.0, 1e-4);
  // The plain GRIB-derived name of the issue, with uppercase T, U, V.
  const std::string b = path("gfs_plain.nc");
  cv::test::write_cf(b, axes,
                     {{"Geopotential_height_isobaric", d, {{"units", "gpm"}}, {}, gh},
                      {"T", d, {{"units", "K"}}, {}, [](const Idx&) { return 250.0; }},
                      {"U", d, {{"units", "m s-1"}}, {}, [](const Idx&) { return 7.0; }},
                      {"V", d, {{"units", "m s-1"}}, {}, [](const Idx&) { return -3.0; }},
                      {"ice_water_mixing_ratio", d, {{"units", "kg/kg"}}, {}, [](const Idx& i) { return i[1] == 1 ? 1e-5 : 0.0; }}});
  auto w = importers::import_file(b, o);
  const auto& t = w.step(0);
  EXPECT_NEAR(t[core::Field::ExtinctionIce][p], ice_sigma(rho, 1e-5, 250.0), 1e-6 * ice_sigma(rho, 1e-5, 250.0));  // fills its box
  EXPECT_NEAR(t[core::Field::WindU][p], 7.0, 1e-5);
  EXPECT_NEAR(t[core::Field::WindV][p], -3.0, 1e-5);
  EXPECT_EQ(w.report.use("temperature").variable, "T");
}

// 4. Water in boxes whose fraction is zero: never divided by a floor fraction, never interpolated
// as two factors. Between a zero-fraction box with packing noise and a cloudy box, fraction x
// in-cloud extinction is the linear interpolation of the two grid-box means.
TEST_F(CfImportFixes, WaterWithoutCloudFractionIsNotInflated) {
  const std::vector<double> hpa = {1000, 850, 700, 500};
  const std::string p = path("nofraction.nc");
  // At 850 hPa the fraction is 0 with a little water: 4.7e-8 kg/kg (packing noise) in every column
  // but the first, where it is 1e-5 kg/kg. At 700 hPa: fraction 0.5, water 2e-4.
  cv::test::write_cf(p, era5_axes({0, 1, 2}, {0, 1}, hpa),
                     {geopotential(hpa), constant("t", "K", "air_temperature", 260.0),
                      constant("q", "kg kg**-1", "specific_humidity", 1e-3),
                      {"cc", kDims, {{"units", "(0 - 1)"}}, {}, [](const Idx& i) { return i[1] == 2 ? 0.5 : 0.0; }},
                      {"clwc", kDims, {{"units", "kg kg**-1"}}, {}, [](const Idx& i) {
                         return i[1] == 2 ? 2e-4 : i[1] == 1 ? (i[3] == 0 && i[2] == 0 ? 1e-5 : 4.7e-8) : 0.0;
                       }}});
  importers::ImportOptions o;
  o.dz_m = 50.0;
  auto v = importers::import_file(p, o);
  const auto& s = v.step(0);
  const auto& g = v.grid;
  const double z850 = level_alt(850), z700 = level_alt(700);
  const double mean700 = liquid_sigma(70000.0 / (287.05 * 260.0 * (1.0 + 0.608 * 1e-3)), 2e-4);
  int checked = 0;
  for (int y = 0; y < g.lat_deg.count; ++y) {
    for (int x = 0; x < g.lon_deg.count; ++x) {
      for (int k = 0; k < g.alt_m.count; ++k) {
        const double alt = g.alt_m.at(k);
        if (alt < z850 || alt > z700) continue;
        const std::size_t n = g.index(x, y, k);
        const double product = double(s[core::Field::CloudFraction][n]) * s[core::Field::ExtinctionLiquid][n];
        const double a = (alt - z850) / (z700 - z850);
        EXPECT_NEAR(product, a * mean700, 1e-6 * mean700) << x << " " << y << " " << alt;
        // And no in-cloud value exceeds the cloudy box's own.
        EXPECT_LE(s[core::Field::ExtinctionLiquid][n], mean700 / 0.5 * (1.0 + 1e-6));
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 6 * 20);
  // The boxes are counted and reported, not filled with invented cloud: 6 columns at 850 hPa, one
  // of them above 1e-7 kg/kg.
  EXPECT_TRUE(any_contains(v.report.warnings, "6 boxes with water (up to 1e-05 kg/kg; 1 above 1e-07 kg/kg) but a cloud fraction below 0.0001"))
      << v.report.to_text();
  EXPECT_TRUE(any_contains(v.report.warnings, "left out")) << v.report.to_text();
}

// 5. The regular altitude axis reaches the highest level: the automatic spacing is fitted to end
// on it, a given spacing gets one more node.
TEST_F(CfImportFixes, AltitudeAxisCoversTheHighestLevel) {
  const std::vector<double> z = {0.0, 1000.0, 2300.0, 3700.0};  // median layer 1300 m: dz 650 does not divide 3700
  const std::string p = path("top.nc");
  const std::vector<std::string> d = {"time", "altitude", "latitude", "longitude"};
  cv::test::write_cf(p,
                     {{"time", {0.0}, {{"units", "hours since 2024-01-15 00:00:00"}}},
                      {"altitude", z, {{"units", "m"}, {"standard_name", "altitude"}, {"positive", "up"}}},
                      {"latitude", {0, 1}, {{"units", "degrees_north"}}},
                      {"longitude", {0, 1}, {{"units", "degrees_east"}}}},
                     {{"t", d, {{"units", "K"}}, {}, [](const Idx&) { return 250.0; }},
                      {"ciwc", d, {{"units", "kg kg**-1"}}, {}, [](const Idx& i) { return i[1] == 3 ? 1e-5 : 0.0; }}});
  auto v = importers::import_file(p);
  EXPECT_NEAR(v.grid.alt_m.last(), 3700.0, 1e-6);
  EXPECT_LE(v.grid.alt_m.step, 650.0);
  // The top level's ice is in the volume, at its own value (pressure from the standard atmosphere).
  const double p_pa = 101325.0 * std::pow(1.0 - 0.0065 * 3700.0 / 288.15, kG0 / (287.05 * 0.0065));
  const double want = ice_sigma(p_pa / (287.05 * 250.0), 1e-5, 250.0);
  const auto& ice = v.step(0)[core::Field::ExtinctionIce];
  EXPECT_NEAR(ice[v.grid.index(1, 1, v.grid.alt_m.count - 1)], want, 1e-6 * want);
  importers::ImportOptions o;
  o.dz_m = 500.0;
  auto w = importers::import_file(p, o);
  EXPECT_DOUBLE_EQ(w.grid.alt_m.step, 500.0);
  EXPECT_GE(w.grid.alt_m.last(), 3700.0);
}

// The automatic axis takes the median level thickness only through its number of intervals; the
// heights are read a second time for the exact median only where the median's 1 cm bin leaves that
// number undecided. Each way the axis is the one the exact median gives (computed here from the
// heights written). Three files: levels evenly 700 m apart (the span is 8 half-medians exactly:
// the bin straddles the boundary, a second pass); levels 700.004 m apart with one column's top
// 4 mm higher (the bin's middle would give 8 intervals, the exact median 9: a second pass, and a
// wrong axis without it); uneven levels (no second pass).
TEST_F(CfImportFixes, AltitudeAxisFromTheMedianThicknessWithOrWithoutASecondPass) {
  constexpr double kR = 6371000.0;
  for (const int kind : {0, 1, 2}) {
    const char* names[] = {"even", "near a boundary", "uneven"};
    SCOPED_TRACE(names[kind]);
    const std::string p = path("median" + std::to_string(kind) + ".nc");
    const std::vector<std::string> d = {"time", "level", "latitude", "longitude"};
    // Geometric heights per level and column, bottom up; geopotential written from them.
    auto height = [kind](int k, int y, int x) {
      if (kind == 0) return 120.0 + 700.0 * k;
      if (kind == 1) return 120.0 + 700.004 * k + (k == 4 && x == 0 && y == 0 ? 0.004 : 0.0);
      return 120.0 + 7.0 * x + 3.0 * y + 700.0 * k + 37.3 * ((k * 5 + x * 3 + y) % 7) + 0.11 * k * k;
    };
    cv::test::write_cf(p,
                       {{"time", {0.0}, {{"units", "hours since 2024-01-15 00:00:00"}}},
                        {"level", {1000, 900, 800, 700, 600}, {{"units", "hPa"}, {"positive", "down"}}},
                        {"latitude", {0, 1}, {{"units", "degrees_north"}}},
                        {"longitude", {0, 1, 2}, {{"units", "degrees_east"}}}},
                       {{"t", d, {{"units", "K"}}, {}, [](const Idx&) { return 260.0; }},
                        {"z", d, {{"units", "m**2 s**-2"}, {"standard_name", "geopotential"}}, {},
                         [&](const Idx& i) {
                           const double h = height(i[1], i[2], i[3]);
                           return kG0 * h * kR / (kR + h);
                         }},
                        {"ciwc", d, {{"units", "kg kg**-1"}}, {}, [](const Idx& i) { return i[1] == 2 ? 1e-5 : 0.0; }}});
    // The exact median from the heights as the importer converts them (z R / (g0 R - z)).
    std::vector<double> thick;
    double zmin = 1e30, zmax = -1e30;
    for (int y = 0; y < 2; ++y) {
      for (int x = 0; x < 3; ++x) {
        double prev = NAN;
        for (int k = 0; k < 5; ++k) {
          const double h = height(k, y, x), phi = kG0 * h * kR / (kR + h);
          const double zz = phi * kR / (kG0 * kR - phi);
          zmin = std::min(zmin, zz), zmax = std::max(zmax, zz);
          if (k) thick.push_back(zz - prev);
          prev = zz;
        }
      }
    }
    std::nth_element(thick.begin(), thick.begin() + static_cast<std::ptrdiff_t>(thick.size() / 2), thick.end());
    const double median = thick[thick.size() / 2];
    const core::RegularAxis want = importers::altitude_axis(std::max(zmin, -500.0), zmax, std::clamp(median / 2.0, 50.0, 500.0), true);
    if (kind == 1) {  // the case is what it claims: the bin's middle would give another axis
      const core::RegularAxis middle = importers::altitude_axis(std::max(zmin, -500.0), zmax, 700.005 / 2.0, true);
      ASSERT_EQ(want.count, 10);
      ASSERT_EQ(middle.count, 9);
    }
    importers::ImportOptions o;
    o.keep_cloudless_levels = true;  // every level in the probe, as counted above
    const std::size_t passes = importers::exact_median_passes();
    auto v = importers::import_file(p, o);
    EXPECT_EQ(importers::exact_median_passes() - passes, kind == 2 ? 0u : 1u);
    EXPECT_EQ(v.grid.alt_m.count, want.count);
    EXPECT_NEAR(v.grid.alt_m.start, want.start, 1e-6);  // the heights' conversion may round otherwise
    EXPECT_NEAR(v.grid.alt_m.step, want.step, 1e-9 * want.step);
  }
}

// 6. Low/mid/high cover by height above the ground where the file gives terrain: cloud 300 m
// above a 4.5 km plateau is low; the same altitude over the sea is mid. It survives a .cvvol.
TEST_F(CfImportFixes, CoverClassesAreMeasuredAboveTheGround) {
  const std::vector<double> z = {4600.0, 4800.0, 5200.0, 7000.0};
  const std::string p = path("plateau.nc");
  const std::vector<std::string> d = {"time", "altitude", "latitude", "longitude"};
  cv::test::write_cf(p,
                     {{"time", {0.0}, {{"units", "hours since 2024-01-15 00:00:00"}}},
                      {"altitude", z, {{"units", "m"}, {"standard_name", "altitude"}, {"positive", "up"}}},
                      {"latitude", {30, 31}, {{"units", "degrees_north"}}},
                      {"longitude", {90, 91}, {{"units", "degrees_east"}}}},
                     {{"t", d, {{"units", "K"}}, {}, [](const Idx&) { return 260.0; }},
                      {"cc", d, {{"units", "1"}}, {}, [](const Idx& i) { return i[1] == 1 ? 0.6 : 0.0; }},
                      {"clwc", d, {{"units", "kg kg**-1"}}, {}, [](const Idx& i) { return i[1] == 1 ? 1e-4 : 0.0; }},
                      {"orog", {"latitude", "longitude"}, {{"units", "m"}, {"standard_name", "surface_altitude"}}, {},
                       [](const Idx& i) { return i[1] == 0 ? 4500.0 : 0.0; }}});
  importers::ImportOptions o;
  o.dz_m = 200.0;  // a node on 4800 m
  auto v = importers::import_file(p, o);
  ASSERT_TRUE(v.has_ground);
  const auto& m = v.step(0).maps;
  const std::size_t plateau = v.grid.column(0, 0), sea = v.grid.column(1, 0);
  EXPECT_NEAR(m.low_cover[plateau], 0.6, 1e-5);
  EXPECT_NEAR(m.mid_cover[plateau], 0.0, 1e-7);
  EXPECT_NEAR(m.low_cover[sea], 0.0, 1e-7);
  EXPECT_NEAR(m.mid_cover[sea], 0.6, 1e-5);
  EXPECT_TRUE(any_contains(v.report.notes, "by height above the ground ('orog')"));
  const std::string out = path("plateau.cvvol");
  core::write_cvvol(out, v, nullptr);
  auto r = core::read_cvvol(out);
  ASSERT_TRUE(r.has_ground);
  EXPECT_NEAR(r.step(0).maps.low_cover[plateau], 0.6, 1e-5);
  EXPECT_NEAR(r.step(0).maps.mid_cover[sea], 0.6, 1e-5);
}

// Speed and size: levels above the highest cloud of any step imported are left out (one
// cloud-free level stays above it), and the report says so; --all-levels keeps them.
TEST_F(CfImportFixes, LevelsAboveTheHighestCloudAreLeftOut) {
  const std::vector<double> hpa = {1000, 850, 700, 500, 300, 200, 100};
  auto axes = era5_axes({0, 10}, {0, 10}, hpa);
  axes[0].values = {0.0, 6.0};
  const std::string p = path("tops.nc");
  // Cloud at 850 hPa in the first step and at 500 hPa in the second; packing-noise water above.
  cv::test::write_cf(p, axes,
                     {geopotential(hpa), constant("t", "K", "air_temperature", 250.0),
                      {"cc", kDims, {{"units", "1"}}, {}, [](const Idx& i) { return i[1] == (i[0] == 0 ? 1 : 3) ? 0.5 : 0.0; }},
                      {"clwc", kDims, {{"units", "kg kg**-1"}}, {}, [](const Idx& i) {
                         return i[1] == (i[0] == 0 ? 1 : 3) ? 1e-4 : 3e-11;
                       }}});
  auto v = importers::import_file(p);
  EXPECT_NEAR(v.grid.alt_m.last(), level_alt(300), 1e-6);  // 500 hPa holds cloud; 300 hPa is the margin
  EXPECT_TRUE(any_contains(v.report.notes, "2 level(s) from 200 hPa (reference pressure) up hold no cloud")) << v.report.to_text();
  importers::ImportOptions o;
  o.keep_cloudless_levels = true;
  auto w = importers::import_file(p, o);
  EXPECT_NEAR(w.grid.alt_m.last(), level_alt(100), 1e-6);
  // Only the second step has the 500 hPa cloud: importing the first alone stops above 850 hPa.
  o.keep_cloudless_levels = false;
  o.time_last = 0;
  auto f = importers::import_file(p, o);
  EXPECT_NEAR(f.grid.alt_m.last(), level_alt(700), 1e-6);
}

// Messages: several vertical axes used by different variables; the real reason is named.
TEST_F(CfImportFixes, SeveralVerticalAxesNameTheRealReason) {
  const std::vector<std::string> iso = {"time", "isobaric3", "lat", "lon"}, hag = {"time", "height_above_ground1", "lat", "lon"};
  std::vector<CfAxis> axes = {{"time", {0.0}, {{"units", "hours since 2024-01-15 00:00:00"}}},
                              {"isobaric3", {100000, 70000}, {{"units", "Pa"}}},
                              {"height_above_ground1", {2.0}, {{"units", "m"}, {"positive", "up"}}},
                              {"lat", {0, 10}, {{"units", "degrees_north"}}},
                              {"lon", {0, 10}, {{"units", "degrees_east"}}}};
  auto gh = [](const Idx& i) { return cv::test::isa_height_m(i[1] == 0 ? 100000.0 : 70000.0); };
  const std::string a = path("no_cloud.nc");
  cv::test::write_cf(a, axes,
                     {{"Geopotential_height_isobaric", iso, {{"units", "gpm"}}, {}, gh},
                      {"Temperature_isobaric", iso, {{"units", "K"}}, {}, [](const Idx&) { return 260.0; }},
                      {"Temperature_height_above_ground", hag, {{"units", "K"}}, {}, [](const Idx&) { return 280.0; }}});
  const std::string why = expect_import_error(a);
  EXPECT_NE(why.find("no cloud variable"), std::string::npos) << why;
  EXPECT_EQ(why.find("same axis"), std::string::npos) << why;
  // With a cloud on the pressure levels, the import works; the 2 m temperature is not used.
  const std::string b = path("cloud.nc");
  cv::test::write_cf(b, axes,
                     {{"Temperature_height_above_ground", hag, {{"units", "K"}}, {}, [](const Idx&) { return 280.0; }},
                      {"Geopotential_height_isobaric", iso, {{"units", "gpm"}}, {}, gh},
                      {"Cloud_mixing_ratio_isobaric", iso, {{"units", "kg/kg"}}, {}, [](const Idx& i) { return i[1] == 1 ? 1e-4 : 0.0; }}});
  auto v = importers::import_file(b);
  EXPECT_NEAR(v.grid.alt_m.start, level_alt(1000), 1e-6);
  EXPECT_TRUE(v.has_field[static_cast<int>(core::Field::ExtinctionLiquid)]);
  EXPECT_EQ(v.report.use("temperature").variable, "");  // the standard atmosphere's, not the 2 m one
}

// Messages: a WRF GEOGRID static file is named as such, with what it holds.
TEST_F(CfImportFixes, GeogridFileSaysItHoldsTerrain) {
  const std::string p = path("geo_em.d01.nc");
  {
    cv::test::NcBuilder b(p);
    const int dt = b.dim("Time", 1), dy = b.dim("south_north", 3), dx = b.dim("west_east", 3);
    b.number(NC_GLOBAL, "MAP_PROJ", NC_INT, {1});
    b.text(NC_GLOBAL, "TITLE", "OUTPUT FROM GEOGRID V4.0");
    b.var("XLAT_M", NC_FLOAT, {dt, dy, dx});
    b.var("XLONG_M", NC_FLOAT, {dt, dy, dx});
    b.var("HGT_M", NC_FLOAT, {dt, dy, dx});
    b.close();
  }
  const std::string why = expect_import_error(p);
  EXPECT_NE(why.find("WRF GEOGRID static file"), std::string::npos) << why;
  EXPECT_NE(why.find("terrain"), std::string::npos) << why;
  EXPECT_NE(why.find("no cloud"), std::string::npos) << why;
  EXPECT_NE(importers::describe_file(p).find("importable: no: " + why), std::string::npos);
}

// Messages: CF's other spellings of the latitude and longitude units are units, not "no units".
TEST_F(CfImportFixes, UnitsWithSpacesAreRead) {
  const std::vector<double> hpa = {1000, 700};
  auto axes = era5_axes({0, 10}, {0, 10}, hpa);
  axes[2].atts = {{"units", "degrees north"}};
  axes[3].atts = {{"units", "Degrees_East"}};
  const std::string p = path("spaces.nc");
  cv::test::write_cf(p, axes, {geopotential(hpa), {"cc", kDims, {{"units", "1"}}, {}, [](const Idx&) { return 0.5; }}});
  const std::string info = importers::describe_file(p);
  EXPECT_EQ(info.find("no units attribute"), std::string::npos) << info;
  EXPECT_NE(info.find("latitude: 'latitude', 2 values from 0 to 10, recognised by attributes (units 'degrees north')"), std::string::npos)
      << info;
}

// Messages: the report gives the stored values' own units (extinction in 1/m, not kg/kg).
TEST_F(CfImportFixes, ReportNamesTheStoredUnits) {
  const std::vector<double> hpa = {1000, 700};
  const std::string p = path("units.nc");
  cv::test::write_cf(p, era5_axes({0, 10}, {0, 10}, hpa),
                     {geopotential(hpa), {"clwc", kDims, {{"units", "kg kg**-1"}}, {}, [](const Idx& i) { return i[1] == 1 ? 1e-4 : 0.0; }}});
  auto v = importers::import_file(p);
  v.step(0);
  const auto& use = v.report.use("cloud liquid water");
  EXPECT_EQ(use.units, "kg kg**-1");
  EXPECT_EQ(use.after_units, "1/m");
  const std::string text = v.report.to_text();
  EXPECT_NE(text.find("kg kg**-1 (0 missing), stored 0 .. "), std::string::npos) << text;
  EXPECT_NE(text.find(" 1/m"), std::string::npos) << text;
  EXPECT_NE(v.report.to_json().find("\"after_units\": \"1/m\""), std::string::npos);
}

// Diagnosed cloud: Sundqvist's fraction against its formula, and the condensate estimate against
// saturation by hand (IFS's Tetens forms), only when asked.
double qsat_by_hand(double p, double t) {
  const double ew = 611.21 * std::exp(17.502 * (t - 273.16) / (t - 32.19));
  const double ei = 611.21 * std::exp(22.587 * (t - 273.16) / (t + 0.7));
  const double a = t >= 273.16 ? 1.0 : t <= 250.16 ? 0.0 : std::pow((t - 250.16) / 23.0, 2);
  const double e = a * ew + (1 - a) * ei;
  return 0.621981 * e / (p - (1 - 0.621981) * e);
}

TEST(CfImportDiagnosed, SundqvistFractionIsItsFormula) {
  EXPECT_EQ(importers::sundqvist_fraction(0.5, 0.8), 0.0);
  EXPECT_EQ(importers::sundqvist_fraction(0.8, 0.8), 0.0);
  EXPECT_NEAR(importers::sundqvist_fraction(0.9, 0.8), 1.0 - std::sqrt(0.5), 1e-15);
  EXPECT_NEAR(importers::sundqvist_fraction(0.95, 0.75), 1.0 - std::sqrt(0.05 / 0.25), 1e-15);
  EXPECT_EQ(importers::sundqvist_fraction(1.0, 0.8), 1.0);
  EXPECT_EQ(importers::sundqvist_fraction(1.3, 0.8), 1.0);  // supersaturated over ice
  for (double t : {240.0, 255.0, 268.0, 280.0}) {
    EXPECT_NEAR(importers::saturation_specific_humidity(70000.0, t), qsat_by_hand(70000.0, t), 1e-12 * qsat_by_hand(70000.0, t));
  }
}

TEST_F(CfImportFixes, DiagnosedCloudFromRelativeHumidity) {
  const std::vector<double> hpa = {1000, 850, 700, 500};
  const double temps[] = {288.0, 278.0, 268.0, 250.0};
  const std::string p = path("rh.nc");
  cv::test::write_cf(p, era5_axes({0, 10, 20}, {0, 10}, hpa),
                     {geopotential(hpa),
                      {"t", kDims, {{"units", "K"}, {"standard_name", "air_temperature"}}, {},
                       [temps](const Idx& i) { return temps[i[1]]; }},
                      {"r", kDims, {{"units", "%"}, {"standard_name", "relative_humidity"}}, {}, [](const Idx& i) {
                         const double rh[] = {50.0, 90.0 + 2.0 * i[3], 85.0, 120.0};
                         return rh[i[1]];
                       }}});
  const std::string why = expect_import_error(p);
  EXPECT_NE(why.find("--diagnose-cloud"), std::string::npos) << why;
  importers::ImportOptions o;
  o.diagnose_cloud = true;
  for (int level : {1, 2}) {
    o.dz_m = level_alt(hpa[static_cast<std::size_t>(level)]) - level_alt(1000);  // node 1 on the level
    auto v = importers::import_file(p, o);
    const auto& s = v.step(0);
    const double t = temps[level], pa = hpa[static_cast<std::size_t>(level)] * 100.0, rho = pa / (287.05 * t);
    const double liquid_share = t >= 273.16 ? 1.0 : std::pow((t - 250.16) / 23.0, 2);
    const double in_cloud = 0.05 * qsat_by_hand(pa, t);
    for (int x = 0; x < 3; ++x) {
      const double rh = level == 1 ? (90.0 + 2.0 * x) / 100.0 : 0.85;
      const std::size_t n = v.grid.index(x, 0, 1);
      EXPECT_NEAR(s[core::Field::CloudFraction][n], 1.0 - std::sqrt((1.0 - rh) / 0.2), 1e-6) << level << " " << x;
      const double liq = liquid_sigma(rho, in_cloud * liquid_share), ice = ice_sigma(rho, in_cloud * (1.0 - liquid_share), t);
      EXPECT_NEAR(s[core::Field::ExtinctionLiquid][n], liq, 1e-5 * liq) << level << " " << x;
      EXPECT_NEAR(s[core::Field::ExtinctionIce][n], ice, 1e-5 * ice + 1e-12) << level << " " << x;
    }
    EXPECT_TRUE(any_contains(v.report.warnings, "DIAGNOSED CLOUD")) << v.report.to_text();
    EXPECT_TRUE(any_contains(v.report.warnings, "Sundqvist et al. (1989)"));
    EXPECT_TRUE(any_contains(v.report.warnings, "RH from 'r'"));
  }
}

}  // namespace

namespace {

// Half floats: exact on representable values, round to nearest even, NaN and infinity kept, and a
// volume written as float16 reads back within the error bound the format states.
TEST(VolumeIo, Float16ConversionsAndTheirBound) {
  using core::float_to_half;
  using core::half_to_float;
  for (float x : {0.0f, 1.0f, -2.0f, 0.5f, 65504.0f, 6.103515625e-05f /* 2^-14 */, 5.9604645e-08f /* 2^-24 */, 1024.5f - 0.5f}) {
    EXPECT_EQ(half_to_float(float_to_half(x)), x) << x;
  }
  EXPECT_EQ(float_to_half(1.0f + 1.0f / 2048.0f), float_to_half(1.0f));              // a tie rounds to even
  EXPECT_EQ(half_to_float(float_to_half(1.0f + 3.0f / 2048.0f)), 1.0f + 2.0f / 1024.0f);  // a tie rounds to even, up
  EXPECT_TRUE(std::isnan(half_to_float(float_to_half(std::nanf("")))));
  EXPECT_TRUE(std::isinf(half_to_float(float_to_half(1e6f))));
  EXPECT_EQ(half_to_float(float_to_half(1e-9f)), 0.0f);
  // Every value over six decades: relative error <= 2^-11 where normal, absolute <= 2^-25 below.
  for (int i = 0; i <= 6000; ++i) {
    const float x = static_cast<float>(1e-8 * std::pow(10.0, i / 1000.0));
    const float y = half_to_float(float_to_half(x));
    if (x >= 6.103515625e-05f) EXPECT_LE(std::abs(y - x), x / 2048.0f * (1.0f + 1e-6f)) << x;
    else EXPECT_LE(std::abs(y - x), 2.9802322e-08f * (1.0f + 1e-6f)) << x;
  }
}

// The writer's array conversion (F16C eight at a time where the processor has it) equals
// float_to_half bit for bit: over a sweep of every 2^12-th float bit pattern (both signs, NaNs with
// payloads, infinities, subnormals, the overflow edge) and the ties around 1, at a scale, and at a
// length that leaves a remainder for the scalar tail.
TEST(VolumeIo, ArrayHalfConversionEqualsTheScalarOne) {
  std::vector<float> in;
  for (std::uint64_t bits = 0; bits < (std::uint64_t(1) << 32); bits += 4096 + 1) {
    const auto b = static_cast<std::uint32_t>(bits);
    float x;
    std::memcpy(&x, &b, sizeof x);
    in.push_back(x);
  }
  for (float x : {65504.0f, 65519.99f, 65520.0f, 1.0f + 1.0f / 2048.0f, 1.0f + 3.0f / 2048.0f, 2.9802322e-08f,
                  8.940697e-08f, -0.0f, std::nanf("")}) {
    in.push_back(x);
  }
  for (float scale : {1.0f, 1000.0f, 0.01f}) {
    std::vector<std::uint16_t> out(in.size());
    core::floats_to_halves(in.data(), scale, out.data(), in.size());
    std::size_t differ = 0;
    for (std::size_t i = 0; i < in.size(); ++i) {
      if (out[i] != core::float_to_half(in[i] * scale)) ++differ;
    }
    EXPECT_EQ(differ, 0u) << "scale " << scale << " over " << in.size() << " values";
  }
}

// The widening of half floats (read_cvvol, derive_maps of a step held as halves) is the scalar
// half_to_float times the scale, bit for bit, over every half: with F16C and without.
TEST(VolumeIo, ArrayHalfWideningEqualsTheScalarOne) {
  std::vector<std::uint16_t> in(65536 + 5);
  for (std::size_t i = 0; i < in.size(); ++i) in[i] = static_cast<std::uint16_t>(i);  // the last 5 again, past a multiple of 8
  for (float scale : {1.0f, 0.001f, 100.0f}) {
    std::vector<float> out(in.size());
    core::halves_to_floats(in.data(), scale, out.data(), in.size());
    std::size_t differ = 0;
    for (std::size_t i = 0; i < in.size(); ++i) {
      const float want = core::half_to_float(in[i]) * scale;
      if (std::isnan(want) ? !std::isnan(out[i]) : std::memcmp(&want, &out[i], sizeof want) != 0) ++differ;
    }
    EXPECT_EQ(differ, 0u) << "scale " << scale;
  }
}

// A step held as half floats (the import's, on its way to a float16 .cvvol) is written as the same
// step held as floats would be, and widened when float32 is asked for.
TEST(VolumeIo, AStepHeldAsHalvesIsWrittenAsItsFloatsWouldBe) {
  const auto dir = cv::test::temp_dir("cvvol_halves");
  core::CloudVolume v;
  v.grid.lon_deg = {0, 1, 5};
  v.grid.lat_deg = {0, 1, 3};
  v.grid.alt_m = {0, 500, 4};
  v.times = {{0, "2024-01-01T00:00:00Z"}};
  const std::vector<int> present = {0, 2, 5, 6, 7};
  for (int f : present) v.has_field[static_cast<std::size_t>(f)] = true;
  const std::size_t n = v.grid.points();
  core::TimeStepData floats, halves;
  for (int f : present) {
    auto& a = floats.fields[static_cast<std::size_t>(f)];
    a.resize(n);
    for (std::size_t p = 0; p < n; ++p) {
      const double x = static_cast<double>(p) + 1.0;
      a[p] = f == 0 ? static_cast<float>(1e-6 * x * x) : f == 2 ? static_cast<float>(x / static_cast<double>(n))
                                                     : f == 7 ? static_cast<float>(1e5 - 900.0 * x) : static_cast<float>(200.0 + 1.3 * x);
    }
    if (f == 0) a[7] = std::numeric_limits<float>::quiet_NaN();
    // Held as halves: the floats through the float16 encoding's scale, then the floats the reader
    // would widen them to, so both steps stand for the same volume.
    const float k = core::half_field_scale(static_cast<core::Field>(f));
    auto& h = halves.halves[static_cast<std::size_t>(f)];
    h.resize(n);
    core::floats_to_halves(a.data(), k, h.data(), n);
    core::halves_to_floats(h.data(), 1.0f / k, a.data(), n);
  }
  core::derive_maps(v.grid, floats);
  core::derive_maps(v.grid, halves);
  ASSERT_EQ(halves.maps.optical_depth.size(), v.grid.columns());
  for (std::size_t c = 0; c < v.grid.columns(); ++c) {
    EXPECT_EQ(halves.maps.optical_depth[c], floats.maps.optical_depth[c]) << c;
    EXPECT_EQ(halves.maps.cloud_cover[c], floats.maps.cloud_cover[c]) << c;
  }
  EXPECT_EQ(halves.bytes(), floats.bytes() - n * present.size() * 2);
  for (const auto encoding : {core::CvvolEncoding::Float16, core::CvvolEncoding::Float32}) {
    const bool f16 = encoding == core::CvvolEncoding::Float16;
    std::string bytes[2];
    for (int held = 0; held < 2; ++held) {
      core::CloudVolume w = v;
      w.put(0, held ? halves : floats);
      const std::string path = (dir / (std::string(held ? "h" : "f") + (f16 ? "16" : "32") + ".cvvol")).string();
      core::write_cvvol(path, w, nullptr, encoding);
      std::ifstream in(path, std::ios::binary);
      bytes[held].assign(std::istreambuf_iterator<char>(in), {});
    }
    EXPECT_GT(bytes[0].size(), n * 2 * present.size());
    EXPECT_TRUE(bytes[0] == bytes[1]) << (f16 ? "float16" : "float32") << ": " << bytes[0].size() << " and " << bytes[1].size() << " bytes";
  }
  std::filesystem::remove_all(dir);
}

TEST(VolumeIo, Float16VolumeReadsBackWithinItsStatedBound) {
  const auto dir = cv::test::temp_dir("cvvol_half");
  core::CloudVolume v;
  v.grid.lon_deg = {0, 1, 4};
  v.grid.lat_deg = {0, 1, 3};
  v.grid.alt_m = {0, 500, 5};
  v.times = {{0, "2024-01-01T00:00:00Z"}};
  for (int f : {0, 1, 2, 6}) v.has_field[static_cast<std::size_t>(f)] = true;
  core::TimeStepData d;
  const std::size_t n = v.grid.points();
  for (int f : {0, 1, 2, 6}) d.fields[static_cast<std::size_t>(f)].resize(n);
  for (std::size_t p = 0; p < n; ++p) {
    d[core::Field::ExtinctionLiquid][p] = static_cast<float>(1e-7 * std::pow(1.7, static_cast<double>(p % 25)));  // 1e-7 .. 0.03 /m
    d[core::Field::ExtinctionIce][p] = p == 3 ? std::numeric_limits<float>::quiet_NaN() : static_cast<float>(3e-11 * p);
    d[core::Field::CloudFraction][p] = static_cast<float>(p) / static_cast<float>(n);
    d[core::Field::Temperature][p] = 200.0f + 0.37f * static_cast<float>(p);
  }
  core::derive_maps(v.grid, d);
  v.put(0, d);
  const std::string path = (dir / "half.cvvol").string();
  core::write_cvvol(path, v, nullptr, core::CvvolEncoding::Float16);
  auto r = core::read_cvvol(path);
  const auto& s = r.step(0);
  for (std::size_t p = 0; p < n; ++p) {
    const float e = d[core::Field::ExtinctionLiquid][p];
    EXPECT_LE(std::abs(s[core::Field::ExtinctionLiquid][p] - e), e / 2048.0f * 1.0001f) << p;
    if (p == 3) EXPECT_TRUE(std::isnan(s[core::Field::ExtinctionIce][p]));
    else EXPECT_LE(std::abs(s[core::Field::ExtinctionIce][p] - d[core::Field::ExtinctionIce][p]), 3e-11f) << p;
    EXPECT_LE(std::abs(s[core::Field::CloudFraction][p] - d[core::Field::CloudFraction][p]), 2.45e-4f) << p;
    EXPECT_LE(std::abs(s[core::Field::Temperature][p] - d[core::Field::Temperature][p]), 0.125f) << p;
  }
  // Half the bytes of float32 for the fields.
  const std::string full = (dir / "full.cvvol").string();
  core::write_cvvol(full, v, nullptr);
  const double field_bytes = 4.0 * static_cast<double>(n) * 4.0;
  EXPECT_NEAR(static_cast<double>(std::filesystem::file_size(full) - std::filesystem::file_size(path)), field_bytes / 2.0, 200.0);
  std::filesystem::remove_all(dir);
}

}  // namespace

namespace {
// GRIB codes in attributes are whole numbers 0..65535 or name no parameter: a huge code (1e30, or
// a 12-digit Grib_Variable_Id) was converted to int, which is undefined (UBSan) or threw
// std::out_of_range past the importer's errors.
TEST_F(CfImportFixes, HugeGribCodesNameNoParameter) {
  const std::vector<std::string> d = kGfsJavaDims;
  const std::vector<CfAxis> axes = gfs_java_axes();
  auto gh = gfs_java_height;
  const std::string a = path("huge_codes.nc");
  cv::test::write_cf(a, axes,
                     {{"Geopotential_height_isobaric", d, {{"units", "gpm"}}, {}, gh},
                      {"Temperature_isobaric", d, {{"units", "K"}}, {{"Grib2_Parameter", {0, 0, 0}}}, [](const Idx&) { return 250.0; }},
                      {"u-component_of_wind_isobaric", d, {{"units", "m/s"}, {"Grib_Variable_Id", "VAR_999999999999-2-2_L100"}}, {},
                       [](const Idx&) { return 7.0; }},
                      {"Ice_water_mixing_ratio_isobaric", d, {{"units", "kg/kg"}}, {{"Grib2_Parameter", {0, 1, 23}}},
                       [](const Idx& i) { return i[1] == 1 ? 1e-5 : 0.0; }}});
  {  // a code past any int, as a double attribute
    int id = -1, var = -1;
    cv::test::nc_check(nc_open(a.c_str(), NC_WRITE, &id), "open");
    cv::test::nc_check(nc_inq_varid(id, "Geopotential_height_isobaric", &var), "varid");
    cv::test::nc_check(nc_redef(id), "redef");
    const double codes[3] = {1e30, 3, 5};
    cv::test::nc_check(nc_put_att_double(id, var, "Grib2_Parameter", NC_DOUBLE, 3, codes), "att");
    cv::test::nc_check(nc_close(id), "close");
  }
  importers::ImportOptions o;
  o.dz_m = level_alt(700) - level_alt(1000);
  auto v = importers::import_file(a, o);
  v.step(0);  // the report names the variables a step read
  EXPECT_TRUE(v.has_field[static_cast<int>(core::Field::ExtinctionIce)]);
  EXPECT_EQ(v.report.use("temperature").variable, "Temperature_isobaric");
  EXPECT_EQ(v.report.use("eastward wind").variable, "u-component_of_wind_isobaric");  // by its name
  EXPECT_NE(importers::describe_file(a).find("importable: yes"), std::string::npos);
}
}  // namespace

// Snow (ECMWF `cswc`) joins the ice: where both are given they add, where the ice is missing the
// snow stands alone, and where the snow is missing the ice is kept; a small negative snow value
// from packing is set to zero and counted like the other waters'.
namespace {
TEST(CfSnow, SnowJoinsTheIceAndItsSmallNegativesAreCounted) {
  const auto dir = cv::test::temp_dir("cf_snow");
  const std::vector<double> hpa = {1000, 700, 500};
  const std::string p = (dir / "snow.nc").string();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double ice[] = {1e-4, nan, 0.0, 1e-4}, snow[] = {5e-5, 5e-5, -2e-6, nan};
  auto at_cloud = [](const Idx& i, double v) { return i[1] == 1 ? v : 0.0; };
  cv::test::write_cf(p, era5_axes({0, 10, 20, 30}, {-10, 0, 10}, hpa),
                     {geopotential(hpa), constant("t", "K", "air_temperature", 260.0),
                      {"cc", kDims, {{"units", "(0 - 1)"}}, {}, [&](const Idx& i) { return at_cloud(i, 0.5); }},
                      {"ciwc", kDims, {{"units", "kg kg**-1"}}, {}, [&](const Idx& i) { return at_cloud(i, ice[i[3]]); }},
                      {"cswc", kDims, {{"units", "kg kg**-1"}}, {}, [&](const Idx& i) { return at_cloud(i, snow[i[3]]); }}});
  importers::ImportOptions o;
  o.dz_m = level_alt(700) - level_alt(1000);  // a node on the 700 hPa level
  auto v = importers::import_file(p, o);
  ASSERT_NEAR(v.grid.alt_m.at(1), level_alt(700), 0.5);
  const double rho = 70000.0 / (287.05 * 260.0);
  const double want[] = {ice_sigma(rho, 1.5e-4 / 0.5, 260.0), ice_sigma(rho, 5e-5 / 0.5, 260.0), 0.0,
                         ice_sigma(rho, 1e-4 / 0.5, 260.0)};
  const auto& ext = v.step(0)[core::Field::ExtinctionIce];
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 3; ++j) {
      EXPECT_NEAR(ext[v.grid.index(i, j, 1)], want[i], 1e-6 * want[0]) << "lon index " << i << " lat index " << j;
    }
  }
  EXPECT_TRUE(any_contains(v.report.warnings, "negative mixing ratios")) << v.report.to_text();
  std::filesystem::remove_all(dir);
}
}  // namespace
