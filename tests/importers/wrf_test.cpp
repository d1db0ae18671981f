// The WRF reader on the two real WRF files, checked by hand against the file's own numbers.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>

#include "importer.hpp"
#include "support/nc_builder.hpp"
#include "support/real_data.hpp"
#include "support/wrf_writer.hpp"
#include "nc_file.hpp"
#include "wrf_import.hpp"

namespace {
using namespace cv;

// WRF's heights: geopotential over its own constant g.
double wrf_height(double phi) { return phi / 9.81; }

TEST(Wrf, LambertHeightsFromPhPhbByHand) {
  REAL_FILE(path, "wrf_d01_allvars_cropped.nc");
  importers::NcFile f(path);
  const auto ph = f.read(f.var("PH"), {0, 0, 0, 0}, {1, 28, 8, 10});
  const auto phb = f.read(f.var("PHB"), {0, 0, 0, 0}, {1, 28, 8, 10});
  const auto hgt = f.read(f.var("HGT"));  // 2-D, no Time dimension
  // The lowest staggered level is the ground: (PH + PHB) / 9.81 equals HGT there (with 9.80665 it
  // would sit 1.7 m above it).
  for (std::size_t n = 0; n < 80; ++n) EXPECT_NEAR(wrf_height(ph[n] + phb[n]), hgt[n], 0.01) << n;
  // The lowest mass level is halfway between the two lowest staggered levels; by hand:
  double zmin = 1e30;
  for (std::size_t n = 0; n < 80; ++n) zmin = std::min(zmin, wrf_height(0.5 * (ph[n] + phb[n] + ph[n + 80] + phb[n + 80])));
  auto vol = importers::import_file(path);
  EXPECT_NEAR(vol.grid.alt_m.start, zmin, 1e-6);
  EXPECT_GT(zmin, 4400.0);  // the Tibetan Plateau
  ASSERT_EQ(vol.times.size(), 4u);
  EXPECT_EQ(vol.times[3].iso_utc, "2005-09-21T09:00:00Z");
  // Never any data below the ground: the lowest value in every column lies above the lowest terrain.
  const double hgt_min = *std::min_element(hgt.begin(), hgt.end());
  const auto& d = vol.step(0);
  const auto& t = d[core::Field::Temperature];
  int columns_with_data = 0;
  for (int y = 0; y < vol.grid.lat_deg.count; ++y) {
    for (int x = 0; x < vol.grid.lon_deg.count; ++x) {
      for (int k = 0; k < vol.grid.alt_m.count; ++k) {
        const float v = t[vol.grid.index(x, y, k)];
        if (std::isnan(v)) continue;
        EXPECT_GT(vol.grid.alt_m.at(k), hgt_min);
        EXPECT_GT(v, 180.0f);
        EXPECT_LT(v, 300.0f);
        ++columns_with_data;
        break;
      }
    }
  }
  EXPECT_GT(columns_with_data, 0);
  // The tilted Lambert domain does not fill its lon/lat bounding box: some columns have no data.
  EXPECT_LT(columns_with_data, vol.grid.lon_deg.count * vol.grid.lat_deg.count);
  bool lie_noted = false;
  for (const auto& n : vol.report.notes) lie_noted |= n.find("claim 200 x 200") != std::string::npos;
  EXPECT_TRUE(lie_noted);
}

TEST(Wrf, ProjectionRotationMatchesCosalphaSinalpha) {
  REAL_FILE(path, "wrf_d01_allvars_cropped.nc");
  importers::NcFile f(path);
  const auto lat = f.read(f.var("XLAT")), lon = f.read(f.var("XLONG"));
  const auto ca = f.read(f.var("COSALPHA")), sa = f.read(f.var("SINALPHA"));
  for (std::size_t n = 0; n < lat.size(); n += 7) {
    const auto [c, s] = importers::wrf_rotation_from_projection(f, lat[n], lon[n]);
    EXPECT_NEAR(c, ca[n], 1e-4) << n;
    EXPECT_NEAR(s, sa[n], 1e-4) << n;
  }
  EXPECT_GT(std::abs(sa[0]), 1e-3);  // the check has something to check: the grid is rotated here
}

TEST(Wrf, MercatorFileWithoutCloudFraction) {
  REAL_FILE(path, "ci_test_file.nc");
  auto vol = importers::import_file(path);
  EXPECT_FALSE(vol.has_field[static_cast<int>(core::Field::CloudFraction)]);
  EXPECT_TRUE(vol.has_field[static_cast<int>(core::Field::ExtinctionLiquid)]);
  EXPECT_FALSE(vol.has_field[static_cast<int>(core::Field::ExtinctionIce)]);
  EXPECT_LT(vol.grid.alt_m.last(), 6000.0);  // cut to the lowest 14 levels (top ~5.6 km)
  const auto& d = vol.step(0);
  float tmax = 0, ext_max = 0;
  for (float v : d[core::Field::Temperature]) {
    if (!std::isnan(v)) tmax = std::max(tmax, v);
  }
  for (float v : d[core::Field::ExtinctionLiquid]) {
    if (!std::isnan(v)) ext_max = std::max(ext_max, v);
  }
  EXPECT_GT(tmax, 295.0f);  // the Gulf of Mexico in August, near the surface
  EXPECT_LT(tmax, 310.0f);
  EXPECT_GT(ext_max, 1e-3f);  // Katrina has clouds
  EXPECT_LT(ext_max, 1.0f);
  bool noted = false;
  for (const auto& n : vol.report.notes) noted |= n.find("no CLDFRA") != std::string::npos;
  EXPECT_TRUE(noted);
}

}  // namespace

