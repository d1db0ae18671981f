// Real model output from ../shared/data/real (see its SOURCES.md), with values checked by hand.
// Skipped with a message when the folder is absent (a user's clone); a failure under CI.
#include <gtest/gtest.h>
#include <netcdf.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "importer.hpp"
#include "support/real_data.hpp"
#include "nc_file.hpp"
#include "volume/volume_io.hpp"

namespace {
using namespace cv;

TEST(RealFiles, Era5PackedValueAgainstTheUnpackedNumberByHand) {
  REAL_FILE(path, "met-era5-cocip1.nc");
  // Raw int16 and attributes straight from netCDF-C, unpacked by hand.
  int id, var;
  ASSERT_EQ(nc_open(path.c_str(), NC_NOWRITE, &id), NC_NOERR);
  ASSERT_EQ(nc_inq_varid(id, "air_temperature", &var), NC_NOERR);
  double scale, offset;
  nc_get_att_double(id, var, "scale_factor", &scale);
  nc_get_att_double(id, var, "add_offset", &offset);
  const std::size_t idx[4] = {3, 2, 1, 5};  // (longitude, latitude, level, time)
  short raw;
  ASSERT_EQ(nc_get_var1_short(id, var, idx, &raw), NC_NOERR);
  nc_close(id);
  const double by_hand = raw * scale + offset;
  importers::NcFile f(path);
  const auto& v = f.var("air_temperature");
  const auto got = f.read(v, {3, 2, 1, 5}, {1, 1, 1, 1});
  ASSERT_EQ(got.size(), 1u);
  EXPECT_DOUBLE_EQ(got[0], by_hand);
  EXPECT_GT(by_hand, 200.0);
  EXPECT_LT(by_hand, 240.0);  // upper-troposphere temperature in January
}

TEST(RealFiles, Era5ImportHeightsComeFromGeopotentialByHand) {
  REAL_FILE(path, "met-era5-cocip1.nc");
  importers::NcFile f(path);
  const auto z = f.read(f.var("geopotential"), {0, 0, 0, 0}, {16, 8, 4, 1});  // first time step
  double zmin = 1e30, zmax = -1e30;
  for (double phi : z) {
    const double h = phi * 6371000.0 / (9.80665 * 6371000.0 - phi);  // geometric height by hand
    zmin = std::min(zmin, h);
    zmax = std::max(zmax, h);
  }
  auto vol = importers::import_file(path);
  EXPECT_NEAR(vol.grid.alt_m.start, zmin, 1e-6);
  EXPECT_GE(vol.grid.alt_m.last(), zmax - vol.grid.alt_m.step);
  EXPECT_LE(vol.grid.alt_m.last(), zmax + 1e-6);
  // 200-300 hPa in January over the North Atlantic: roughly 8.5 to 12 km.
  EXPECT_GT(zmin, 8000.0);
  EXPECT_LT(zmax, 12500.0);
  EXPECT_EQ(vol.times.size(), 13u);
  EXPECT_EQ(vol.times[12].iso_utc, "2019-01-01T12:00:00Z");
  // Ice only, no liquid, and the report knows the longitude had no units.
  EXPECT_TRUE(vol.has_field[static_cast<int>(core::Field::ExtinctionIce)]);
  EXPECT_FALSE(vol.has_field[static_cast<int>(core::Field::ExtinctionLiquid)]);
  const auto& d = vol.step(0);
  float max_ext = 0.0f;
  for (float x : d[core::Field::ExtinctionIce]) {
    if (!std::isnan(x)) max_ext = std::max(max_ext, x);
  }
  // Cirrus: in-cloud extinction of order 1e-4 to 1e-2 per metre.
  EXPECT_GT(max_ext, 1e-5f);
  EXPECT_LT(max_ext, 5e-2f);
  bool noted = false;
  for (const auto& n : vol.report.notes) noted |= n.find("no units attribute") != std::string::npos;
  EXPECT_TRUE(noted);
}

TEST(RealFiles, Era5DescendingLatitudeAndMillibarsDescribed) {
  REAL_FILE(path, "met-accf-pl.nc");
  const std::string info = importers::describe_file(path);
  EXPECT_NE(info.find("millibars"), std::string::npos) << info;
  EXPECT_NE(info.find("2022-11-11T00:00:00Z"), std::string::npos) << info;  // hours since 1900 by hand: 1076976 h
  EXPECT_NE(info.find("importable: no"), std::string::npos) << info;
}

TEST(RealFiles, FilesWithoutCloudVariablesSayWhatIsMissing) {
  for (const char* name : {"met-accf-pl.nc", "GFS_global.nc"}) {
    REAL_FILE(path, name);
    try {
      importers::import_file(path);
      ADD_FAILURE() << name;
    } catch (const importers::ImportError& e) {
      EXPECT_NE(std::string(e.what()).find("no cloud variable"), std::string::npos) << e.what();
    }
  }
}

// Neither file has a cloud field; the ERA5-style one has temperature and relative humidity, so a
// cloud can be diagnosed when asked; GFS has temperature and heights only, and is told why not.
TEST(RealFiles, DiagnosedCloudWhereTheFileHasHumidity) {
  REAL_FILE(accf, "met-accf-pl.nc");
  importers::ImportOptions o;
  o.diagnose_cloud = true;
  auto vol = importers::import_file(accf, o);
  ASSERT_TRUE(vol.has_field[static_cast<int>(core::Field::CloudFraction)]);
  const auto& d = vol.step(0);
  float most = 0.0f;
  for (float c : d[core::Field::CloudFraction]) {
    if (!std::isnan(c)) most = std::max(most, c);
  }
  EXPECT_GT(most, 0.5f);  // 100-350 hPa over the North Atlantic in November: ice-supersaturated layers
  EXPECT_LE(most, 1.0f);
  bool loud = false;
  for (const auto& w : vol.report.warnings) loud |= w.find("DIAGNOSED CLOUD") != std::string::npos && w.find("RH from 'r'") != std::string::npos;
  EXPECT_TRUE(loud) << vol.report.to_text();
  const std::string info = importers::describe_file(accf);
  EXPECT_NE(info.find("importable with --diagnose-cloud: yes"), std::string::npos) << info;
  REAL_FILE(gfs, "GFS_global.nc");
  try {
    importers::import_file(gfs);
    ADD_FAILURE() << "GFS has no cloud field";
  } catch (const importers::ImportError& e) {
    // Without the flag, the message says at once that a diagnosis would not help either.
    EXPECT_NE(std::string(e.what()).find("nor can one be diagnosed"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("the file has no humidity"), std::string::npos) << e.what();
  }
  try {
    importers::import_file(gfs, o);
    ADD_FAILURE() << "GFS has no humidity";
  } catch (const importers::ImportError& e) {
    EXPECT_NE(std::string(e.what()).find("has temperature and no humidity"), std::string::npos) << e.what();
  }
}

TEST(RealFiles, GfsTimeUnitsAndSeamAreUnderstood) {
  REAL_FILE(path, "GFS_global.nc");
  const std::string info = importers::describe_file(path);
  EXPECT_NE(info.find("2021-01-30T18:00:00Z"), std::string::npos) << info;  // "Hour since ...T12:00:00Z" + 6
  EXPECT_NE(info.find("gpm"), std::string::npos) << info;
}

}  // namespace

namespace {
// `cloudviewer import` asks the reader for half floats (ImportOptions::half_fields): on the real
// files they are the float import's values as the float16 .cvvol stores them, bit for bit; WRF
// files keep float steps.
TEST(RealFiles, HalfFieldsAreTheFloatImportAsTheVolumeStoresIt) {
  struct Case {
    const char* name;
    bool diagnose;
    bool halves;  // whether the reader makes half floats
  };
  for (const Case c : {Case{"met-era5-cocip1.nc", false, true}, Case{"met-accf-pl.nc", true, true},
                       Case{"wrf_d01_allvars_cropped.nc", false, false}}) {
    SCOPED_TRACE(c.name);
    REAL_FILE(path, c.name);
    importers::ImportOptions o;
    o.diagnose_cloud = c.diagnose;
    auto f = importers::import_file(path, o);
    o.half_fields = true;
    auto h = importers::import_file(path, o);
    ASSERT_EQ(f.times.size(), h.times.size());
    const std::size_t n = f.grid.points();
    std::size_t compared = 0;
    for (std::size_t t = 0; t < f.times.size(); t += std::max<std::size_t>(1, f.times.size() / 3)) {
      const auto& df = f.step(t);
      const auto& dh = h.step(t);
      for (int k = 0; k < core::kFieldCount; ++k) {
        const std::size_t kk = static_cast<std::size_t>(k);
        if (!f.has_field[kk]) continue;
        ASSERT_EQ(df.fields[kk].size(), n);
        if (!c.halves) {
          EXPECT_TRUE(dh.halves[kk].empty());
          ASSERT_EQ(dh.fields[kk].size(), n);
          EXPECT_EQ(std::memcmp(dh.fields[kk].data(), df.fields[kk].data(), n * sizeof(float)), 0)  // NaN == NaN here
              << core::field_name(static_cast<core::Field>(k));
          continue;
        }
        ASSERT_EQ(dh.halves[kk].size(), n) << core::field_name(static_cast<core::Field>(k));
        core::HalfBuffer want(n);
        core::floats_to_halves(df.fields[kk].data(), core::half_field_scale(static_cast<core::Field>(k)), want.data(), n);
        EXPECT_TRUE(want == dh.halves[kk]) << core::field_name(static_cast<core::Field>(k)) << " at step " << t;
        compared += n;
      }
    }
    if (c.halves) {
      EXPECT_GT(compared, 0u);
    }
  }
}
}  // namespace
