// The modelled cloud's detail carried by the wind (issue 18, item 3; core/kernel/detail_drift and
// march.glsl detail_factor; docs/physics.md "The detail moves with the wind"):
// - a level's rate is the angular rate of the wind where the cloud is, and finite without data;
// - the displacement is the time integral of the rate, linear in time between steps: continuous,
//   with the interpolated wind's rate at every instant;
// - the noise pattern the kernel draws moves between two instants as far as the wind carries the
//   air, measured by cross-correlating the pattern at the two instants, level by level.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <vector>

#include "kernel/detail_drift.hpp"
#include "kernel/march_kernel.hpp"
#include "kernel/prepared_volume.hpp"
#include "kernel/volume_cache.hpp"
#include "noise/noise.hpp"
#include "scene/instant.hpp"

namespace cv::core {
namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;
constexpr double kR = 6371000.0;

// 21 x 13 columns of 0.5 degree at 40-46 N, 5 levels 1 km apart.
VolumeGrid box() {
  VolumeGrid g;
  g.lon_deg = {10.0, 0.5, 21};
  g.lat_deg = {40.0, 0.5, 13};
  g.alt_m = {0.0, 1000.0, 5};
  return g;
}

// A step with cloud fraction `cf` and liquid extinction 1e-3 /m on levels 1-3 (or only on row
// `row` when row >= 0), winds (u[k], v[k]) on level k.
TimeStepData step(const VolumeGrid& g, const std::vector<double>& u, const std::vector<double>& v, double cf = 0.5, int row = -1) {
  TimeStepData d;
  d[Field::CloudFraction].assign(g.points(), float(cf));
  d[Field::ExtinctionLiquid].assign(g.points(), 0.0f);
  d[Field::WindU].assign(g.points(), 0.0f);
  d[Field::WindV].assign(g.points(), 0.0f);
  for (int k = 0; k < g.alt_m.count; ++k)
    for (int j = 0; j < g.lat_deg.count; ++j)
      for (int i = 0; i < g.lon_deg.count; ++i) {
        const std::size_t p = g.index(i, j, k);
        if (k >= 1 && k <= 3 && (row < 0 || j == row)) d[Field::ExtinctionLiquid][p] = 1e-3f;
        d[Field::WindU][p] = float(u[std::size_t(k)]);
        d[Field::WindV][p] = float(v[std::size_t(k)]);
      }
  return d;
}

std::vector<ValidTime> hours(std::initializer_list<int> h) {
  std::vector<ValidTime> t;
  const std::int64_t base = 1704067200;  // 2024-01-01T00:00:00Z
  for (int x : h) t.push_back({base + 3600 * std::int64_t(x), format_iso_utc(base + 3600 * std::int64_t(x))});
  return t;
}

TEST(DetailDrift, ALevelsRateIsTheAngularRateOfTheCloudyAir) {
  const VolumeGrid g = box();
  // Cloud only on row 6 (43 N), where the wind is 30 m/s east and 12 m/s south; calm elsewhere.
  TimeStepData d = step(g, {0, 0, 0, 0, 0}, {0, 0, 0, 0, 0}, 0.5, 6);
  for (int k = 0; k < g.alt_m.count; ++k)
    for (int i = 0; i < g.lon_deg.count; ++i) d[Field::WindU][g.index(i, 6, k)] = 30.0f, d[Field::WindV][g.index(i, 6, k)] = -12.0f;
  const std::vector<double> r = level_drift_rate(g, d);
  ASSERT_EQ(r.size(), 10u);
  const double step = 0.5 * kDeg;
  for (int k = 1; k <= 3; ++k) {
    EXPECT_NEAR(r[2 * k], 30.0 / (kR * std::cos(43.0 * kDeg)) / step, 1e-12 * std::abs(r[2 * k])) << "level " << k;
    EXPECT_NEAR(r[2 * k + 1], -12.0 / kR / step, 1e-12 * std::abs(r[2 * k + 1])) << "level " << k;
  }
  // Levels without cloud take the area's mean: the wind on row 6 over 13 rows, between the bounds
  // the rows' latitudes give.
  for (int k : {0, 4}) {
    EXPECT_GT(r[2 * k], 30.0 / 13.0 / (kR * std::cos(40.0 * kDeg)) / step) << "level " << k;
    EXPECT_LT(r[2 * k], 30.0 / 13.0 / (kR * std::cos(46.0 * kDeg)) / step) << "level " << k;
  }
}

TEST(DetailDrift, WithoutWindsOrWithBadWindsTheRateIsFiniteOrZero) {
  const VolumeGrid g = box();
  TimeStepData none = step(g, {1, 1, 1, 1, 1}, {1, 1, 1, 1, 1});
  none[Field::WindU].clear();
  for (double r : level_drift_rate(g, none)) EXPECT_EQ(r, 0.0);
  TimeStepData bad = step(g, {10, 10, 10, 10, 10}, {0, 0, 0, 0, 0});
  bad[Field::WindU][g.index(3, 3, 2)] = std::numeric_limits<float>::quiet_NaN();
  bad[Field::WindU][g.index(4, 3, 2)] = 9.96921e36f;  // netCDF's fill value
  bad[Field::WindV][g.index(5, 3, 2)] = -std::numeric_limits<float>::infinity();
  bad[Field::ExtinctionLiquid][g.index(6, 3, 2)] = std::numeric_limits<float>::quiet_NaN();
  const std::vector<double> r = level_drift_rate(g, bad), clean = level_drift_rate(g, step(g, {10, 10, 10, 10, 10}, {0, 0, 0, 0, 0}));
  for (std::size_t i = 0; i < r.size(); ++i) {
    EXPECT_TRUE(std::isfinite(r[i])) << i;
    EXPECT_NEAR(r[i], clean[i], 0.02 * std::abs(clean[i]) + 1e-15) << "the bad nodes are left out, " << i;
  }
}

// Three steps at 0, 3 and 9 h with uniform east winds of 10, 20 and 0 m/s, all on row 6's cloud.
struct ThreeSteps {
  VolumeGrid g = box();
  CloudVolume vol;
  double rate[3] = {};
  ThreeSteps() {
    vol.grid = g;
    vol.times = hours({0, 3, 9});
    const double u[3] = {10.0, 20.0, 0.0};
    for (int s = 0; s < 3; ++s) {
      vol.put(std::size_t(s), step(g, std::vector<double>(5, u[s]), std::vector<double>(5, 0.0), 0.5, 6));
      rate[s] = u[s] / (kR * std::cos(43.0 * kDeg)) / (0.5 * kDeg);
    }
  }
  Instant at(const char* iso) { return instant_at_time(vol.times, iso, "three steps"); }
};

TEST(DetailDrift, TheDisplacementIsTheIntegralOfTheInterpolatedRate) {
  ThreeSteps t;
  DetailDrift drift;
  const double h = 3600.0;
  const double at1 = 0.5 * (t.rate[0] + t.rate[1]) * 3 * h;  // the trapezoid is exact for a rate linear in time
  const double at2 = at1 + 0.5 * (t.rate[1] + t.rate[2]) * 6 * h;
  EXPECT_EQ(drift.at(t.vol, t.at("2024-01-01T00:00:00Z"))[2], 0.0) << "the first step is the origin";
  EXPECT_NEAR(drift.at(t.vol, t.at("2024-01-01T03:00:00Z"))[2], at1, 1e-9 * at1);
  EXPECT_NEAR(drift.at(t.vol, t.at("2024-01-01T09:00:00Z"))[2], at2, 1e-9 * at2);
  // Inside the second gap, 1.5 h in (fraction 1/4): 6 h x (f r1 + f^2 (r2 - r1) / 2).
  const double f = 0.25, inside = at1 + 6 * h * (f * t.rate[1] + 0.5 * f * f * (t.rate[2] - t.rate[1]));
  EXPECT_NEAR(drift.at(t.vol, t.at("2024-01-01T04:30:00Z"))[2], inside, 1e-9 * inside);
  // Continuous at a step, and moving at the interpolated rate: one second before and after step 1.
  const double before = drift.at(t.vol, t.at("2024-01-01T02:59:59Z"))[2], after = drift.at(t.vol, t.at("2024-01-01T03:00:01Z"))[2];
  EXPECT_NEAR(after - before, 2.0 * t.rate[1], 1e-3 * t.rate[1]) << "no jump at a step";
  // The other levels' cloud is the same row: the same rate; northward nothing.
  const std::vector<double> d = drift.at(t.vol, t.at("2024-01-01T09:00:00Z"));
  for (int k = 1; k <= 3; ++k) EXPECT_NEAR(d[2 * k], at2, 1e-9 * at2);
  for (int k = 0; k < 5; ++k) EXPECT_EQ(d[2 * k + 1], 0.0);
}

// The prepared media the viewer's cache makes carry their instant, and an advected one the winds'
// angular flow at it (the data mode's reprojection moves its history by it); a linear blend, which
// moves nothing, carries none.
TEST(DetailDrift, TheCachesMediaCarryTheirInstantAndAnAdvectedOneItsFlow) {
  ThreeSteps t;
  PreparedVolumeCache cache;
  const Instant at = t.at("2024-01-01T01:30:00Z");  // half-way between 10 and 20 m/s
  const auto advected = cache.get("three steps", t.vol, at, TimeInterpolation::Advected);
  EXPECT_DOUBLE_EQ(advected->time_s, 1704067200.0 + 5400.0);
  ASSERT_FALSE(advected->flow.empty());
  const std::size_t q = (std::size_t(2) * 13 + 6) * 21 + 10;  // level 2, 43 N, every node kept
  EXPECT_NEAR(advected->flow.deg_per_s[2 * q] * ((kR + 2000.0) * std::cos(43.0 * kDeg)) * kDeg, 15.0, 15.0 * 1e-6);  // float
  EXPECT_EQ(advected->flow.deg_per_s[2 * q + 1], 0.0f);
  const auto linear = cache.get("three steps", t.vol, at, TimeInterpolation::Linear);
  EXPECT_DOUBLE_EQ(linear->time_s, 1704067200.0 + 5400.0);
  EXPECT_TRUE(linear->flow.empty());
  const auto step = cache.get("three steps", t.vol, std::size_t(1));
  EXPECT_DOUBLE_EQ(step->time_s, 1704067200.0 + 3 * 3600.0);
  EXPECT_TRUE(step->flow.empty());
}

TEST(DetailDrift, AFileWithoutTimesStaysStill) {
  ThreeSteps t;
  t.vol.times = {{0, "0"}, {1, "1"}, {2, "2"}};  // step labels, no UTC valid times
  DetailDrift drift;
  Instant at;
  at.step0 = at.step1 = 2;
  for (double x : drift.at(t.vol, at)) EXPECT_EQ(x, 0.0);
}

// The kernel's modelled-cloud factor over a prepared volume (march.glsl detail_factor), with the
// volume's shift texture, as the march and the Monte Carlo read it.
struct DetailField {
  std::shared_ptr<const PreparedVolume> v;
  std::vector<float> shift;
  kernel::f64::MarchKernel k;
  DetailField(std::shared_ptr<const PreparedVolume> volume, const ErosionNoise& noise, double scale_m) : v(std::move(volume)) {
    MarchSettings s;
    s.medium.modelled = true;
    s.medium.detail_scale_m = scale_m;
    Camera cam;
    cam.width = cam.height = 1;
    static_cast<kernel::MarchParams&>(k) = march_params(*v, cam, Sun{}, s, glm::ivec2(0));
    const VolumeGrid& g = v->grid;
    const glm::ivec3 n(g.lon_deg.count, g.lat_deg.count, g.alt_m.count);
    k.u_liquid = {v->extinction.liquid_per_m.data(), n};
    k.u_ice = {v->extinction.ice_per_m.data(), n};
    k.u_fraction = {v->extinction.fraction.data(), n};
    k.u_column_tau = {v->column_maps.data(), {v->columns.nx, v->columns.ny, int(kColumnMapLayers)}, int(kColumnMapChannels)};
    k.u_noise_low = {noise.low.texels.data(), glm::ivec3(noise.low.n)};
    k.u_noise_high = {noise.high.texels.data(), glm::ivec3(noise.high.n)};
    k.u_detail_table = {noise.detail.data(), {CV_DETAIL_COVERS + 1, CV_DETAIL_ROWS}, 2};
    shift = detail_shift_texels(*v, k);
    k.u_detail_shift = {shift.data(), {g.alt_m.count, 1}, 2};
    k.kModelled = true;
  }
};

// The pattern's displacement (grid cells, x and y) from a to b on level z, in cell (6, 6): a
// cell holds one tile here, so the pattern repeats every cell and the two instants must lie less
// than half a tile apart. The peak of the circular cross-correlation over a lattice of n x n points,
// refined by a parabola through the peak and its neighbours.
glm::dvec2 displacement(DetailField& a, DetailField& b, int z, int n = 64) {
  std::vector<double> pa(std::size_t(n * n)), pb(std::size_t(n * n));
  double ma = 0.0, mb = 0.0;
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const glm::dvec3 f(6.0 + (x + 0.5) / n, 6.0 + (y + 0.5) / n, double(z));
      pa[std::size_t(y * n + x)] = a.k.detail_factor(f);
      pb[std::size_t(y * n + x)] = b.k.detail_factor(f);
      ma += pa[std::size_t(y * n + x)], mb += pb[std::size_t(y * n + x)];
    }
  ma /= n * n, mb /= n * n;
  std::vector<double> c(std::size_t(n * n), 0.0);
  int best = 0;
  for (int sy = 0; sy < n; ++sy)
    for (int sx = 0; sx < n; ++sx) {
      double sum = 0.0;  // b(x + s) against a(x): the shift that carries a onto b
      for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) sum += (pa[std::size_t(y * n + x)] - ma) * (pb[std::size_t(((y + sy) % n) * n + (x + sx) % n)] - mb);
      c[std::size_t(sy * n + sx)] = sum;
      if (sum > c[std::size_t(best)]) best = sy * n + sx;
    }
  const int bx = best % n, by = best / n;
  auto at = [&](int x, int y) { return c[std::size_t(((y + n) % n) * n + (x + n) % n)]; };
  auto vertex = [](double l, double m, double r) { const double d = l - 2.0 * m + r; return d < 0.0 ? 0.5 * (l - r) / d : 0.0; };
  const double dx = bx + vertex(at(bx - 1, by), at(bx, by), at(bx + 1, by));
  const double dy = by + vertex(at(bx, by - 1), at(bx, by), at(bx, by + 1));
  auto wrap = [&](double s) { return (s > 0.5 * n ? s - n : s) / n; };  // to (-half, half] of a tile, in cells
  return {wrap(dx), wrap(dy)};
}

