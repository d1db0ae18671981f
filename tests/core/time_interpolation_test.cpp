// Interpolation between forecast steps (core/volume/time_interpolation): a blob carried by a uniform
// wind has a known exact position; positivity, the no-inflation rule and stability under any winds;
// the instant against a file's time axis and the scene's time keys.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "scene/instant.hpp"
#include "scene/scene_json.hpp"
#include "volume/time_interpolation.hpp"

namespace cv::core {
namespace {

constexpr double kPi = 3.14159265358979323846;

// 64 x 9 x 3 nodes of 0.5 degree around the equator, 1 km apart from 1 km up.
VolumeGrid strip() {
  VolumeGrid g;
  g.lon_deg = {0.0, 0.5, 64};
  g.lat_deg = {-2.0, 0.5, 9};
  g.alt_m = {1000.0, 1000.0, 3};
  return g;
}

// A Gaussian blob of width 3 cells centred at longitude index x0, latitude row 4, every level.
std::vector<float> blob(const VolumeGrid& g, double x0) {
  std::vector<float> f(g.points());
  for (int k = 0; k < g.alt_m.count; ++k)
    for (int j = 0; j < g.lat_deg.count; ++j)
      for (int i = 0; i < g.lon_deg.count; ++i) {
        const double r2 = (i - x0) * (i - x0) + (j - 4.0) * (j - 4.0);
        f[g.index(i, j, k)] = static_cast<float>(1e-3 * std::exp(-r2 / 9.0));
      }
  return f;
}

StepWinds uniform(const VolumeGrid& g, double u, double v = 0.0, double w = 0.0) {
  StepWinds s;
  s.u.assign(g.points(), static_cast<float>(u));
  s.v.assign(g.points(), static_cast<float>(v));
  if (w != 0.0) s.w.assign(g.points(), static_cast<float>(w));
  return s;
}

// The longitude index of the largest value on the blob's row at the lowest level.
int peak_x(const VolumeGrid& g, const std::vector<float>& f) {
  int best = 0;
  for (int i = 1; i < g.lon_deg.count; ++i)
    if (f[g.index(i, 4, 0)] > f[g.index(best, 4, 0)]) best = i;
  return best;
}

double total(const std::vector<float>& f) {
  double t = 0.0;
  for (float v : f) t += v;
  return t;
}

// The blob at 16 cells at the earlier step and 16 cells further east at the later one, as a uniform
// eastward wind carries it over a gap of 3 h.
struct Carried {
  VolumeGrid g = strip();
  double gap_s = 3 * 3600.0;
  double cells = 16.0;
  double u = cells * (g.earth_radius_m + g.alt_m.start) * (0.5 * kPi / 180.0) / gap_s;  // m/s
  GridMeanExtinction e0{blob(g, 16.0), {}}, e1{blob(g, 16.0 + cells), {}};
  StepWinds w = uniform(g, u);
};

TEST(TimeInterpolation, AdvectedRecoversAUniformlyCarriedBlobAtHalfTheGapAndLinearDoesNot) {
  const Carried c;
  TimeInterpolationReport r;
  const GridMeanExtinction adv = interpolate_extinction(c.g, c.e0, c.e1, c.w, c.w, c.gap_s, 0.5, TimeInterpolation::Advected, &r);
  EXPECT_EQ(r.used, TimeInterpolation::Advected);
  EXPECT_TRUE(r.warning.empty());
  EXPECT_LE(std::abs(peak_x(c.g, adv.liquid_per_m) - 24), 1) << "the exact position at half the gap is 24";
  // Its peak keeps the blob's height (a moved blob, not two faded ones).
  EXPECT_GT(adv.liquid_per_m[c.g.index(24, 4, 0)], 0.9e-3);
  const GridMeanExtinction lin = interpolate_extinction(c.g, c.e0, c.e1, c.w, c.w, c.gap_s, 0.5, TimeInterpolation::Linear);
  EXPECT_GT(std::abs(peak_x(c.g, lin.liquid_per_m) - 24), 1) << "a blend peaks where the steps had the blob, not between";
  EXPECT_LT(lin.liquid_per_m[c.g.index(24, 4, 0)], 0.1e-3);
}

TEST(TimeInterpolation, AdvectedIsTheDefaultWithWindsAndFallsBackToLinearWithAWarningWithout) {
  const Carried c;
  TimeInterpolationReport r;
  interpolate_extinction(c.g, c.e0, c.e1, c.w, c.w, c.gap_s, 0.25, TimeInterpolation::Auto, &r);
  EXPECT_EQ(r.used, TimeInterpolation::Advected);
  const StepWinds none;
  const GridMeanExtinction fell = interpolate_extinction(c.g, c.e0, c.e1, none, none, c.gap_s, 0.25, TimeInterpolation::Advected, &r);
  EXPECT_EQ(r.used, TimeInterpolation::Linear);
  EXPECT_NE(r.warning.find("fell back to linear"), std::string::npos) << r.warning;
  const GridMeanExtinction lin = interpolate_extinction(c.g, c.e0, c.e1, none, none, c.gap_s, 0.25, TimeInterpolation::Linear);
  EXPECT_EQ(fell.liquid_per_m, lin.liquid_per_m);
  interpolate_extinction(c.g, c.e0, c.e1, none, none, c.gap_s, 0.25, TimeInterpolation::Auto, &r);
  EXPECT_EQ(r.used, TimeInterpolation::Linear);
  EXPECT_TRUE(r.warning.empty()) << "auto without winds is linear by choice, not a fallback";
}

TEST(TimeInterpolation, NearestAndTheEndsAreTheStepsThemselves) {
  const Carried c;
  for (TimeInterpolation m : {TimeInterpolation::Nearest, TimeInterpolation::Linear, TimeInterpolation::Advected}) {
    EXPECT_EQ(interpolate_extinction(c.g, c.e0, c.e1, c.w, c.w, c.gap_s, 0.0, m).liquid_per_m, c.e0.liquid_per_m);
    EXPECT_EQ(interpolate_extinction(c.g, c.e0, c.e1, c.w, c.w, c.gap_s, 1.0, m).liquid_per_m, c.e1.liquid_per_m);
  }
  EXPECT_EQ(interpolate_extinction(c.g, c.e0, c.e1, c.w, c.w, c.gap_s, 0.4, TimeInterpolation::Nearest).liquid_per_m, c.e0.liquid_per_m);
  EXPECT_EQ(interpolate_extinction(c.g, c.e0, c.e1, c.w, c.w, c.gap_s, 0.6, TimeInterpolation::Nearest).liquid_per_m, c.e1.liquid_per_m);
}

// A convergent wind (eastward, slowing to the east) piles a field up: the carried field may not
// hold more optical depth than its source, nor any column more than the source's thickest.
TEST(TimeInterpolation, TheWarpNeitherGoesNegativeNorInflatesTheOpticalDepth) {
  const VolumeGrid g = strip();
  std::vector<float> f(g.points());
  for (std::size_t p = 0; p < f.size(); ++p) f[p] = static_cast<float>(1e-4 * (1.0 + std::sin(0.7 * double(p))));
  StepWinds w;
  w.u.resize(g.points()), w.v.assign(g.points(), 0.0f), w.w.resize(g.points());
  for (int k = 0; k < g.alt_m.count; ++k)
    for (int j = 0; j < g.lat_deg.count; ++j)
      for (int i = 0; i < g.lon_deg.count; ++i) {
        w.u[g.index(i, j, k)] = static_cast<float>(40.0 * std::cos(2.0 * kPi * i / 64.0));
        w.w[g.index(i, j, k)] = static_cast<float>(0.3 * std::sin(2.0 * kPi * i / 64.0));
      }
  const GridMeanExtinction e0{f, f}, e1{f, {}};
  TimeInterpolationReport r;
  const GridMeanExtinction adv = interpolate_extinction(g, e0, e1, w, w, 6 * 3600.0, 0.5, TimeInterpolation::Advected, &r);
  EXPECT_TRUE(r.vertical_wind);
  const GridMeanExtinction lin = interpolate_extinction(g, e0, e1, w, w, 6 * 3600.0, 0.5, TimeInterpolation::Linear);
  ASSERT_EQ(adv.liquid_per_m.size(), g.points());
  ASSERT_EQ(adv.ice_per_m.size(), g.points());
  for (float v : adv.liquid_per_m) ASSERT_TRUE(std::isfinite(v) && v >= 0.0f);
  for (float v : adv.ice_per_m) ASSERT_TRUE(std::isfinite(v) && v >= 0.0f);
  // On this strip near the equator the area weights are all but equal: the plain sums compare.
  EXPECT_LE(total(adv.liquid_per_m), total(lin.liquid_per_m) * (1.0 + 1e-4));
  EXPECT_LE(total(adv.ice_per_m), total(lin.ice_per_m) * (1.0 + 1e-4));
  double src_col = 0.0;
  const std::size_t cols = g.columns();
  for (std::size_t c = 0; c < cols; ++c) {
    double s = 0.0, a = 0.0;
    for (int k = 0; k < g.alt_m.count; ++k) s += f[k * cols + c];
    src_col = std::max(src_col, s);
    (void)a;
  }
  for (std::size_t c = 0; c < cols; ++c) {
    double a = 0.0;
    for (int k = 0; k < g.alt_m.count; ++k) a += adv.liquid_per_m[k * cols + c];
    EXPECT_LE(a, src_col * (1.0 + 1e-5)) << "column " << c;
  }
}

TEST(TimeInterpolation, AStiffCaseStaysFiniteAndNonNegative) {
  const VolumeGrid g = strip();
  const std::vector<float> f = blob(g, 20.0);
  StepWinds w0 = uniform(g, 3e4, -2e4, 50.0), w1 = uniform(g, -1e5, 7e4, -80.0);
  w0.u[17] = std::numeric_limits<float>::quiet_NaN();
  w1.v[5] = std::numeric_limits<float>::infinity();
  TimeInterpolationReport r;
  const GridMeanExtinction out = interpolate_extinction(g, {f, {}}, {f, {}}, w0, w1, 30 * 86400.0, 0.3, TimeInterpolation::Advected, &r);
  EXPECT_EQ(r.substeps, kMaxAdvectionSubsteps);
  EXPECT_GT(r.max_courant, 1e3);
  const double peak = *std::max_element(f.begin(), f.end());
  for (float v : out.liquid_per_m) {
    ASSERT_TRUE(std::isfinite(v));
    ASSERT_GE(v, 0.0f);
    ASSERT_LE(v, peak * (1.0 + 1e-6));
  }
}

// A blob carried 16 rows north and 4 levels up over the gap arrives there whole: the rows and
// levels beyond a trajectory's reach of any cloud are skipped, and the reach must cover this.
TEST(TimeInterpolation, AdvectedCarriesABlobAcrossRowsAndLevels) {
  VolumeGrid g;
  g.lon_deg = {0.0, 0.5, 32};
  g.lat_deg = {-8.0, 0.5, 33};
  g.alt_m = {1000.0, 500.0, 9};
  std::vector<float> f(g.points(), 0.0f);
  for (int k = 0; k < 9; ++k)
    for (int j = 0; j < 33; ++j)
      for (int i = 0; i < 32; ++i) {
        const double r2 = (i - 16.0) * (i - 16.0) + (j - 8.0) * (j - 8.0) + 4.0 * (k - 2.0) * (k - 2.0);
        f[g.index(i, j, k)] = static_cast<float>(1e-3 * std::max(0.0, 1.0 - r2 / 9.0));  // 0 beyond 3 cells
      }
  const double gap_s = 6 * 3600.0;
  const double v = 16.0 * (g.earth_radius_m + 2000.0) * (0.5 * kPi / 180.0) / gap_s, w = 4.0 * 500.0 / gap_s;
  StepWinds winds;
  winds.u.assign(g.points(), 0.0f), winds.v.assign(g.points(), static_cast<float>(v)), winds.w.assign(g.points(), static_cast<float>(w));
  int substeps = 0;
  const std::vector<float> moved = advect_field(g, f, winds, winds, gap_s, 1.0, 0, &substeps);
  std::size_t best = 0;
  for (std::size_t p = 1; p < moved.size(); ++p)
    if (moved[p] > moved[best]) best = p;
  const int bi = static_cast<int>(best % 32), bj = static_cast<int>(best / 32 % 33), bk = static_cast<int>(best / (32 * 33));
  EXPECT_EQ(bi, 16);
  EXPECT_LE(std::abs(bj - 24), 1) << "16 rows north of row 8";
  EXPECT_LE(std::abs(bk - 6), 1) << "4 levels above level 2";
  EXPECT_GT(moved[best], 0.8e-3) << "the blob arrives whole";
  EXPECT_GE(substeps, 16) << "at most a cell per sub-step";
  // Nothing is left where the blob was.
  EXPECT_LT(moved[g.index(16, 8, 2)], 1e-6);
}

// On grids above kMaxTrajectoryColumns the trajectories run on a lattice and the nodes between
// blend their displacements: on smooth winds that is the nodes' own trajectories to a small part of
// a cell (the blend's error is the lattice spacing squared times the displacement's curvature:
// about 0.01 cell here, against features 10 cells wide).
TEST(TimeInterpolation, TheTrajectoryLatticeMatchesEveryNodesOwnTrajectoryOnSmoothWinds) {
  VolumeGrid g;
  g.lon_deg = {0.0, 0.5, 512};
  g.lat_deg = {-64.0, 0.5, 256};
  g.alt_m = {1000.0, 1000.0, 2};
  ASSERT_EQ(trajectory_stride(g), 2);
  std::vector<float> f(g.points());
  StepWinds w;
  w.u.resize(g.points()), w.v.resize(g.points());
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 256; ++j)
      for (int i = 0; i < 512; ++i) {
        const std::size_t p = g.index(i, j, k);
        f[p] = static_cast<float>(1e-3 * std::max(0.0, std::sin(0.3 * i) * std::sin(0.25 * j)));
        w.u[p] = static_cast<float>(15.0 + 10.0 * std::sin(2.0 * kPi * i / 256.0));
        w.v[p] = static_cast<float>(5.0 * std::cos(2.0 * kPi * j / 128.0));
      }
  int n_lattice = 0, n_nodes = 0;
  const std::vector<float> lattice = advect_field(g, f, w, w, 6 * 3600.0, 0.5, 0, &n_lattice);
  const std::vector<float> nodes = advect_field(g, f, w, w, 6 * 3600.0, 0.5, 0, &n_nodes, nullptr, 1);
  EXPECT_GE(n_nodes, 4) << "the winds move the field about 5 cells' lengths of latitude";
  double worst = 0.0, sum = 0.0, moved = 0.0;
  for (std::size_t p = 0; p < f.size(); ++p) {
    worst = std::max(worst, double(std::abs(lattice[p] - nodes[p])));
    sum += std::abs(lattice[p] - nodes[p]);
    moved += std::abs(nodes[p] - f[p]);
  }
  EXPECT_LT(worst, 1e-5) << "1 % of the field's largest value";
  EXPECT_LT(sum, 1e-3 * moved) << "the lattice's difference is a thousandth of the motion itself";
  std::printf("lattice against every node: largest difference %.3g, summed %.3g of the motion's\n", worst, sum / moved);
}

// A global grid on a lattice (its polar rows' zonal winds are thousands of cells over the gap):
// finite, non-negative, never above the source's largest.
TEST(TimeInterpolation, AGlobalLatticeWithPolarRowsStaysBounded) {
  VolumeGrid g;
  g.lon_deg = {0.0, 0.5, 720};
  g.lat_deg = {-90.0, 0.5, 361};
  g.alt_m = {1000.0, 1000.0, 2};
  ASSERT_TRUE(g.wraps_lon());
  ASSERT_GT(trajectory_stride(g), 1);
  std::vector<float> f(g.points());
  for (std::size_t p = 0; p < f.size(); ++p) f[p] = static_cast<float>(1e-3 * std::max(0.0, std::sin(0.05 * double(p))));
  StepWinds w0 = uniform(g, 40.0, 20.0), w1 = uniform(g, -30.0, 60.0);
  w0.u[g.index(3, 360, 1)] = std::numeric_limits<float>::quiet_NaN();
  w1.v[g.index(700, 0, 0)] = std::numeric_limits<float>::infinity();
  TimeInterpolationReport r;
  const GridMeanExtinction out = interpolate_extinction(g, {f, f}, {f, {}}, w0, w1, 12 * 3600.0, 0.4, TimeInterpolation::Advected, &r);
  EXPECT_EQ(r.stride, trajectory_stride(g));
  EXPECT_GT(r.max_courant, 1e3) << "the polar rows";
  EXPECT_LT(r.substeps, kMaxAdvectionSubsteps) << "sub-steps count cells on the ground: the polar rows' thousand index cells do not drive them to the cap";
  const double peak = *std::max_element(f.begin(), f.end());
  for (const std::vector<float>* field : {&out.liquid_per_m, &out.ice_per_m}) {
    ASSERT_EQ(field->size(), g.points());
    for (float v : *field) {
      ASSERT_TRUE(std::isfinite(v));
      ASSERT_GE(v, 0.0f);
      ASSERT_LE(v, peak * (1.0 + 1e-6));
    }
  }
}

std::vector<ValidTime> three_hourly(int n) {
  std::vector<ValidTime> t;
  for (int i = 0; i < n; ++i) {
    const std::int64_t s = 1705276800 + i * 10800;  // 2024-01-15T00:00:00Z
    t.push_back({s, format_iso_utc(s)});
  }
  return t;
}

// The winds' angular flow (for the viewer's reprojection): a uniform wind's rates are u / ((R + z)
// cos lat) and v / (R + z) in degrees per second, linear in time between the steps, averaged onto a
// coarser grid where the grid is large, with no data as calm; no flow without both steps' winds.
TEST(AngularFlow, GivesTheWindsRatesOnACoarseGridLinearInTime) {
  const VolumeGrid g = strip();
  const StepWinds w0 = uniform(g, 10.0, 4.0), w1 = uniform(g, 30.0, -4.0);
  const AngularFlow f = angular_flow(g, w0, w1, 0.25);
  ASSERT_FALSE(f.empty());
  EXPECT_EQ(f.lon_deg.count, 64);  // small enough: every node kept
  EXPECT_EQ(f.lat_deg.count, 9);
  EXPECT_EQ(f.levels, 3);
  const double u = 0.75 * 10.0 + 0.25 * 30.0, v = 0.75 * 4.0 + 0.25 * -4.0;
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j < 9; ++j) {
      const double r = g.earth_radius_m + g.alt_m.at(k), lat = g.lat_deg.at(j) * kPi / 180.0;
      const std::size_t q = (std::size_t(k) * 9 + std::size_t(j)) * 64 + 17;
      EXPECT_NEAR(f.deg_per_s[2 * q], u / (r * std::cos(lat)) * 180.0 / kPi, 1e-9) << j << " " << k;
      EXPECT_NEAR(f.deg_per_s[2 * q + 1], v / r * 180.0 / kPi, 1e-10);
    }

