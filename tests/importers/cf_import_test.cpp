// The CF/ERA5 importer against files the tests write, one per trap real files contain, with
// expected values computed by hand from the brief's formulas.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <string>

#include "cf_time.hpp"
#include "importer.hpp"
#include "volume/volume_io.hpp"
#include "support/nc_builder.hpp"

namespace {
using namespace cv;
using cv::test::SynthOptions;

constexpr double kR = 6371000.0;
double geometric(double geopotential_height_m) { return geopotential_height_m * kR / (kR - geopotential_height_m); }
double level_alt(double hpa) { return geometric(cv::test::isa_height_m(hpa * 100.0)); }

// Extinction (1/m) of the synthetic cloud by hand: in-cloud water q / cf, air density from the
// ideal gas law with virtual temperature, sigma = 3 rho q / (2 rho_w r_eff), r_eff 10 um.
double expected_extinction(double p_pa, double cf) {
  const double rho = p_pa / (287.05 * 260.0 * (1.0 + 0.608 * 1e-3));
  return 3.0 * rho * (2e-4 / cf) / (2.0 * 1000.0 * 10e-6);
}

class CfImport : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = cv::test::temp_dir(::testing::UnitTest::GetInstance()->current_test_info()->name()); }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string write(const SynthOptions& o, const std::string& name = "synth.nc") {
    const std::string p = (dir_ / name).string();
    cv::test::write_synth(p, o);
    return p;
  }
  // An import whose altitude grid has a point exactly on the 700 hPa level (index 1).
  core::CloudVolume import(const std::string& path, importers::ImportOptions o = {}) {
    o.dz_m = level_alt(700) - level_alt(1000);
    return importers::import_file(path, o);
  }
  std::filesystem::path dir_;
};

int lon_index(const core::VolumeGrid& g, double lon) {
  for (int i = 0; i < g.lon_deg.count; ++i) {
    if (std::abs(std::fmod(g.lon_deg.at(i) - lon + 720.0, 360.0)) < 1e-6) return i;
  }
  return -1;
}
int lat_index(const core::VolumeGrid& g, double lat) {
  for (int j = 0; j < g.lat_deg.count; ++j) {
    if (std::abs(g.lat_deg.at(j) - lat) < 1e-6) return j;
  }
  return -1;
}

// Two fields hold the same values, NaN (no data, e.g. above a column's top level) where the other
// has NaN too.
::testing::AssertionResult same_field(const std::vector<float>& a, const std::vector<float>& b) {
  if (a.size() != b.size()) return ::testing::AssertionFailure() << "sizes " << a.size() << " and " << b.size();
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (!(a[i] == b[i] || (std::isnan(a[i]) && std::isnan(b[i])))) {
      return ::testing::AssertionFailure() << "at " << i << ": " << a[i] << " and " << b[i];
    }
  }
  return ::testing::AssertionSuccess();
}

// Checks the cloud level of a synthetic import against the hand values.
void expect_synthetic_values(core::CloudVolume& v, double tol_rel) {
  const auto& g = v.grid;
  ASSERT_NEAR(g.alt_m.start, level_alt(1000), 0.5);
  ASSERT_NEAR(g.alt_m.at(1), level_alt(700), 0.5);
  const auto& d = v.step(0);
  for (double lon : {170.0, 180.0, -170.0}) {
    for (double lat : {45.0, 55.0}) {
      const int i = lon_index(g, lon), j = lat_index(g, lat);
      ASSERT_GE(i, 0) << lon;
      ASSERT_GE(j, 0) << lat;
      const std::size_t p = g.index(i, j, 1);
      const double cf = lon == 170.0 ? 0.8 : 0.5;
      EXPECT_NEAR(d[core::Field::CloudFraction][p], cf, 1e-4);
      EXPECT_NEAR(d[core::Field::ExtinctionLiquid][p], expected_extinction(70000.0, cf), tol_rel * expected_extinction(70000.0, cf));
      EXPECT_NEAR(d[core::Field::WindU][p], 10.0 + lat / 10.0, 1e-3);
      EXPECT_NEAR(d[core::Field::WindV][p], cv::test::synth_lon180(lon) / 100.0, 1e-3);
      EXPECT_NEAR(d[core::Field::Temperature][p], 260.0, 1e-2);
      EXPECT_EQ(d[core::Field::ExtinctionLiquid][g.index(i, j, 0)], 0.0f);  // clear at 1000 hPa
    }
  }
}

