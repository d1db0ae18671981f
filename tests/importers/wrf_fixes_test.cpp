// Issue 12, WRF: a moving nest placed step by step, winds rotated with interpolated
// COSALPHA/SINALPHA, and consistency counts of the file's own boxes. Each test writes a small
// Mercator WRF file (true latitude 0, STAND_LON 0) whose fields are known functions of position.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <string>

#include "importer.hpp"
#include "support/nc_builder.hpp"
#include "support/wrf_writer.hpp"

namespace {
using namespace cv;

constexpr double kR = 6370000.0;  // WRF's sphere
constexpr double kDeg = 3.14159265358979323846 / 180.0;
constexpr double kDx = 50000.0;
double merc_y(double lat) { return kR * std::log(std::tan(3.14159265358979323846 / 4.0 + lat * kDeg / 2.0)); }
double merc_lat(double y) { return (2.0 * std::atan(std::exp(y / kR)) - 3.14159265358979323846 / 2.0) / kDeg; }

struct WrfSpec {
  int nx = 8, ny = 6, nz = 3, nt = 1;
  double lon0 = 10.0, lat0 = 5.0;
  std::vector<int> shift_cells = {0};  // per step: the domain's first point moves this many cells east
  bool cosalpha = false;
  bool cldfra = false;
  // QCLOUD (kg/kg) at mass level 1 from the mass point's true longitude (degrees).
  std::function<double(double lon)> qcloud = [](double lon) { return 1e-5 * (1.0 + lon); };
  std::function<double(int i, int j)> cldfra_at = [](int, int) { return 1.0; };
};

double lon_of(const WrfSpec& s, int t, int i) { return s.lon0 + (s.shift_cells[static_cast<std::size_t>(t)] + i) * kDx / kR / kDeg; }
double lat_of(const WrfSpec& s, int j) { return merc_lat(merc_y(s.lat0) + j * kDx); }

void write_wrf(const std::string& p, const WrfSpec& s) {
  cv::test::WrfFile f;
  f.nx = s.nx, f.ny = s.ny, f.nz = s.nz, f.nt = s.nt;
  f.map_proj = 3;  // Mercator, true latitude 0, STAND_LON 0
  f.dx = kDx;
  f.latlon_per_step = s.nt > 1;
  f.latlon = [&s](int t, int i, int j) { return std::pair{lat_of(s, j), lon_of(s, t, i)}; };
  f.qcloud = [&s](int t, int k, int i, int) { return k == 1 ? s.qcloud(lon_of(s, t, i)) : 0.0; };
  if (s.cldfra) f.cldfra = [&s](int, int k, int i, int j) { return k == 1 ? s.cldfra_at(i, j) : 0.0; };
  // Interpolated bilinearly, these give 0.9 + 0.01 fi and 0.1 + 0.02 fj.
  if (s.cosalpha) f.cos_sin_alpha = [](int i, int j) { return std::pair{0.9 + 0.01 * i, 0.1 + 0.02 * j}; };
  f.winds = true;  // grid u = 10, v = 0
  cv::test::write_wrf_file(p, f);
}

// Mass level 1 (1.5 km, p = 85 000 Pa, T = 300 (0.85)^(R_d/c_p), no vapour): sigma of q.
double sigma_level1(double q) {
  const double t = 300.0 * std::pow(0.85, 287.05 / 1004.6), rho = 85000.0 / (287.05 * t);
  return 3.0 * rho * q / (2.0 * 1000.0 * 10e-6);
}

bool any_contains(const std::vector<std::string>& lines, const std::string& what) {
  for (const auto& l : lines) {
    if (l.find(what) != std::string::npos) return true;
  }
  return false;
}

// 3. A vortex-following nest: XLAT/XLONG move 3 cells east at the second step. Each step's data
// lies where that step's domain is, with the values of the place, and the report says so.
TEST(Wrf, MovingNestIsPlacedWithEachStepsOwnGrid) {
  const auto dir = cv::test::temp_dir("wrf_moving");
  const std::string p = (dir / "nest.nc").string();
  WrfSpec s;
  s.nt = 2;
  s.shift_cells = {0, 3};
  write_wrf(p, s);
  auto vol = importers::import_file(p);
  EXPECT_TRUE(any_contains(vol.report.warnings, "the nest moves")) << vol.report.to_text();
  const auto& g = vol.grid;
  ASSERT_NEAR(g.alt_m.start, 500.0, 1e-6);
  ASSERT_NEAR(g.alt_m.at(2), 1500.0, 1e-6);  // the cloud level is a node
  // The output box holds both domains.
  EXPECT_LE(g.lon_deg.start, lon_of(s, 0, 0) + 1e-9);
  EXPECT_GE(g.lon_deg.last(), lon_of(s, 1, s.nx - 1) - g.lon_deg.step);
  int checked_in = 0, checked_out = 0;
  for (int t = 0; t < 2; ++t) {
    const auto& ext = vol.step(static_cast<std::size_t>(t))[core::Field::ExtinctionLiquid];
    const double west = lon_of(s, t, 0), east = lon_of(s, t, s.nx - 1);
    for (int y = 0; y < g.lat_deg.count; ++y) {
      const double lat = g.lat_deg.at(y);
      if (lat < lat_of(s, 0) + 0.01 || lat > lat_of(s, s.ny - 1) - 0.01) continue;  // clear of the south/north edges
      for (int x = 0; x < g.lon_deg.count; ++x) {
        const double lon = g.lon_deg.at(x);
        const float e = ext[g.index(x, y, 2)];
        if (lon > west + 0.01 && lon < east - 0.01) {
          ASSERT_FALSE(std::isnan(e)) << "step " << t << " lon " << lon;
          // QCLOUD is linear in longitude, so bilinear interpolation gives it exactly.
          EXPECT_NEAR(e, sigma_level1(s.qcloud(lon)), 1e-5 * sigma_level1(s.qcloud(lon))) << "step " << t << " lon " << lon;
          ++checked_in;
        } else if (lon < west - 0.01 || lon > east + 0.01) {
          EXPECT_TRUE(std::isnan(e)) << "step " << t << " lon " << lon << " is outside that step's domain";
          ++checked_out;
        }
      }
    }
  }
  EXPECT_GT(checked_in, 20);
  EXPECT_GT(checked_out, 10);
  std::filesystem::remove_all(dir);
}

// 7. Winds rotated with COSALPHA/SINALPHA interpolated at each column, not the lower-left cell's.
TEST(Wrf, WindRotationInterpolatesCosalphaSinalpha) {
  const auto dir = cv::test::temp_dir("wrf_rotation");
  const std::string p = (dir / "rot.nc").string();
  WrfSpec s;
  s.cosalpha = true;
  write_wrf(p, s);
  // A region whose corner lies inside a cell, so the columns fall between the mass points (the
  // default grid nearly lines up with them).
  importers::ImportOptions o;
  const double cell_deg = kDx / kR / kDeg;
  o.region = importers::Region{s.lon0 + 0.45 * cell_deg, 179.0, s.lat0 + 0.3 * cell_deg, 89.0};
  auto vol = importers::import_file(p, o);
  const auto& g = vol.grid;
  const auto& d = vol.step(0);
  int checked = 0;
  double most_off_cell = 0.0;  // how far the columns lie from a cell corner: the check can fail
  for (int y = 0; y < g.lat_deg.count; ++y) {
    for (int x = 0; x < g.lon_deg.count; ++x) {
      const std::size_t n = g.index(x, y, 2);
      if (std::isnan(d[core::Field::WindU][n])) continue;
      const double fi = (g.lon_deg.at(x) - s.lon0) * kDeg * kR / kDx, fj = (merc_y(g.lat_deg.at(y)) - merc_y(s.lat0)) / kDx;
      // Grid u = 10, v = 0: earth u = 10 cos, v = 10 sin.
      EXPECT_NEAR(d[core::Field::WindU][n], 10.0 * (0.9 + 0.01 * fi), 1e-4) << fi;
      EXPECT_NEAR(d[core::Field::WindV][n], 10.0 * (0.1 + 0.02 * fj), 1e-4) << fj;
      most_off_cell = std::max({most_off_cell, std::min(fi - std::floor(fi), std::ceil(fi) - fi),
                                std::min(fj - std::floor(fj), std::ceil(fj) - fj)});
      ++checked;
    }
  }
  EXPECT_GT(checked, 20);
  EXPECT_GT(most_off_cell, 0.25);
  std::filesystem::remove_all(dir);
}

// Messages: WRF consistency counts name what they count; the file's boxes are counted too.
TEST(Wrf, ConsistencyCountsNameTheFileBoxes) {
  const auto dir = cv::test::temp_dir("wrf_counts");
  const std::string p = (dir / "counts.nc").string();
  WrfSpec s;
  s.cldfra = true;
  s.cldfra_at = [](int i, int) { return i == 0 ? 0.0 : 1.0; };  // the western column of boxes: water, no fraction
  write_wrf(p, s);
  auto vol = importers::import_file(p);
  vol.step(0);
  EXPECT_TRUE(any_contains(vol.report.warnings, std::to_string(s.ny) + " file boxes with water")) << vol.report.to_text();
  EXPECT_TRUE(any_contains(vol.report.warnings, "resampled points (output columns x model levels) with water"))
      << vol.report.to_text();
  std::filesystem::remove_all(dir);
}

}  // namespace