  // At most 16 nodes per axis: every 5th of 64 (0, 5, ..., 60: 13 nodes) and every 1st of 9.
  StepWinds holes = w0;
  holes.u[g.index(20, 4, 1)] = std::numeric_limits<float>::quiet_NaN();  // counts as calm
  const AngularFlow c = angular_flow(g, holes, holes, 0.0, 16);
  ASSERT_EQ(c.lon_deg.count, 13);
  EXPECT_DOUBLE_EQ(c.lon_deg.step, 2.5);
  EXPECT_DOUBLE_EQ(c.lon_deg.start, 0.0);
  EXPECT_EQ(c.lat_deg.count, 9);
  const double r1 = g.earth_radius_m + g.alt_m.at(1);
  const std::size_t q4 = (std::size_t(1) * 9 + 4) * 13 + 4;  // coarse node 4 = fine node 20: fine nodes 18..22
  EXPECT_NEAR(c.deg_per_s[2 * q4], 0.8 * 10.0 / r1 * 180.0 / kPi, 1e-10) << "one of the five nodes averaged is calm";
  EXPECT_NEAR(c.deg_per_s[2 * (q4 + 1)], 10.0 / r1 * 180.0 / kPi, 1e-10);

  EXPECT_TRUE(angular_flow(g, w0, StepWinds{}, 0.5).empty());
  EXPECT_TRUE(angular_flow(g, StepWinds{}, w1, 0.5).empty());
}