TEST_F(CfImport, AnalyticValuesUnpackedAndPacked) {
  SynthOptions o;
  o.packed = false;
  auto v = import(write(o));
  EXPECT_EQ(v.liquid_r_eff_um, 10.0);  // the default the extinction was computed with
  EXPECT_EQ(v.grid.lon_deg.count, 6);
  EXPECT_DOUBLE_EQ(v.grid.lon_deg.start, 170.0);
  expect_synthetic_values(v, 1e-6);
  o.packed = true;
  auto w = import(write(o, "packed.nc"));
  expect_synthetic_values(w, 1e-4);
  // The derived maps: one cloudy layer of fraction 0.5 gives a cover of 0.5, base = top = 700 hPa.
  const auto& m = w.step(0).maps;
  const std::size_t c = w.grid.column(lon_index(w.grid, 180.0), 0);
  EXPECT_NEAR(m.cloud_cover[c], 0.5, 1e-4);
  EXPECT_NEAR(m.cloud_base_m[c], level_alt(700), 0.5);
  EXPECT_NEAR(m.cloud_top_m[c], level_alt(700), 0.5);
}

TEST_F(CfImport, DescendingLatitudeIsFlipped) {
  SynthOptions o;
  o.lats = {55, 50, 45, 40};
  auto v = import(write(o));
  EXPECT_DOUBLE_EQ(v.grid.lat_deg.start, 40.0);
  EXPECT_DOUBLE_EQ(v.grid.lat_deg.step, 5.0);
  expect_synthetic_values(v, 1e-4);
  bool noted = false;
  for (const auto& n : v.report.notes) noted |= n.find("north to south") != std::string::npos;
  EXPECT_TRUE(noted);
}

TEST_F(CfImport, LongitudeConventionsGiveTheSameVolume) {
  SynthOptions a;
  SynthOptions b;
  b.lons = {170, 175, 180, -175, -170, -165};  // -180..180 storage, jumping at the date line
  auto va = import(write(a, "a.nc"));
  auto vb = import(write(b, "b.nc"));
  EXPECT_DOUBLE_EQ(va.grid.lon_deg.start, vb.grid.lon_deg.start);
  EXPECT_EQ(va.grid.lon_deg.count, vb.grid.lon_deg.count);
  EXPECT_TRUE(same_field(va.step(0)[core::Field::ExtinctionLiquid], vb.step(0)[core::Field::ExtinctionLiquid]));
  expect_synthetic_values(vb, 1e-4);
}

TEST_F(CfImport, GlobalGridWithDuplicatedWrapColumn) {
  SynthOptions o;
  o.lons.clear();
  for (int k = 0; k <= 12; ++k) o.lons.push_back(30.0 * k);  // 0..360: the last column repeats the first
  auto v = import(write(o));
  EXPECT_EQ(v.grid.lon_deg.count, 12);
  EXPECT_TRUE(v.grid.wraps_lon());
  // A box across the date line on the global grid starts at its western edge.
  importers::ImportOptions r;
  r.region = importers::Region{150.0, -150.0, -90.0, 90.0};
  auto w = import(write(o, "g2.nc"), r);
  EXPECT_DOUBLE_EQ(w.grid.lon_deg.start, 150.0);
  EXPECT_EQ(w.grid.lon_deg.count, 3);  // 150, 180, 210
  // And a box across 0 degrees.
  r.region = importers::Region{-30.0, 30.0, -90.0, 90.0};
  auto z = import(write(o, "g3.nc"), r);
  EXPECT_DOUBLE_EQ(z.grid.lon_deg.start, -30.0);
  EXPECT_EQ(z.grid.lon_deg.count, 3);
}

TEST_F(CfImport, DimensionOrderDoesNotMatter) {
  SynthOptions a;
  SynthOptions b;
  b.lon_first_order = true;  // (longitude, latitude, level, time), as some converters write
  auto va = import(write(a, "a.nc"));
  auto vb = import(write(b, "b.nc"));
  for (auto f : {core::Field::CloudFraction, core::Field::ExtinctionLiquid, core::Field::WindU, core::Field::WindV}) {
    EXPECT_TRUE(same_field(va.step(1)[f], vb.step(1)[f])) << core::field_name(f);
  }
}

