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
const double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string fmt(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.6g", v);
  return b;
}
}  // namespace

void ColumnCounts::merge(const ColumnCounts& o) {
  water_without_cf += o.water_without_cf;
  water_without_cf_significant += o.water_without_cf_significant;
  cf_without_water += o.cf_without_water;
  nonmonotonic += o.nonmonotonic;
  most_water_without_cf = std::max(most_water_without_cf, o.most_water_without_cf);
}

core::RegularAxis altitude_axis(double zmin_m, double zmax_m, double dz_m, bool fit) {
  const double span = zmax_m - zmin_m;
  // Intervals needed to reach the top; a hair of tolerance so a span that is a whole number of
  // steps (to rounding) does not get one more.
  const int intervals = std::max(1, static_cast<int>(std::ceil(span / dz_m - 1e-9)));
  const double dz = fit ? span / intervals : dz_m;
  return {zmin_m, dz, intervals + 1};
}

void place_column(std::span<LevelSample> levels, const core::VolumeGrid& grid, int x, int y,
                  const ConversionOptions& options, core::TimeStepData& out, ColumnCounts& counts) {
  const int n = static_cast<int>(levels.size());
  // Per level: SI quantities in the order of core::Field (a per-thread buffer, reused). The two
  // extinctions are grid-box means here; they become in-cloud values node by node below.
  thread_local std::vector<double> buffer;
  buffer.resize(static_cast<std::size_t>(core::kFieldCount) * static_cast<std::size_t>(n));
  auto q = [&](int f) { return buffer.data() + static_cast<std::size_t>(f) * static_cast<std::size_t>(n); };
  constexpr int kLiq = static_cast<int>(core::Field::ExtinctionLiquid), kIce = static_cast<int>(core::Field::ExtinctionIce),
                kCf = static_cast<int>(core::Field::CloudFraction);
  for (int l = 0; l < n; ++l) {
    LevelSample& s = levels[static_cast<std::size_t>(l)];
    const double rho = s.p_pa / (kRdJPerKgK * s.t_k * (1.0 + 0.608 * s.qv));
    const double total = (std::isnan(s.q_liquid) ? 0.0 : s.q_liquid) + (std::isnan(s.q_ice) ? 0.0 : s.q_ice);
    // A box's water counts only where its fraction says there is cloud to hold it.
    double keep = 1.0;
    if (!std::isnan(s.cf)) {
      if (total > 0.0 && s.cf < kZeroCloudFraction) {
        ++counts.water_without_cf;
        if (total > kZeroWater) ++counts.water_without_cf_significant;
        counts.most_water_without_cf = std::max(counts.most_water_without_cf, total);
        keep = 0.0;
      }
      if (s.cf > 0.1 && total <= kZeroWater) ++counts.cf_without_water;
    }
    const double r_liq_m = options.r_eff_liquid_um * 1e-6;
    const double r_ice_m = (options.r_eff_ice_um > 0 ? options.r_eff_ice_um : ice_effective_radius_um(s.t_k)) * 1e-6;
    q(kLiq)[l] = std::isnan(s.q_liquid) ? kNaN : keep * 3.0 * rho * s.q_liquid / (2.0 * kRhoWater * r_liq_m);
    q(kIce)[l] = std::isnan(s.q_ice) ? kNaN : keep * 3.0 * rho * s.q_ice / (2.0 * kRhoIce * r_ice_m);
    q(kCf)[l] = s.cf;
    q(static_cast<int>(core::Field::WindU))[l] = s.u;
    q(static_cast<int>(core::Field::WindV))[l] = s.v;
    q(static_cast<int>(core::Field::WindW))[l] = s.w;
    q(static_cast<int>(core::Field::Temperature))[l] = s.t_k;
    // Pressure is interpolated in its logarithm (exact in an isothermal layer), turned back below.
    q(static_cast<int>(core::Field::Pressure))[l] = s.p_pa > 0.0 ? std::log(s.p_pa) : kNaN;
  }
  for (int l = 1; l < n; ++l) {
    if (!(levels[static_cast<std::size_t>(l)].z_m > levels[static_cast<std::size_t>(l - 1)].z_m)) ++counts.nonmonotonic;
  }
  const bool has_cf = !out.fields[static_cast<std::size_t>(kCf)].empty();
  // Linear interpolation in altitude; outside the column's levels: no data. A node within a
  // micrometre of the top level (the axis was fitted to end there) takes the top level's value.
  // First each node's level pair and weight, then field by field over the nodes.
  const double z_top = n > 0 ? levels[static_cast<std::size_t>(n - 1)].z_m : kNaN;
  thread_local std::vector<int> node_level;
  thread_local std::vector<double> node_weight;
  node_level.assign(static_cast<std::size_t>(grid.alt_m.count), -1);
  node_weight.resize(static_cast<std::size_t>(grid.alt_m.count));
  int l = 1;
  for (int z = 0; z < grid.alt_m.count; ++z) {
    double alt = grid.alt_m.at(z);
    if (alt > z_top && alt - z_top < 1e-6) alt = z_top;
    while (l < n && !(levels[static_cast<std::size_t>(l)].z_m >= alt)) ++l;
    if (l >= n) break;
    const double z0 = levels[static_cast<std::size_t>(l - 1)].z_m, z1 = levels[static_cast<std::size_t>(l)].z_m;
    if (!(z0 <= alt) || !(z1 > z0)) continue;
    node_level[static_cast<std::size_t>(z)] = l;
    node_weight[static_cast<std::size_t>(z)] = (alt - z0) / (z1 - z0);
  }
  const std::size_t layer = grid.columns(), p0 = grid.index(x, y, 0);
  const double* qcf = q(kCf);
  for (int f = 0; f < core::kFieldCount; ++f) {
    auto& dst = out.fields[static_cast<std::size_t>(f)];
    if (dst.empty()) continue;
    const double* qf = q(f);
    // In-cloud = grid-box mean / fraction. Water was kept only where the fraction is meaningful,
    // so where the fraction vanishes the mean does too and the ratio stays bounded by its
    // neighbours' in-cloud values.
    const bool in_cloud = (f == kLiq || f == kIce) && has_cf;
    for (int z = 0; z < grid.alt_m.count; ++z) {
      const int lz = node_level[static_cast<std::size_t>(z)];
      if (lz < 0) continue;
      const double a = node_weight[static_cast<std::size_t>(z)];
      double v = qf[lz - 1] + a * (qf[lz] - qf[lz - 1]);
      if (in_cloud) {
        const double cf = qcf[lz - 1] + a * (qcf[lz] - qcf[lz - 1]);
        if (!std::isnan(cf)) v = v > 0.0 && cf > 0.0 ? v / cf : (std::isnan(v) ? v : 0.0);
      }
      if (f == static_cast<int>(core::Field::Pressure)) v = std::exp(v);
      dst[p0 + static_cast<std::size_t>(z) * layer] = static_cast<float>(v);
    }
  }
}