TEST(Instant, FallsBetweenStepsAndNamesTheRangeWhenOutside) {
  const auto times = three_hourly(6);
  EXPECT_EQ(times[1].iso_utc, "2024-01-15T03:00:00Z");
  const Instant at = instant_at_time(times, "2024-01-15T04:30:00Z", "f.nc");
  EXPECT_EQ(at.step0, 1u);
  EXPECT_EQ(at.step1, 2u);
  EXPECT_DOUBLE_EQ(at.fraction, 0.5);
  EXPECT_DOUBLE_EQ(at.gap_s, 10800.0);
  EXPECT_EQ(at.iso_utc, "2024-01-15T04:30:00Z");
  EXPECT_TRUE(at.between());
  const Instant on = instant_at_time(times, "2024-01-15T06:00:00Z", "f.nc");
  EXPECT_FALSE(on.between());
  EXPECT_EQ(on.step0, 2u);
  EXPECT_FALSE(instant_at_time(times, "2024-01-15T15:00:00Z", "f.nc").between());  // the last step
  try {
    instant_at_time(times, "2024-01-16T00:00:00Z", "f.nc");
    FAIL() << "no error";
  } catch (const TimeError& e) {
    EXPECT_STREQ(e.what(), "f.nc: time 2024-01-16T00:00:00Z is outside the file's times 2024-01-15T00:00:00Z .. "
                           "2024-01-15T15:00:00Z (6 steps), expected an instant within them");
  }
  EXPECT_THROW(instant_at_step(times, 6, "f.nc"), TimeError);
  EXPECT_THROW(instant_at_time(times, "tomorrow", "f.nc"), TimeError);
}