TEST_F(CfImport, LevelUnitsAndOrder) {
  SynthOptions ref;
  auto vr = import(write(ref, "ref.nc"));
  struct Case {
    std::string units;
    double scale;
    bool top_first;
  };
  for (const Case& c : {Case{"Pa", 100.0, false}, Case{"mb", 1.0, false}, Case{"millibars", 1.0, true},
                        Case{"hPa", 1.0, true}}) {
    SynthOptions o;
    o.level_units = c.units;
    o.level_scale = c.scale;
    if (c.top_first) o.levels_hpa = {300, 500, 700, 850, 1000};
    auto v = import(write(o, c.units + std::to_string(c.top_first) + ".nc"));
    EXPECT_EQ(v.grid.alt_m.count, vr.grid.alt_m.count) << c.units;
    EXPECT_TRUE(same_field(v.step(0)[core::Field::ExtinctionLiquid], vr.step(0)[core::Field::ExtinctionLiquid])) << c.units;
  }
  SynthOptions bad;
  bad.level_units = "furlongs";
  EXPECT_THROW(import(write(bad, "bad.nc")), importers::ImportError);
}

TEST(CfTime, UnitsSpellingsAndCalendars) {
  using importers::parse_time_units;
  using importers::valid_time;
  EXPECT_EQ(valid_time(parse_time_units("Hour since 2021-01-30T12:00:00Z", "proleptic_gregorian", "t"), 6).iso_utc,
            "2021-01-30T18:00:00Z");
  EXPECT_EQ(valid_time(parse_time_units("hours since 1900-01-01 00:00:00.0", "gregorian", "t"), 1076976).iso_utc,
            "2022-11-11T00:00:00Z");
  EXPECT_EQ(valid_time(parse_time_units("days since 2000-01-01", "", "t"), 59).iso_utc, "2000-02-29T00:00:00Z");
  EXPECT_EQ(valid_time(parse_time_units("days since 2000-01-01", "noleap", "t"), 59).iso_utc, "2000-03-01T00:00:00Z");
  EXPECT_EQ(valid_time(parse_time_units("days since 2000-01-01", "360_day", "t"), 59).iso_utc, "2000-02-30T00:00:00Z");
  EXPECT_EQ(valid_time(parse_time_units("days since 2001-01-01", "all_leap", "t"), 59).iso_utc, "2001-02-29T00:00:00Z");
  EXPECT_EQ(valid_time(parse_time_units("seconds since 1970-01-01T02:00:00+02:00", "", "t"), 0).unix_s, 0);
  EXPECT_EQ(valid_time(parse_time_units("minutes since 2020-03-01", "", "t"), -1).iso_utc, "2020-02-29T23:59:00Z");
  EXPECT_EQ(valid_time(parse_time_units("hours since 1970-01-01", "", "t"), 24).unix_s, 86400);
  bool approx = false;
  const auto d = valid_time(parse_time_units("days since 2000-01-01", "360_day", "t"), 59, &approx);
  EXPECT_TRUE(approx);
  EXPECT_EQ(d.unix_s, importers::days_from_civil(2000, 2, 29) * 86400);  // 30 Feb -> 29 Feb 2000
  for (const auto& [units, cal] : {std::pair{"hours after 2000-01-01", ""}, std::pair{"fortnights since 2000-01-01", ""},
                                   std::pair{"hours since 2000-13-01", ""}, std::pair{"hours since 2000-01-01", "julian"}}) {
    try {
      parse_time_units(units, cal, "f.nc: variable 'time'");
      ADD_FAILURE() << units << " " << cal;
    } catch (const importers::ImportError& e) {
      EXPECT_NE(std::string(e.what()).find("f.nc: variable 'time'"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("expected"), std::string::npos) << e.what();
    }
  }
}

TEST_F(CfImport, TimeUnitsInTheFileAndAMissingTimeVariable) {
  SynthOptions o;
  o.time_units = "Hour since 2021-01-30T12:00:00Z";
  auto v = import(write(o));
  ASSERT_EQ(v.times.size(), 2u);
  EXPECT_EQ(v.times[1].iso_utc, "2021-01-30T15:00:00Z");
  o.time_variable = false;
  auto w = import(write(o, "notime.nc"));
  EXPECT_EQ(w.times.size(), 2u);
  bool noted = false;
  for (const auto& n : w.report.notes) noted |= n.find("no time coordinate") != std::string::npos;
  EXPECT_TRUE(noted);
  expect_synthetic_values(w, 1e-4);
}

TEST_F(CfImport, HyphenatedNamesAreFoundByStandardName) {
  SynthOptions o;
  o.cc_name = "cloud-area-fraction";
  o.cc_standard_name = "cloud_area_fraction_in_atmosphere_layer";
  auto v = import(write(o));
  expect_synthetic_values(v, 1e-4);
  EXPECT_EQ(v.report.use("cloud fraction").variable, "cloud-area-fraction");
}

TEST_F(CfImport, NegativeScaleAndFillDifferentFromMissing) {
  SynthOptions o;
  o.negative_scale = true;
  o.fill_differs_from_missing = true;
  auto v = import(write(o));
  expect_synthetic_values(v, 1e-4);
  // Two cloud-fraction values were fill and missing: both counted as missing, neither turned into a number.
  EXPECT_EQ(v.report.use("cloud fraction").before.missing, 2u);
}

TEST_F(CfImport, TinyNegativeWaterIsClampedAndReported) {
  SynthOptions o;
  o.clwc_noise = 3e-9;
  auto v = import(write(o));
  const auto& ext = v.step(0)[core::Field::ExtinctionLiquid];
  for (float x : ext) {
    if (!std::isnan(x)) {
      ASSERT_GE(x, 0.0f);
    }
  }
  bool warned = false;
  for (const auto& w : v.report.warnings) warned |= w.find("negative mixing ratios") != std::string::npos;
  EXPECT_TRUE(warned);
}

TEST_F(CfImport, NanMissingValueOnAnIntegerVariable) {
  SynthOptions o;
  const std::string p = write(o);
  {
    int id, var;
    cv::test::nc_check(nc_open(p.c_str(), NC_WRITE, &id), "open");
    cv::test::nc_check(nc_inq_varid(id, "cc", &var), "cc");
    nc_redef(id);
    const double nan = NAN;
    cv::test::nc_check(nc_put_att_double(id, var, "missing_value", NC_DOUBLE, 1, &nan), "att");
    nc_close(id);
  }
  auto v = import(p);
  expect_synthetic_values(v, 1e-4);
}

TEST_F(CfImport, RegionAcrossTheDateLineAndStride) {
  SynthOptions o;
  o.lons.clear();
  for (int k = 0; k <= 12; ++k) o.lons.push_back(160.0 + 5.0 * k);  // 160..220 in the 0..360 convention
  importers::ImportOptions r;
  r.region = importers::Region{170.0, -170.0, 42.0, 60.0};
  auto v = import(write(o), r);
  EXPECT_DOUBLE_EQ(v.grid.lon_deg.start, 170.0);
  EXPECT_EQ(v.grid.lon_deg.count, 5);
  EXPECT_DOUBLE_EQ(v.grid.lat_deg.start, 45.0);
  EXPECT_EQ(v.grid.lat_deg.count, 3);
  expect_synthetic_values(v, 1e-4);
  r.horizontal_stride = 2;
  auto w = import(write(o, "s.nc"), r);
  EXPECT_EQ(w.grid.lon_deg.count, 3);
  EXPECT_DOUBLE_EQ(w.grid.lon_deg.step, 10.0);
}

TEST_F(CfImport, GaussianLatitudesAreResampledOntoAnEvenGrid) {
  SynthOptions o;
  o.lats = {40.0, 44.0, 50.5, 55.0};
  auto v = import(write(o));
  EXPECT_EQ(v.grid.lat_deg.count, 4);
  EXPECT_DOUBLE_EQ(v.grid.lat_deg.step, 5.0);
  // u = 10 + lat / 10 is linear in latitude, so resampling keeps it exactly.
  const auto& u = v.step(0)[core::Field::WindU];
  EXPECT_NEAR(u[v.grid.index(0, 1, 1)], 10.0 + 4.5, 1e-3);
}

TEST_F(CfImport, LazyLoadingEvictsBeyondTheCache) {
  SynthOptions o;
  o.times = 4;
  importers::ImportOptions io;
  io.cache_steps = 1;
  auto v = import(write(o), io);
  v.step(0);
  v.step(3);
  EXPECT_EQ(v.loaded_steps(), 1u);
  EXPECT_TRUE(v.is_loaded(3));
  EXPECT_FALSE(v.is_loaded(0));
  io.time_first = 1;
  io.time_last = 3;
  io.time_stride = 2;
  auto w = import(write(o, "t.nc"), io);
  ASSERT_EQ(w.times.size(), 2u);
  EXPECT_EQ(w.times[1].iso_utc, "2024-01-15T09:00:00Z");
  // By valid time: 03:00 to 06:00 inclusive.
  importers::ImportOptions by_time;
  by_time.time_from_iso = "2024-01-15T03:00:00Z";
  by_time.time_to_iso = "2024-01-15T06:00:00Z";
  auto z = import(write(o, "t2.nc"), by_time);
  ASSERT_EQ(z.times.size(), 2u);
  EXPECT_EQ(z.times[0].iso_utc, "2024-01-15T03:00:00Z");
  by_time.time_from_iso = "2030-01-01T00:00:00Z";
  by_time.time_to_iso.clear();
  try {
    import(write(o, "t3.nc"), by_time);
    FAIL();
  } catch (const importers::ImportError& e) {
    EXPECT_NE(std::string(e.what()).find("from 2024-01-15T00:00:00Z to 2024-01-15T09:00:00Z"), std::string::npos) << e.what();
  }
}

// Bad input: one line naming the file, the variable and what was expected; never a crash.
void expect_import_error(const std::string& path, std::initializer_list<const char*> needles) {
  try {
    // Some checks run when a time step is read (values), others when the file is opened (structure).
    importers::import_file(path).step(0);
    ADD_FAILURE() << "no error for " << path;
  } catch (const importers::ImportError& e) {
    const std::string m = e.what();
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;
    EXPECT_NE(m.find(path), std::string::npos) << m;
    for (const char* n : needles) EXPECT_NE(m.find(n), std::string::npos) << m;
  }
}

TEST_F(CfImport, AbsurdValuesAreRejected) {
  SynthOptions o;
  o.packed = false;
  o.cc_override = 7.0;
  expect_import_error(write(o, "cc7.nc"), {"'cc'", "7", "expected a fraction"});
  SynthOptions z;
  z.packed = false;
  z.z_override = -1e30;
  expect_import_error(write(z, "z.nc"), {"'z'", "expected"});
  // One height out of range among 100 rows: the altitude probe reads the heights in bands of rows
  // on every core, and still names the one value.
  SynthOptions one;
  one.packed = false;
  one.lats.clear();
  for (int k = 0; k < 100; ++k) one.lats.push_back(89.1 - 1.8 * k);
  one.z_bad_row = 70;
  one.z_bad_value = 5.0e6;  // m2 s-2: about 510 km up
  expect_import_error(write(one, "z_one.nc"), {"'z'", "value 5e+06", "a height of", "expected a height between -1 km and 100 km"});
}

TEST_F(CfImport, BrokenAndUnsupportedFiles) {
  expect_import_error((dir_ / "absent.nc").string(), {"no such file"});
  const std::string garbage = (dir_ / "garbage.nc").string();
  std::ofstream(garbage) << "this is not a netcdf file at all";
  expect_import_error(garbage, {"not a readable NetCDF file"});
  // A classic file cut short.
  const std::string classic = (dir_ / "classic.nc").string();
  {
    cv::test::NcBuilder b(classic, NC_CLOBBER);
    const int d = b.dim("x", 100000);
    const int v = b.var("big", NC_DOUBLE, {d});
    b.put(v, std::vector<double>(100000, 1.0));
    b.close();
  }
  std::filesystem::resize_file(classic, 700000);  // 100 000 doubles need 800 000 bytes
  expect_import_error(classic, {"truncated"});
  // No cloud variable.
  SynthOptions o;
  o.with_cloud = false;
  expect_import_error(write(o, "nocloud.nc"), {"no cloud variable", "cc", "clwc", "ciwc"});
  // A cloud variable with an extra dimension.
  const std::string extra = (dir_ / "extra.nc").string();
  {
    cv::test::NcBuilder b(extra);
    const int dx = b.dim("longitude", 3), dy = b.dim("latitude", 2), dz = b.dim("level", 2), de = b.dim("ensemble", 2);
    const int vx = b.var("longitude", NC_FLOAT, {dx}), vy = b.var("latitude", NC_FLOAT, {dy}), vz = b.var("level", NC_FLOAT, {dz});
    b.text(vx, "units", "degrees_east");
    b.text(vy, "units", "degrees_north");
    b.text(vz, "units", "hPa");
    b.var("cc", NC_FLOAT, {de, dz, dy, dx});
    b.put(vx, {0.0, 1.0, 2.0});
    b.put(vy, {0.0, 1.0});
    b.put(vz, {1000.0, 500.0});
    b.close();
  }
  expect_import_error(extra, {"'cc'", "ensemble", "expected"});
}

TEST_F(CfImport, AGridClaimingATrillionPointsIsRefusedBeforeAllocating) {
  const std::string p = (dir_ / "huge.nc").string();
  {
    cv::test::NcBuilder b(p);
    const std::size_t nx = 1000000, ny = 1000000;
    const int dx = b.dim("longitude", nx), dy = b.dim("latitude", ny), dz = b.dim("level", 2);
    const int vx = b.var("longitude", NC_DOUBLE, {dx}), vy = b.var("latitude", NC_DOUBLE, {dy}), vz = b.var("level", NC_DOUBLE, {dz});
    b.text(vx, "units", "degrees_east");
    b.text(vy, "units", "degrees_north");
    b.text(vz, "units", "hPa");
    b.text(b.var("cc", NC_FLOAT, {dz, dy, dx}), "units", "1");
    std::vector<double> lon(nx), lat(ny);
    for (std::size_t i = 0; i < nx; ++i) lon[i] = 360.0 * static_cast<double>(i) / nx;
    for (std::size_t j = 0; j < ny; ++j) lat[j] = -90.0 + 180.0 * static_cast<double>(j) / (ny - 1);
    b.put(vx, lon);
    b.put(vy, lat);
    b.put(vz, {1000.0, 500.0});
    b.close();
  }
  expect_import_error(p, {"GB per time step", "subset"});
}

TEST_F(CfImport, ReportJsonNamesEveryVariableItUsed) {
  SynthOptions o;
  auto v = import(write(o));
  v.step(0);
  const std::string j = v.report.to_json();
  for (const char* name : {"\"cc\"", "\"clwc\"", "\"z\"", "\"t\"", "\"q\"", "\"u\"", "\"v\"", "\"missing\"", "\"clamped\""}) {
    EXPECT_NE(j.find(name), std::string::npos) << name << "\n" << j;
  }
  EXPECT_NE(v.report.to_text().find("liquid extinction"), std::string::npos);
}

}  // namespace