bool in_time_range(const core::ValidTime& t, const ImportOptions& o) {
  return (o.time_from_iso.empty() || t.iso_utc >= o.time_from_iso) && (o.time_to_iso.empty() || t.iso_utc <= o.time_to_iso);
}

void report_counts(const ColumnCounts& c, int t, core::ImportReport& report) {
  report_counts(c, t, "", report);
}

void report_counts(const ColumnCounts& c, int t, const std::string& what, core::ImportReport& report) {
  const std::string at = " at time step " + std::to_string(t);
  const std::string boxes = what.empty() ? "boxes" : what;
  if (c.water_without_cf) {
    report.warn(std::to_string(c.water_without_cf) + " " + boxes + " with water (up to " + fmt(c.most_water_without_cf) +
                " kg/kg; " + std::to_string(c.water_without_cf_significant) + " above " + fmt(kZeroWater) +
                " kg/kg) but a cloud fraction below " + fmt(kZeroCloudFraction) + at +
                ": their water is left out, no cloud is invented there");
  }
  if (c.cf_without_water) {
    report.warn(std::to_string(c.cf_without_water) + " " + boxes + " with cloud fraction above 0.1 but no cloud water" + at);
  }
  if (c.nonmonotonic) report.warn(std::to_string(c.nonmonotonic) + " level pairs whose heights do not rise with the level" + at);
}

}  // namespace cv::importers