namespace {

TEST(Wrf, AVariableOfTheWrongShapeIsRefusedBeforeAnyRead) {
  const auto dir = cv::test::temp_dir("wrf_shape");
  const std::string p = (dir / "wrf.nc").string();
  {
    cv::test::NcBuilder b(p);
    const int dt = b.dim("Time", 1), dx = b.dim("west_east", 3), dy = b.dim("south_north", 3), dz = b.dim("bottom_top", 2);
    const int dzs = b.dim("bottom_top_stag", 3);
    for (const char* a : {"MAP_PROJ"}) b.number(NC_GLOBAL, a, NC_INT, {3});
    for (const char* a : {"TRUELAT1", "TRUELAT2", "STAND_LON"}) b.number(NC_GLOBAL, a, NC_FLOAT, {0});
    for (const char* a : {"DX", "DY"}) b.number(NC_GLOBAL, a, NC_FLOAT, {100000});
    b.var("XLAT", NC_FLOAT, {dy, dx});
    b.var("XLONG", NC_FLOAT, {dy, dx});
    b.var("PH", NC_FLOAT, {dt, dzs, dy, dx});
    b.var("PHB", NC_FLOAT, {dt, dzs, dy, dx});
    b.var("P", NC_FLOAT, {dt, dz, dy});  // one dimension short
    b.var("QCLOUD", NC_FLOAT, {dt, dz, dy, dx});
    b.close();
  }
  try {
    importers::import_file(p);
    FAIL();
  } catch (const importers::ImportError& e) {
    EXPECT_NE(std::string(e.what()).find("variable 'P' has shape (1 x 2 x 3)"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}

}  // namespace

#include <GeographicLib/PolarStereographic.hpp>

namespace {

// A small polar stereographic WRF domain whose XLAT/XLONG come from the inverse projection (WRF's
// 6370 km sphere, true latitude +-60), in the given hemisphere.
std::string write_polar_wrf(const std::filesystem::path& dir, bool north) {
  const std::string p = (dir / (north ? "north.nc" : "south.nc")).string();
  const int nx = 6, ny = 5, nz = 3;
  const double dx = 50000.0, stand_lon = -45.0, truelat = north ? 60.0 : -60.0;
  GeographicLib::PolarStereographic ps(6370000.0, 0.0, 1.0);
  ps.SetScale(std::abs(truelat), 1.0);
  double x0, y0;
  ps.Forward(north, north ? 70.0 : -70.0, 10.0, x0, y0);  // the domain's first mass point, 10 degrees east of STAND_LON
  std::vector<double> lat, lon;
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      double la, lo;
      ps.Reverse(north, x0 + i * dx, y0 + j * dx, la, lo);
      lat.push_back(la);
      lon.push_back(lo + stand_lon);
    }
  }
  cv::test::WrfFile f;
  f.nx = nx, f.ny = ny, f.nz = nz;
  f.map_proj = 2;
  f.truelat1 = f.truelat2 = truelat;
  f.stand_lon = stand_lon;
  f.dx = dx;
  f.latlon = [&](int, int i, int j) { return std::pair{lat[static_cast<std::size_t>(j * nx + i)], lon[static_cast<std::size_t>(j * nx + i)]}; };
  f.qcloud = [](int, int k, int, int) { return k == 1 ? 1e-4 : 0.0; };
  f.qcloud_type = NC_FLOAT;
  cv::test::write_wrf_file(p, f);
  return p;
}

TEST(Wrf, PolarStereographicInBothHemispheres) {
  const auto dir = cv::test::temp_dir("wrf_polar");
  for (bool north : {true, false}) {
    auto vol = importers::import_file(write_polar_wrf(dir, north));
    bool checked = false;
    for (const auto& n : vol.report.notes) {
      if (n.find("projection checked") != std::string::npos) {
        checked = true;
        const double off = std::stod(n.substr(n.find("lies ") + 5));
        EXPECT_LT(off, 1.0) << (north ? "north: " : "south: ") << n;
      }
    }
    EXPECT_TRUE(checked);
    // Mass levels at 0.5, 1.5 and 2.5 km; the cloud on the middle one.
    EXPECT_NEAR(vol.grid.alt_m.start, 500.0, 1e-3);
    const auto& d = vol.step(0);
    float most = 0.0f;
    for (float v : d[core::Field::ExtinctionLiquid]) {
      if (!std::isnan(v)) most = std::max(most, v);
    }
    // sigma = 3 rho q / (2 rho_w r_eff) at p = 850 hPa, T = 300 (p / 1e5)^(R_d / c_p), no vapour.
    const double t = 300.0 * std::pow(0.85, 287.05 / 1004.6), rho = 85000.0 / (287.05 * t);
    EXPECT_NEAR(most, 3.0 * rho * 1e-4 / (2.0 * 1000.0 * 10e-6), 1e-4) << (north ? "north" : "south");
  }
  std::filesystem::remove_all(dir);
}

}  // namespace

namespace {
// Global attributes that become integers are checked as numbers first: fuzz_netcdf_semantic found
// MAP_PROJ = 3.4e38, whose conversion to int is undefined (and a UBSan abort in `info`).
TEST(Wrf, HugeProjectionAndGridClaimsAreNumbersNotOverflows) {
  REAL_FILE(real, "ci_test_file.nc");
  const auto dir = std::filesystem::temp_directory_path() / ("cv_wrf_claims_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  auto with = [&](const char* name, double value) {
    const std::string p = (dir / (std::string(name) + ".nc")).string();
    std::filesystem::copy_file(real, p, std::filesystem::copy_options::overwrite_existing);
    std::filesystem::permissions(p, std::filesystem::perms::owner_write, std::filesystem::perm_options::add);
    int id = -1;
    cv::test::nc_check(nc_open(p.c_str(), NC_WRITE, &id), "open " + p);
    cv::test::nc_check(nc_redef(id), "redef");
    cv::test::nc_check(nc_put_att_double(id, NC_GLOBAL, name, NC_DOUBLE, 1, &value), "att");
    cv::test::nc_check(nc_close(id), "close");
    return p;
  };
  for (double bad : {3.4e38, -1e300, 2.5, 6.0}) {
    const std::string p = with("MAP_PROJ", bad);
    std::string msg;
    try {
      importers::import_file(p);
    } catch (const importers::ImportError& e) {
      msg = e.what();
    }
    EXPECT_NE(msg.find(": MAP_PROJ is "), std::string::npos) << bad << ": " << msg;
    EXPECT_NE(msg.find("expected 1 (Lambert conformal), 2 (polar stereographic) or 3 (Mercator)"), std::string::npos) << msg;
    // `info` refuses the same way.
    std::string info;
    try {
      info = importers::describe_file(p);
    } catch (const importers::ImportError& e) {
      info = e.what();
    }
    EXPECT_NE(info.find(": MAP_PROJ is "), std::string::npos) << bad << ": " << info;
  }
  // A grid size claim past any int is a claim that differs from the file: noted, and the file's
  // own dimensions used.
  const auto vol = importers::import_file(with("WEST-EAST_GRID_DIMENSION", 1e30));
  bool noted = false;
  for (const auto& n : vol.report.notes) noted |= n.find("(cropped?)") != std::string::npos;
  EXPECT_TRUE(noted);
  std::filesystem::remove_all(dir);
}
}  // namespace