namespace {

// Findings of a review, each a file the importer once took silently or read past.
TEST_F(CfImport, GeopotentialInMetresIsReadAsGeopotentialHeight) {
  SynthOptions o;
  o.packed = false;
  const std::string p = write(o);
  {
    int id, var;
    cv::test::nc_check(nc_open(p.c_str(), NC_WRITE, &id), "open");
    cv::test::nc_check(nc_inq_varid(id, "z", &var), "z");
    nc_redef(id);
    cv::test::nc_check(nc_put_att_text(id, var, "units", 1, "m"), "units");
    nc_enddef(id);
    // Overwrite z with the heights themselves (metres), as a "z" in m would hold.
    std::size_t n = 2 * 5 * 4 * 6;
    std::vector<double> zv(n);
    nc_get_var_double(id, var, zv.data());
    for (double& x : zv) x /= 9.80665;
    nc_put_var_double(id, var, zv.data());
    nc_close(id);
  }
  auto v = import(p);
  expect_synthetic_values(v, 1e-5);
}

TEST_F(CfImport, UpwardVelocityInMetresPerSecondIsNotOmega) {
  SynthOptions o;
  o.packed = false;
  const std::string p = write(o);
  {
    int id, dims[4], var;
    cv::test::nc_check(nc_open(p.c_str(), NC_WRITE, &id), "open");
    int u;
    nc_inq_varid(id, "u", &u);
    nc_inq_vardimid(id, u, dims);
    nc_redef(id);
    cv::test::nc_check(nc_def_var(id, "w", NC_FLOAT, 4, dims, &var), "w");
    nc_put_att_text(id, var, "units", 5, "m s-1");
    nc_put_att_text(id, var, "standard_name", 19, "upward_air_velocity");
    nc_enddef(id);
    std::vector<float> w(2 * 5 * 4 * 6, 1.0f);
    nc_put_var_float(id, var, w.data());
    nc_close(id);
  }
  auto v = import(p);
  const auto& d = v.step(0)[core::Field::WindW];
  ASSERT_FALSE(d.empty());
  EXPECT_NEAR(d[v.grid.index(0, 0, 1)], 1.0f, 1e-6f);
}

TEST_F(CfImport, RotatedPoleGridsAreRefused) {
  const std::string p = (dir_ / "rot.nc").string();
  {
    cv::test::NcBuilder b(p);
    const int dx = b.dim("rlon", 3), dy = b.dim("rlat", 2), dz = b.dim("level", 2);
    const int vx = b.var("rlon", NC_DOUBLE, {dx}), vy = b.var("rlat", NC_DOUBLE, {dy}), vz = b.var("level", NC_DOUBLE, {dz});
    b.text(vx, "standard_name", "grid_longitude");
    b.text(vx, "units", "degrees");
    b.text(vy, "standard_name", "grid_latitude");
    b.text(vy, "units", "degrees");
    b.text(vz, "units", "hPa");
    b.text(b.var("cc", NC_FLOAT, {dz, dy, dx}), "units", "1");
    b.put(vx, {0, 1, 2});
    b.put(vy, {0, 1});
    b.put(vz, {1000, 500});
    b.close();
  }
  expect_import_error(p, {"'rlon'", "expected a plain longitude/latitude grid"});
}

TEST_F(CfImport, ARegionBetweenTwoRowsAndInfiniteCoordinatesAreRefused) {
  SynthOptions o;
  importers::ImportOptions r;
  r.region = importers::Region{170.0, 190.0, 46.0, 48.0};  // rows are at 45 and 50
  try {
    import(write(o), r);
    FAIL();
  } catch (const importers::ImportError& e) {
    EXPECT_NE(std::string(e.what()).find("between two grid rows"), std::string::npos) << e.what();
  }
  SynthOptions inf;
  inf.lons = {170, 175, INFINITY, 185, 190, 195};
  inf.coord_type = NC_DOUBLE;
  expect_import_error(write(inf, "inf.nc"), {"'longitude'", "infinite"});
}

TEST_F(CfImport, ARegionReadsOnlyItsPartOfTheFile) {
  SynthOptions o;
  o.lons.clear();
  for (int k = 0; k <= 12; ++k) o.lons.push_back(160.0 + 5.0 * k);
  importers::ImportOptions r;
  r.region = importers::Region{170.0, 190.0, 45.0, 55.0};
  r.level_min_hpa = 500.0;
  auto v = import(write(o), r);
  v.step(0);
  // 13 longitudes x 4 latitudes x 5 levels in the file; the box needs 5 x 3 x 4.
  const auto& before = v.report.use("cloud fraction").before;
  EXPECT_EQ(before.count + before.missing, 5u * 3u * 4u);
}

}  // namespace

