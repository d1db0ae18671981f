// The conversion of a row of model columns (place_row) against the formulas, node by node, on a
// row wide enough for its vector path: columns in blocks of 1 to 9 that share their level heights,
// so a layer's nodes fall into runs of every length between the same level pair, with missing
// water, missing and vanishing fractions, and a column whose top levels have no height.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "column.hpp"

namespace {
using namespace cv;
using importers::RowLevels;

constexpr int kColumns = 46, kLevels = 6;
const double kNaN = std::numeric_limits<double>::quiet_NaN();

// The block of column x (blocks of 1, 2, 3, ..., 9 columns) and the heights its levels share.
int block_of(int x) {
  int b = 0, start = 0;
  while (start + b + 1 <= x) start += ++b;
  return b;
}
double height(int l, int x) {
  if (x == kColumns - 1 && l >= 4) return kNaN;  // the last column's top levels: no height
  return 1000.0 * l + 90.0 * block_of(x);
}

// Values that reach each branch of the in-cloud ratio, one after another along the row.
double fraction(int l, int x) {
  const double f[] = {0.3, kNaN, 0.0, 1.0, 5e-5, 0.7, 0.45};
  return f[(3 * l + x) % 7];
}
double liquid(int l, int x) {
  const double q[] = {2e-4, 0.0, kNaN, 1e-4, 3e-5};
  return q[(l + 2 * x) % 5];
}

bool same(float got, double want, double rel) {
  if (std::isnan(want)) return std::isnan(got);
  return std::fabs(static_cast<double>(got) - want) <= rel * std::fabs(want);
}

TEST(PlaceRow, EveryNodeIsTheFormulasOnRunsOfEveryLength) {
  RowLevels r;
  r.resize(kColumns, kLevels);
  for (int l = 0; l < kLevels; ++l) {
    for (int x = 0; x < kColumns; ++x) {
      const std::size_t i = r.at(l, x);
      r.z_m[i] = height(l, x);
      r.p_pa[i] = 100000.0 * std::exp(-(1000.0 * l + 90.0 * block_of(x)) / 8000.0);
      r.t_k[i] = 290.0 - 6.0 * l + 0.25 * x;
      r.qv[i] = 0.001 * (kLevels - l);
      r.cf[i] = fraction(l, x);
      r.q_liquid[i] = liquid(l, x);
      r.q_ice[i] = kNaN, r.u[i] = kNaN, r.v[i] = kNaN, r.w[i] = kNaN;
    }
  }
  core::VolumeGrid grid;
  grid.lon_deg = {0.0, 1.0, kColumns};
  grid.lat_deg = {10.0, 1.0, 1};
  grid.alt_m = {0.0, 137.0, 42};  // nodes from the ground to above the highest level
  core::TimeStepData out;
  for (core::Field f : {core::Field::ExtinctionLiquid, core::Field::CloudFraction, core::Field::Temperature, core::Field::Pressure}) {
    out[f].assign(grid.points(), -1.0f);
  }
  importers::ColumnCounts counts;
  importers::StoredStats stored;
  importers::place_row(r, grid, 0, 0, importers::ConversionOptions{}, out, counts, &stored);

  // The box extinction of the mean water (zero where the fraction says no cloud holds it).
  auto box_extinction = [&](int l, int x) {
    const std::size_t i = r.at(l, x);
    const double q = r.q_liquid[i], cf = r.cf[i];
    if (std::isnan(q)) return kNaN;
    if (!std::isnan(cf) && q > 0.0 && cf < importers::kZeroCloudFraction) return 0.0;
    const double rho = r.p_pa[i] / (287.05 * r.t_k[i] * (1.0 + 0.608 * r.qv[i]));
    return 3.0 * rho * q / (2.0 * 1000.0 * 10e-6);
  };
  std::size_t with_data = 0, in_cloud = 0, dropped = 0, runs_of_four = 0;
  for (int x = 0; x < kColumns; ++x) {
    for (int l = 0; l < kLevels; ++l) {
      const double q = r.q_liquid[r.at(l, x)], cf = r.cf[r.at(l, x)];
      if (!std::isnan(cf) && q > 0.0 && cf < importers::kZeroCloudFraction) ++dropped;
    }
  }
  for (int z = 0; z < grid.alt_m.count; ++z) {
    int run = 0, last_level = -2;
    for (int x = 0; x < kColumns; ++x) {
      const double alt = grid.alt_m.at(z);
      int level = -1;
      for (int l = 1; l < kLevels; ++l) {
        if (height(l - 1, x) <= alt && alt <= height(l, x)) {
          level = l;
          break;
        }
      }
      run = level == last_level ? run + 1 : 1;
      last_level = level;
      if (run == 4 && level > 0) ++runs_of_four;
      const std::size_t n = grid.index(x, 0, z);
      const float t = out[core::Field::Temperature][n], f = out[core::Field::CloudFraction][n];
      const float e = out[core::Field::ExtinctionLiquid][n], p = out[core::Field::Pressure][n];
      if (level < 0) {
        EXPECT_TRUE(std::isnan(t) && std::isnan(f) && std::isnan(e) && std::isnan(p)) << "x " << x << " z " << z;
        continue;
      }
      ++with_data;
      const double z0 = height(level - 1, x), a = (alt - z0) / (height(level, x) - z0);
      auto lerp = [&](const std::vector<double>& v) {
        const double v0 = v[r.at(level - 1, x)];
        return v0 + a * (v[r.at(level, x)] - v0);
      };
      // Temperature and fraction are the linear interpolation itself, to the float's rounding.
      EXPECT_EQ(t, static_cast<float>(lerp(r.t_k))) << "x " << x << " z " << z;
      const double cf = lerp(r.cf);
      if (std::isnan(cf)) EXPECT_TRUE(std::isnan(f)) << "x " << x << " z " << z;
      else EXPECT_EQ(f, static_cast<float>(cf)) << "x " << x << " z " << z;
      // Pressure in its logarithm: p0 (p1 / p0)^a.
      const double p0 = r.p_pa[r.at(level - 1, x)], p1 = r.p_pa[r.at(level, x)];
      EXPECT_TRUE(same(p, p0 * std::pow(p1 / p0, a), 1e-6)) << "x " << x << " z " << z << ": " << p;
      // In-cloud extinction: the interpolated box extinction over the interpolated fraction.
      const double e0 = box_extinction(level - 1, x), box = e0 + a * (box_extinction(level, x) - e0);
      double want = box;
      if (!std::isnan(cf)) want = box > 0.0 && cf > 0.0 ? box / cf : (std::isnan(box) ? box : 0.0);
      if (want > 0.0) ++in_cloud;
      EXPECT_TRUE(same(e, want, 1e-6)) << "x " << x << " z " << z << ": " << e << " against " << want;
    }
  }
  // The row exercised what it was built for.
  EXPECT_GT(with_data, 1000u);
  EXPECT_GT(in_cloud, 200u);
  EXPECT_GT(runs_of_four, 50u);
  EXPECT_EQ(counts.water_without_cf, dropped);
  EXPECT_GT(dropped, 0u);
  EXPECT_EQ(stored[static_cast<std::size_t>(core::Field::Temperature)].count, with_data);
}

}  // namespace

