// Vertical coordinates other than pressure levels: heights (above sea level and above ground) and
// hybrid sigma-pressure levels (both formula_terms forms), against closed forms.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "importer.hpp"
#include "support/nc_builder.hpp"

namespace {
using namespace cv;
using cv::test::NcBuilder;

constexpr double kR = 6371000.0;
double geometric(double zgp) { return zgp * kR / (kR - zgp); }

// A 3 x 2 column set with cloud (cc 0.5, clwc 2e-4 kg/kg) on level index `cloud_level`, T 260 K, q 0.
struct Columns {
  std::string path;
  NcBuilder b;
  int dx, dy, dz, dt;
  std::vector<int> dims4;
  Columns(const std::string& p, std::size_t nz) : path(p), b(p) {
    dt = b.dim("time", 1), dz = b.dim("lev", nz), dy = b.dim("latitude", 2), dx = b.dim("longitude", 3);
    dims4 = {dt, dz, dy, dx};
  }
  void horizontal() {
    const int vx = b.var("longitude", NC_DOUBLE, {dx}), vy = b.var("latitude", NC_DOUBLE, {dy});
    b.text(vx, "units", "degrees_east");
    b.text(vy, "units", "degrees_north");
    b.put(vx, {10.0, 11.0, 12.0});
    b.put(vy, {45.0, 46.0});
  }
  void fields(std::size_t nz, std::size_t cloud_level) {
    const int cc = b.var("cc", NC_FLOAT, dims4), lw = b.var("clwc", NC_FLOAT, dims4), t = b.var("t", NC_FLOAT, dims4);
    b.text(t, "units", "K");
    std::vector<double> vcc(nz * 6, 0.0), vlw(nz * 6, 0.0), vt(nz * 6, 260.0);
    for (std::size_t n = 0; n < 6; ++n) vcc[cloud_level * 6 + n] = 0.5, vlw[cloud_level * 6 + n] = 2e-4;
    b.put(cc, vcc);
    b.put(lw, vlw);
    b.put(t, vt);
  }
};

double extinction(double p_pa) { return 3.0 * (p_pa / (287.05 * 260.0)) * (2e-4 / 0.5) / (2.0 * 1000.0 * 10e-6); }
double isa_p(double z) { return 101325.0 * std::pow(1.0 - 0.0065 * z / 288.15, 9.80665 / (287.05 * 0.0065)); }

TEST(Vertical, HeightLevelsInKilometres) {
  const auto dir = cv::test::temp_dir("vertical_height");
  const std::string p = (dir / "h.nc").string();
  {
    Columns c(p, 5);
    c.horizontal();
    const int vz = c.b.var("lev", NC_DOUBLE, {c.dz});
    c.b.text(vz, "units", "km");
    c.b.text(vz, "positive", "up");
    c.b.text(vz, "standard_name", "altitude");
    c.b.put(vz, {0.5, 1.0, 2.0, 3.0, 5.0});
    c.fields(5, 2);
    c.b.close();
  }
  importers::ImportOptions o;
  o.dz_m = 500.0;
  o.keep_cloudless_levels = true;  // the axis of every level, not only up to the cloud
  auto v = importers::import_file(p, o);
  EXPECT_DOUBLE_EQ(v.grid.alt_m.start, 500.0);
  EXPECT_EQ(v.grid.alt_m.count, 10);
  const auto& d = v.step(0);
  const std::size_t at2km = v.grid.index(1, 1, 3);
  EXPECT_NEAR(d[core::Field::CloudFraction][at2km], 0.5, 1e-6);
  // Pressure from the standard atmosphere at 2 km (the report warns so).
  EXPECT_NEAR(d[core::Field::ExtinctionLiquid][at2km], extinction(isa_p(2000.0)), 1e-6 * extinction(isa_p(2000.0)));
  EXPECT_EQ(v.report.format, "CF height levels");
  std::filesystem::remove_all(dir);
}

TEST(Vertical, HeightsAboveGroundAddTheSurfaceAltitude) {
  const auto dir = cv::test::temp_dir("vertical_agl");
  const std::string p = (dir / "agl.nc").string();
  {
    Columns c(p, 4);
    c.horizontal();
    const int vz = c.b.var("lev", NC_DOUBLE, {c.dz});
    c.b.text(vz, "units", "m");
    c.b.text(vz, "positive", "up");
    c.b.text(vz, "standard_name", "height");
    c.b.put(vz, {500.0, 1000.0, 2000.0, 3000.0});
    const int orog = c.b.var("orog", NC_DOUBLE, {c.dy, c.dx});
    c.b.text(orog, "standard_name", "surface_altitude");
    c.b.text(orog, "units", "m");
    c.b.put(orog, std::vector<double>(6, 1000.0));
    c.fields(4, 2);
    c.b.close();
  }
  importers::ImportOptions o;
  o.dz_m = 500.0;
  auto v = importers::import_file(p, o);
  EXPECT_DOUBLE_EQ(v.grid.alt_m.start, 1500.0);  // 500 m above a 1000 m surface
  const auto& d = v.step(0);
  EXPECT_NEAR(d[core::Field::CloudFraction][v.grid.index(0, 0, 3)], 0.5, 1e-6);  // cloud at 3000 m altitude
  std::filesystem::remove_all(dir);
}

// Isothermal (T 260 K, q 0) hybrid columns over a surface at sea level with ps = 1000 hPa: the
// hypsometric equation gives Z = R_d T / g0 ln(ps / p) exactly.
void hybrid_case(bool ap_form) {
  const auto dir = cv::test::temp_dir(ap_form ? "vertical_hyb_ap" : "vertical_hyb_a");
  const std::string p = (dir / "hyb.nc").string();
  // Levels top first, as IFS stores them: p = 300, 500, 700, 850, 950 hPa at ps = 1000 hPa.
  const std::vector<double> ap = {30000.0, 20000.0, 7000.0, 0.0, 0.0};
  const std::vector<double> bb = {0.0, 0.3, 0.63, 0.85, 0.95};
  {
    Columns c(p, 5);
    c.horizontal();
    const int vz = c.b.var("lev", NC_DOUBLE, {c.dz});
    c.b.text(vz, "standard_name", "atmosphere_hybrid_sigma_pressure_coordinate");
    c.b.text(vz, "formula_terms", ap_form ? "ap: hyam b: hybm ps: ps" : "a: hyam b: hybm p0: P0 ps: ps");
    c.b.put(vz, {1.0, 2.0, 3.0, 4.0, 5.0});
    const int va = c.b.var("hyam", NC_DOUBLE, {c.dz}), vb = c.b.var("hybm", NC_DOUBLE, {c.dz});
    if (ap_form) {
      c.b.text(va, "units", "Pa");
      c.b.put(va, ap);
    } else {
      const int p0 = c.b.var("P0", NC_DOUBLE, {});
      std::vector<double> a;
      for (double x : ap) a.push_back(x / 1e5);
      c.b.put(va, a);
      c.b.put(p0, {1e5});
    }
    c.b.put(vb, bb);
    const int ps = c.b.var("ps", NC_DOUBLE, {c.dt, c.dy, c.dx});
    c.b.put(ps, std::vector<double>(6, 1e5));
    c.fields(5, 2);  // cloud at 700 hPa
    c.b.close();
  }
  auto zgp = [](double pa) { return 287.05 * 260.0 / 9.80665 * std::log(1e5 / pa); };
  importers::ImportOptions o;
  o.dz_m = 100.0;
  auto v = importers::import_file(p, o);
  const auto& d = v.step(0);
  const double z950 = geometric(zgp(95000.0)), z850 = geometric(zgp(85000.0)), z700 = geometric(zgp(70000.0));
  // The column's data start at the first grid altitude at or above the 950 hPa level.
  int first = -1;
  for (int z = 0; z < v.grid.alt_m.count && first < 0; ++z) {
    if (!std::isnan(d[core::Field::Temperature][v.grid.index(2, 1, z)])) first = z;
  }
  ASSERT_GE(first, 0);
  EXPECT_GE(v.grid.alt_m.at(first), z950 - 1e-6);
  EXPECT_LT(v.grid.alt_m.at(first), z950 + o.dz_m);
  // Between 850 and 700 hPa the fraction rises linearly in altitude from 0 to 0.5: this checks the
  // hypsometric heights of both levels against the closed form.
  int checked = 0;
  for (int z = 0; z < v.grid.alt_m.count; ++z) {
    const double alt = v.grid.alt_m.at(z);
    if (alt <= z850 || alt >= z700) continue;
    EXPECT_NEAR(d[core::Field::CloudFraction][v.grid.index(2, 1, z)], 0.5 * (alt - z850) / (z700 - z850), 1e-5) << alt;
    ++checked;
  }
  EXPECT_GT(checked, 10);
  EXPECT_EQ(v.report.format, "CF hybrid sigma-pressure levels");
  std::filesystem::remove_all(dir);
}

TEST(Vertical, HybridLevelsApForm) { hybrid_case(true); }
TEST(Vertical, HybridLevelsAP0Form) { hybrid_case(false); }

TEST(Vertical, IfsModelLevelsWithHyamHybmAndLnsp) {
  // The same isothermal columns as above, written as cdo writes IFS model levels.
  const auto dir = cv::test::temp_dir("vertical_ifs");
  const std::string p = (dir / "ml.nc").string();
  {
    Columns c(p, 5);
    c.horizontal();
    const int vz = c.b.var("lev", NC_DOUBLE, {c.dz});
    c.b.text(vz, "long_name", "model_level_number");
    c.b.put(vz, {1.0, 2.0, 3.0, 4.0, 5.0});
    const int va = c.b.var("hyam", NC_DOUBLE, {c.dz}), vb = c.b.var("hybm", NC_DOUBLE, {c.dz});
    c.b.text(va, "units", "Pa");
    c.b.put(va, {30000.0, 20000.0, 7000.0, 0.0, 0.0});
    c.b.put(vb, {0.0, 0.3, 0.63, 0.85, 0.95});
    const int ls = c.b.var("lnsp", NC_DOUBLE, {c.dt, c.dy, c.dx});
    c.b.put(ls, std::vector<double>(6, std::log(1e5)));
    c.fields(5, 2);
    c.b.close();
  }
  importers::ImportOptions o;
  o.dz_m = 100.0;
  auto v = importers::import_file(p, o);
  auto zgp = [](double pa) { return 287.05 * 260.0 / 9.80665 * std::log(1e5 / pa); };
  const double z850 = geometric(zgp(85000.0)), z700 = geometric(zgp(70000.0));
  const auto& d = v.step(0);
  int checked = 0;
  for (int z = 0; z < v.grid.alt_m.count; ++z) {
    const double alt = v.grid.alt_m.at(z);
    if (alt <= z850 || alt >= z700) continue;
    EXPECT_NEAR(d[core::Field::CloudFraction][v.grid.index(0, 0, z)], 0.5 * (alt - z850) / (z700 - z850), 1e-5) << alt;
    ++checked;
  }
  EXPECT_GT(checked, 10);
  std::filesystem::remove_all(dir);
}

TEST(Vertical, ModelLevelNumbersWithoutCoefficientsSayWhatIsNeeded) {
  const auto dir = cv::test::temp_dir("vertical_ml");
  const std::string p = (dir / "ml.nc").string();
  {
    Columns c(p, 3);
    c.horizontal();
    const int vz = c.b.var("lev", NC_INT, {c.dz});
    c.b.text(vz, "standard_name", "model_level_number");
    c.b.put(vz, {1.0, 2.0, 3.0});
    c.fields(3, 1);
    c.b.close();
  }
  try {
    importers::import_file(p);
    FAIL();
  } catch (const importers::ImportError& e) {
    EXPECT_NE(std::string(e.what()).find("model-level numbers need their coefficients"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}

}  // namespace

namespace {

TEST(Vertical, ColumnsWithHundredsOfLevels) {
  const auto dir = cv::test::temp_dir("vertical_many");
  const std::string p = (dir / "many.nc").string();
  const std::size_t nz = 300;
  {
    Columns c(p, nz);
    c.horizontal();
    const int vz = c.b.var("lev", NC_DOUBLE, {c.dz});
    c.b.text(vz, "units", "m");
    c.b.text(vz, "positive", "up");
    std::vector<double> z;
    for (std::size_t k = 0; k < nz; ++k) z.push_back(100.0 + 50.0 * static_cast<double>(k));
    c.b.put(vz, z);
    c.fields(nz, 150);  // cloud at 7600 m
    c.b.close();
  }
  importers::ImportOptions o;
  o.dz_m = 50.0;
  o.keep_cloudless_levels = true;  // the axis of every level, not only up to the cloud
  auto v = importers::import_file(p, o);
  EXPECT_EQ(v.grid.alt_m.count, 300);
  EXPECT_NEAR(v.step(0)[core::Field::CloudFraction][v.grid.index(1, 1, 150)], 0.5, 1e-6);
  std::filesystem::remove_all(dir);
}

}  // namespace