// A step's input is read in bands of 32 file rows (importers.md): with 100 rows, stored north to
// south, every output row must still read its own row, and every file row must be counted once in
// the report's input ranges; the ranges of what was stored must be those of the volume.
// Asked for half floats (the import's way to a float16 .cvvol), the reader stores each field's
// floats converted as write_cvvol would convert them, bit for bit, keeps no float copy, reports
// the same ranges, and derives its maps from the values a reader of the .cvvol will see.
TEST_F(CfImport, HalfFieldsAreTheFloatFieldsAsTheVolumeStoresThem) {
  SynthOptions o;
  o.lats = {40, 42, 44, 46, 48, 50, 52, 54, 56};
  const std::string path = write(o);
  // With the fixture's spacing (the first step's arrays prepared while the file is opened, on a
  // machine of two cores or more), and with a fine spacing asked for, which prepares none.
  for (const double dz : {0.0, 50.0}) {
    SCOPED_TRACE("dz " + std::to_string(dz));
    importers::ImportOptions as_float, as_half;
    as_float.dz_m = as_half.dz_m = dz;
    as_float.keep_cloudless_levels = as_half.keep_cloudless_levels = dz > 0.0;  // the grid spans every level
    as_half.half_fields = true;
    auto run = [&](const importers::ImportOptions& opt) { return dz > 0.0 ? importers::import_file(path, opt) : import(path, opt); };
    auto f = run(as_float);
    auto h = run(as_half);
    ASSERT_EQ(f.times.size(), h.times.size());
    const std::size_t n = f.grid.points();
    int compared = 0;
    for (std::size_t t = 0; t < f.times.size(); ++t) {
      core::TimeStepData widened;
      {
        const core::TimeStepData& df = f.step(t);
        const core::TimeStepData& dh = h.step(t);
        for (int k = 0; k < core::kFieldCount; ++k) {
          const auto field = static_cast<core::Field>(k);
          const std::size_t kk = static_cast<std::size_t>(k);
          ASSERT_EQ(f.has_field[kk], h.has_field[kk]) << core::field_name(field);
          ASSERT_TRUE(dh.fields[kk].empty()) << core::field_name(field);
          if (!f.has_field[kk]) {
            EXPECT_TRUE(dh.halves[kk].empty()) << core::field_name(field);
            continue;
          }
          ASSERT_EQ(df.fields[kk].size(), n);
          ASSERT_EQ(dh.halves[kk].size(), n);
          const float scale = core::half_field_scale(field);
          core::HalfBuffer want(n);
          core::floats_to_halves(df.fields[kk].data(), scale, want.data(), n);
          EXPECT_TRUE(want == dh.halves[kk]) << core::field_name(field) << " at step " << t;
          widened.fields[kk].resize(n);
          core::halves_to_floats(dh.halves[kk].data(), 1.0f / scale, widened.fields[kk].data(), n);
          ++compared;
        }
        widened.ground_m = dh.ground_m;
        core::derive_maps(h.grid, widened);
        for (std::size_t c = 0; c < h.grid.columns(); ++c) {
          const float a = widened.maps.optical_depth[c], b = dh.maps.optical_depth[c];
          EXPECT_TRUE(a == b || (std::isnan(a) && std::isnan(b))) << "column " << c;
          EXPECT_TRUE(widened.maps.cloud_cover[c] == dh.maps.cloud_cover[c] ||
                      (std::isnan(widened.maps.cloud_cover[c]) && std::isnan(dh.maps.cloud_cover[c])));
        }
      }
    }
    EXPECT_GE(compared, 10);
    ASSERT_EQ(f.report.variables.size(), h.report.variables.size());
    for (std::size_t i = 0; i < f.report.variables.size(); ++i) {
      const auto &a = f.report.variables[i], &b = h.report.variables[i];
      EXPECT_EQ(a.variable, b.variable);
      EXPECT_EQ(a.after.count, b.after.count) << a.variable;
      EXPECT_EQ(a.after.min, b.after.min) << a.variable;
      EXPECT_EQ(a.after.max, b.after.max) << a.variable;
    }
  }
}

