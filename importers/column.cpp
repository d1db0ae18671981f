// The per-column physics of the conversion.
#include "column.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "importer.hpp"

namespace cv::importers {
namespace {
constexpr double kRhoWater = 1000.0;  // kg/m3
constexpr double kRhoIce = 917.0;     // kg/m3
// A cloud fraction below this is zero to within int16 packing (whose step is ~1.5e-5 over 0..1).
constexpr double kZeroCloudFraction = 1e-4;
// Water below this counts as none for the consistency checks: int16 packing leaves a step or two
// (~5e-8 kg/kg) where there is none, and 1e-7 kg/kg gives an optical depth of ~0.015 per km.
constexpr double kZeroWater = 1e-7;
// Water in a box whose fraction is zero gets this fraction, keeping the box's mean water.
constexpr double kRaisedCloudFraction = 0.01;
const double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string fmt(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.6g", v);
  return b;
}
}  // namespace

void place_column(std::span<LevelSample> levels, const core::VolumeGrid& grid, int x, int y,
                  const ConversionOptions& options, core::TimeStepData& out, ColumnCounts& counts) {
  const int n = static_cast<int>(levels.size());
  // Per level: SI quantities in the order of core::Field (a per-thread buffer, reused).
  thread_local std::vector<double> buffer;
  buffer.resize(static_cast<std::size_t>(core::kFieldCount) * static_cast<std::size_t>(n));
  auto q = [&](int f) { return buffer.data() + static_cast<std::size_t>(f) * static_cast<std::size_t>(n); };
  for (int l = 0; l < n; ++l) {
    LevelSample& s = levels[static_cast<std::size_t>(l)];
    const double rho = s.p_pa / (kRdJPerKgK * s.t_k * (1.0 + 0.608 * s.qv));
    const double total = (std::isnan(s.q_liquid) ? 0.0 : s.q_liquid) + (std::isnan(s.q_ice) ? 0.0 : s.q_ice);
    // Grid-box mean to in-cloud: divide by the cloud fraction where it is non-zero.
    double div = 1.0;
    if (!std::isnan(s.cf)) {
      if (total > kZeroWater && s.cf < kZeroCloudFraction) {
        ++counts.water_without_cf;
        counts.most_water_without_cf = std::max(counts.most_water_without_cf, total);
        s.cf = kRaisedCloudFraction;  // keeps the box's mean water (and optical depth)
      }
      if (s.cf > 0.1 && total <= kZeroWater) ++counts.cf_without_water;
      div = std::max(s.cf, kZeroCloudFraction);
    }
    const double r_liq_m = options.r_eff_liquid_um * 1e-6;
    const double r_ice_m = (options.r_eff_ice_um > 0 ? options.r_eff_ice_um : ice_effective_radius_um(s.t_k)) * 1e-6;
    q(static_cast<int>(core::Field::ExtinctionLiquid))[l] =
        std::isnan(s.q_liquid) ? kNaN : 3.0 * rho * s.q_liquid / div / (2.0 * kRhoWater * r_liq_m);
    q(static_cast<int>(core::Field::ExtinctionIce))[l] =
        std::isnan(s.q_ice) ? kNaN : 3.0 * rho * s.q_ice / div / (2.0 * kRhoIce * r_ice_m);
    q(static_cast<int>(core::Field::CloudFraction))[l] = s.cf;
    q(static_cast<int>(core::Field::WindU))[l] = s.u;
    q(static_cast<int>(core::Field::WindV))[l] = s.v;
    q(static_cast<int>(core::Field::WindW))[l] = s.w;
    q(static_cast<int>(core::Field::Temperature))[l] = s.t_k;
  }
  for (int l = 1; l < n; ++l) {
    if (!(levels[static_cast<std::size_t>(l)].z_m > levels[static_cast<std::size_t>(l - 1)].z_m)) ++counts.nonmonotonic;
  }
  // Linear interpolation in altitude; outside the column's levels: no data.
  int l = 1;
  for (int z = 0; z < grid.alt_m.count; ++z) {
    const double alt = grid.alt_m.at(z);
    while (l < n && !(levels[static_cast<std::size_t>(l)].z_m >= alt)) ++l;
    if (l >= n) break;
    const double z0 = levels[static_cast<std::size_t>(l - 1)].z_m, z1 = levels[static_cast<std::size_t>(l)].z_m;
    if (!(z0 <= alt) || !(z1 > z0)) continue;
    const double a = (alt - z0) / (z1 - z0);
    const std::size_t p = grid.index(x, y, z);
    for (int f = 0; f < core::kFieldCount; ++f) {
      auto& dst = out.fields[static_cast<std::size_t>(f)];
      if (dst.empty()) continue;
      const double* qf = q(f);
      dst[p] = static_cast<float>(qf[l - 1] + a * (qf[l] - qf[l - 1]));
    }
  }
}

bool in_time_range(const core::ValidTime& t, const ImportOptions& o) {
  return (o.time_from_iso.empty() || t.iso_utc >= o.time_from_iso) && (o.time_to_iso.empty() || t.iso_utc <= o.time_to_iso);
}

void report_counts(const ColumnCounts& c, int t, core::ImportReport& report) {
  const std::string at = " at time step " + std::to_string(t);
  if (c.water_without_cf) {
    report.warn(std::to_string(c.water_without_cf) + " points with cloud water (up to " + fmt(c.most_water_without_cf) +
                " kg/kg) but zero cloud fraction" + at + ": fraction raised to 0.01, grid-box mean water kept");
  }
  if (c.cf_without_water) {
    report.warn(std::to_string(c.cf_without_water) + " points with cloud fraction above 0.1 but no cloud water" + at);
  }
  if (c.nonmonotonic) report.warn(std::to_string(c.nonmonotonic) + " level pairs whose heights do not rise with the level" + at);
}

}  // namespace cv::importers