TEST(DetailDrift, TheNoisePatternMovesWithTheWind) {
  // Uniform cloud (fraction 0.5) at 40-46 N; levels 1-2 blow 15 m/s east and 10 m/s south, level 3
  // 20 m/s west; two steps an hour apart with the same winds. Tiles of 40 km: one per 0.5 degree
  // cell along each axis.
  const VolumeGrid g = box();
  const std::vector<double> u = {15, 15, 15, -20, -20}, v = {-10, -10, -10, 0, 0};
  CloudVolume vol;
  vol.grid = g;
  vol.times = hours({0, 1});
  vol.put(0, step(g, u, v));
  vol.put(1, step(g, u, v));
  ErosionNoise noise = make_erosion_noise();
  with_detail_table(noise);
  PreparedVolumeCache cache;
  // Seven instants 10 minutes apart: each interval moves the pattern less than half a tile, and the
  // intervals' displacements add up over the hour.
  glm::dvec2 total[2] = {{0, 0}, {0, 0}};
  std::unique_ptr<DetailField> prev;
  for (int m = 0; m <= 60; m += 10) {
    char iso[32];
    std::snprintf(iso, sizeof iso, "2024-01-01T%02d:%02d:00Z", m / 60, m % 60);
    const Instant at = instant_at_time(vol.times, iso, "drift test");
    auto field = std::make_unique<DetailField>(cache.get("drift test", vol, at, TimeInterpolation::Linear, nullptr, true), noise, 40000.0);
    ASSERT_EQ(field->k.u_detail_tiles.x, 1.0);
    ASSERT_EQ(field->k.u_detail_tiles.y, 1.0);
    if (prev) {
      total[0] += displacement(*prev, *field, 2);
      total[1] += displacement(*prev, *field, 3);
    }
    prev = std::move(field);
  }
  // The wind's displacement over the hour at the measured cell's latitude (43.25 N), in metres,
  // against the pattern's (cells x the cell's size there).
  const double lat = 43.25 * kDeg, cell_x = 0.5 * kDeg * kR * std::cos(lat), cell_y = 0.5 * kDeg * kR;
  for (int l = 0; l < 2; ++l) {
    const int k = l == 0 ? 2 : 3;
    const glm::dvec2 pattern_m(total[l].x * cell_x, total[l].y * cell_y), wind_m(u[std::size_t(k)] * 3600.0, v[std::size_t(k)] * 3600.0);
    std::printf("level %d: the pattern moved %.2f km east, %.2f km north in an hour; the wind %.2f km, %.2f km\n", k,
                pattern_m.x / 1e3, pattern_m.y / 1e3, wind_m.x / 1e3, wind_m.y / 1e3);
    // Within 2 % of the wind's way plus 1/64 of a cell per interval (the lattice) on each axis; the
    // level's one angular rate is exact at the cloud's mean latitude (43 N) and 0.4 % off here.
    EXPECT_NEAR(pattern_m.x, wind_m.x, 0.02 * std::abs(wind_m.x) + 6.0 * cell_x / 64.0) << "level " << k;
    EXPECT_NEAR(pattern_m.y, wind_m.y, 0.02 * std::abs(wind_m.y) + 6.0 * cell_y / 64.0) << "level " << k;
  }
  // Without the drift (the data mode's preparation) the detail stands still: 10 minutes apart, the same pattern.
  DetailField a(cache.get("drift test", vol, instant_at_time(vol.times, "2024-01-01T00:00:00Z", "t"), TimeInterpolation::Linear), noise, 40000.0);
  DetailField b(cache.get("drift test", vol, instant_at_time(vol.times, "2024-01-01T00:10:00Z", "t"), TimeInterpolation::Linear), noise, 40000.0);
  const glm::dvec2 still = displacement(a, b, 2);
  EXPECT_NEAR(still.x, 0.0, 1e-9);
  EXPECT_NEAR(still.y, 0.0, 1e-9);
}

}  // namespace
}  // namespace cv::core