TEST_F(CfImport, BandsOfRowsReadEveryRowOnce) {
  SynthOptions o;
  o.lats.clear();
  for (int k = 0; k < 100; ++k) o.lats.push_back(89.1 - 1.8 * k);  // 89.1 .. -89.1, north first
  importers::ImportOptions opt;
  opt.keep_cloudless_levels = true;  // every level read: the counts below are the whole file's
  for (int stride : {1, 3}) {
    SCOPED_TRACE("stride " + std::to_string(stride));
    opt.horizontal_stride = stride;
    auto v = import(write(o, "rows" + std::to_string(stride) + ".nc"), opt);
    const auto& g = v.grid;
    ASSERT_EQ(g.lat_deg.count, stride == 1 ? 100 : 34);
    // The wind u = 10 + lat / 10 tells which file row each output row read (at 700 hPa).
    const std::size_t nsteps = v.times.size();
    ASSERT_EQ(nsteps, 2u);
    core::ValueStats stored_u;
    for (std::size_t t = 0; t < nsteps; ++t) {
      const auto& d = v.step(t);
      for (int j = 0; j < g.lat_deg.count; ++j) {
        for (int i = 0; i < g.lon_deg.count; ++i) {
          ASSERT_NEAR(d[core::Field::WindU][g.index(i, j, 1)], 10.0 + g.lat_deg.at(j) / 10.0, 1e-3) << "row " << j;
        }
      }
      stored_u.add_all(d[core::Field::WindU].data(), d[core::Field::WindU].size());
    }
    const auto& u = v.report.use("eastward wind");
    // Read: each step's 100 rows x 5 levels over the columns from the first used to the last
    // (all 6; with stride 3, columns 0 and 3 are used, so 0..3), once. A stride reads the rows
    // between the used ones too.
    const std::size_t columns_read = stride == 1 ? 6u : 4u;
    EXPECT_EQ(u.before.count + u.before.missing, columns_read * 100u * 5u * 2u);
    EXPECT_EQ(u.before.missing, 0u);
    EXPECT_NEAR(u.before.min, 10.0 - 8.91, 1e-3);
    EXPECT_NEAR(u.before.max, 10.0 + 8.91, 1e-3);
    // Stored: exactly the ranges of the volume's values.
    EXPECT_EQ(u.after.count, stored_u.count);
    EXPECT_EQ(u.after.missing, stored_u.missing);
    EXPECT_EQ(u.after.min, stored_u.min);
    EXPECT_EQ(u.after.max, stored_u.max);
  }
}