TEST(Instant, ADuplicateOrBackwardTimeIsAnErrorNamingTheValues) {
  auto times = three_hourly(4);
  times[2] = times[1];
  try {
    instant_at_time(times, "2024-01-15T01:00:00Z", "dup.nc");
    FAIL() << "no error";
  } catch (const TimeError& e) {
    EXPECT_STREQ(e.what(), "dup.nc: the valid times are duplicated: step 1 is 2024-01-15T03:00:00Z and step 2 is "
                           "2024-01-15T03:00:00Z, expected strictly ascending times");
  }
  times = three_hourly(4);
  std::swap(times[0], times[3]);
  EXPECT_THROW(check_time_axis(times, "back.nc"), TimeError);
}

TEST(Instant, AOneStepFileHoldsOnlyItsStep) {
  const auto times = three_hourly(1);
  EXPECT_FALSE(instant_at_time(times, "2024-01-15T00:00:00Z", "one.nc").between());
  EXPECT_THROW(instant_at_time(times, "2024-01-15T00:30:00Z", "one.nc"), TimeError);
  const std::vector<ValidTime> labels = {{0, "0"}, {1, "1"}};  // a file without a time axis
  EXPECT_THROW(instant_at_time(labels, "2024-01-15T00:00:00Z", "bare.nc"), TimeError);
  EXPECT_FALSE(instant_at_step(labels, 1, "bare.nc").time_known);
}