// Ice extinction takes the effective radius of its box's temperature (20 um at -60 C and below, 50
// um at 0 C and above, linear between) or the radius the options fix, and liquid the droplets'
// radius, on a row whose 135 level samples leave three after the vector path's blocks of four
// (those three set apart: missing ice, a box with water but no fraction, a missing fraction with
// a temperature on the radius's ramp); boxes with water but no fraction keep none.
TEST(PlaceRow, IceExtinctionTakesTheRadiusOfItsBoxesTemperature) {
  constexpr int kCols = 45, kLev = 3;
  RowLevels r;
  r.resize(kCols, kLev);
  for (int l = 0; l < kLev; ++l) {
    for (int x = 0; x < kCols; ++x) {
      const std::size_t i = r.at(l, x);
      r.z_m[i] = 1000.0 * l;
      r.p_pa[i] = 90000.0 - 20000.0 * l;
      r.t_k[i] = 190.0 + 2.5 * x + 3.0 * l;  // 190 to 306 K: both ends of the clamp and the ramp
      r.qv[i] = 0.0005;
      const double f[] = {0.6, 1.0, kNaN, 5e-5, 0.25};
      r.cf[i] = f[(x + l) % 5];
      const double q[] = {3e-5, kNaN, 1e-4, 0.0, 7e-6, 2e-4};
      r.q_ice[i] = q[(2 * x + l) % 6];
      const double ql[] = {1e-4, 0.0, 4e-5, kNaN, 2e-5, 3e-4, 6e-6};
      r.q_liquid[i] = ql[(x + 2 * l) % 7];
      r.u[i] = kNaN, r.v[i] = kNaN, r.w[i] = kNaN;
    }
  }
  // The scalar remainder: the last three samples (top level, columns 42-44), and below them
  // water and a fraction, so the nodes on the top level take these samples' values.
  for (int x = 42; x < kCols; ++x) {
    const std::size_t below = r.at(1, x), top = r.at(2, x);
    r.q_ice[below] = 5e-5, r.q_liquid[below] = 5e-5, r.cf[below] = 0.8;
    r.q_liquid[top] = 1e-4;
  }
  r.q_ice[r.at(2, 42)] = kNaN, r.cf[r.at(2, 42)] = 0.5, r.t_k[r.at(2, 42)] = 200.0;  // missing ice (liquid kept)
  r.q_ice[r.at(2, 43)] = 3e-5, r.cf[r.at(2, 43)] = 5e-5, r.t_k[r.at(2, 43)] = 300.0;  // water, no fraction: none kept
  r.q_ice[r.at(2, 44)] = 3e-5, r.cf[r.at(2, 44)] = kNaN, r.t_k[r.at(2, 44)] = 250.0;  // no fraction value; on the ramp
  core::VolumeGrid grid;
  grid.lon_deg = {0.0, 1.0, kCols};
  grid.lat_deg = {10.0, 1.0, 1};
  grid.alt_m = {0.0, 1000.0, kLev};  // a node on every level
  for (const double fixed_um : {0.0, 30.0}) {
    core::TimeStepData out;
    for (core::Field f : {core::Field::ExtinctionIce, core::Field::ExtinctionLiquid, core::Field::CloudFraction}) {
      out[f].assign(grid.points(), -1.0f);
    }
    importers::ColumnCounts counts;
    importers::ConversionOptions options;
    options.r_eff_ice_um = fixed_um;
    importers::place_row(r, grid, 0, 0, options, out, counts);
    std::size_t checked = 0, dropped = 0, clamped_low = 0, clamped_high = 0, in_cloud = 0;
    // The box extinction of the mean ice (or liquid), by the formula; none where the box's water
    // (ice and liquid together) has no fraction to hold it.
    auto box = [&](int l, int x, bool ice) {
      const std::size_t i = r.at(l, x);
      const double q = ice ? r.q_ice[i] : r.q_liquid[i], cf = r.cf[i], t = r.t_k[i];
      if (std::isnan(q)) return kNaN;
      const double total = (std::isnan(r.q_ice[i]) ? 0.0 : r.q_ice[i]) + (std::isnan(r.q_liquid[i]) ? 0.0 : r.q_liquid[i]);
      if (!std::isnan(cf) && total > 0.0 && cf < importers::kZeroCloudFraction) return 0.0;
      const double radius_um = !ice ? 10.0 : fixed_um > 0 ? fixed_um : std::min(50.0, std::max(20.0, 50.0 + 0.5 * (t - 273.15)));
      const double rho = r.p_pa[i] / (287.05 * t * (1.0 + 0.608 * r.qv[i]));
      return 3.0 * rho * q / (2.0 * (ice ? 917.0 : 1000.0) * radius_um * 1e-6);
    };
    for (int l = 0; l < kLev; ++l) {
      for (int x = 0; x < kCols; ++x) {
        const std::size_t i = r.at(l, x);
        const double t = r.t_k[i];
        clamped_low += t < 213.15 ? 1 : 0;
        clamped_high += t > 273.15 ? 1 : 0;
        const double total = (std::isnan(r.q_ice[i]) ? 0.0 : r.q_ice[i]) + (std::isnan(r.q_liquid[i]) ? 0.0 : r.q_liquid[i]);
        if (!std::isnan(r.cf[i]) && total > 0.0 && r.cf[i] < importers::kZeroCloudFraction) ++dropped;
        // The node on level l lies at the bottom of the pair (0, 1), or at the top of (l - 1, l).
        const int l0 = l == 0 ? 0 : l - 1, l1 = l == 0 ? 1 : l;
        const double a = l == 0 ? 0.0 : 1.0;
        const double c0 = r.cf[r.at(l0, x)], cf = c0 + a * (r.cf[r.at(l1, x)] - c0);
        for (const bool ice : {true, false}) {
          const double e0 = box(l0, x, ice), e = e0 + a * (box(l1, x, ice) - e0);
          double want = e;
          if (!std::isnan(cf)) want = e > 0.0 && cf > 0.0 ? e / cf : (std::isnan(e) ? e : 0.0);
          in_cloud += want > 0.0 ? 1 : 0;
          const float got = out[ice ? core::Field::ExtinctionIce : core::Field::ExtinctionLiquid][grid.index(x, 0, l)];
          EXPECT_TRUE(same(got, want, 1e-6)) << (ice ? "ice" : "liquid") << ", r_eff " << fixed_um << " x " << x << " level " << l
                                             << ": " << got << " against " << want;
          ++checked;
        }
      }
    }
    EXPECT_GT(in_cloud, 80u);
    // The three samples of the scalar remainder reached the nodes on the top level as set.
    EXPECT_TRUE(std::isnan(out[core::Field::ExtinctionIce][grid.index(42, 0, 2)]));
    EXPECT_GT(out[core::Field::ExtinctionLiquid][grid.index(42, 0, 2)], 0.0f);
    EXPECT_EQ(out[core::Field::ExtinctionIce][grid.index(43, 0, 2)], 0.0f);
    EXPECT_GT(out[core::Field::ExtinctionIce][grid.index(44, 0, 2)], 0.0f);
    EXPECT_EQ(checked, static_cast<std::size_t>(2 * kCols * kLev));
    EXPECT_GT(dropped, 0u);
    EXPECT_EQ(counts.water_without_cf, dropped);
    EXPECT_GT(clamped_low, 5u);
    EXPECT_GT(clamped_high, 5u);
  }
}