TEST(SceneTime, KeysAreReadCheckedAndWritten) {
  const Scene s = scene_from_json(R"({"version": 1, "time": {"valid_utc": "2024-01-15T04:30:00Z", "interpolation": "nearest"}})");
  EXPECT_EQ(s.time.valid_utc, "2024-01-15T04:30:00Z");
  EXPECT_EQ(s.time.interpolation, TimeInterpolation::Nearest);
  EXPECT_EQ(scene_from_json(R"({"version": 1})").time.interpolation, TimeInterpolation::Auto);
  try {
    scene_from_json(R"({"version": 1, "time": {"interpolation": "cubic"}})", "s.json");
    FAIL() << "no error";
  } catch (const SceneError& e) {
    EXPECT_STREQ(e.what(), "s.json: time.interpolation: found \"cubic\", expected \"auto\", \"nearest\", \"linear\" or \"advected\"");
  }
  EXPECT_THROW(scene_from_json(R"({"version": 1, "time": {"valid_utc": "noon"}})"), SceneError);
  EXPECT_THROW(scene_from_json(R"({"version": 1, "time": {"when": 3}})"), SceneError);
  EXPECT_EQ(scene_from_json(R"({"version": 1, "sun": {"mode": "local_noon"}})").sun.mode, SunMode::LocalNoon);
}

}  // namespace
}  // namespace cv::core
