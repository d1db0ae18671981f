// Two sources on a common grid.
#include "analysis/compare.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "volume/grid_mean.hpp"
#include "volume/sampler.hpp"

namespace cv::core {

namespace {
// A longitude interval [lo, hi] (lo <= hi, hi - lo <= 360) of a grid, in its own convention.
void lon_interval(const VolumeGrid& g, double& lo, double& hi) {
  if (g.wraps_lon()) {
    lo = g.lon_deg.start;
    hi = lo + 360.0;
    return;
  }
  lo = g.lon_deg.start;
  hi = g.lon_deg.last();
}
}  // namespace

Overlap grid_overlap(const VolumeGrid& a, const VolumeGrid& b) {
  Overlap o;
  o.lat_lo = std::max(a.lat_deg.start, b.lat_deg.start);
  o.lat_hi = std::min(a.lat_deg.last(), b.lat_deg.last());
  o.alt_lo = std::max(a.alt_m.start, b.alt_m.start);
  o.alt_hi = std::min(a.alt_m.last(), b.alt_m.last());
  double a0, a1, b0, b1;
  lon_interval(a, a0, a1);
  lon_interval(b, b0, b1);
  // B's interval shifted by whole turns to where it overlaps A most.
  double best = -1.0, lo = 0.0, hi = 0.0;
  for (int turn = -2; turn <= 2; ++turn) {
    const double s0 = b0 + 360.0 * turn, s1 = b1 + 360.0 * turn;
    const double l = std::max(a0, s0), h = std::min(a1, s1);
    if (h - l > best) best = h - l, lo = l, hi = h;
  }
  o.lon_lo = lo;
  o.lon_hi = std::min(hi, lo + 360.0);
  o.empty = !(best >= 0.0) || o.lat_hi < o.lat_lo || o.alt_hi < o.alt_lo;
  return o;
}

VolumeGrid common_grid(const VolumeGrid& a, const VolumeGrid& b, const Overlap& o) {
  VolumeGrid g;
  g.earth_radius_m = a.earth_radius_m;
  auto axis = [](double lo, double hi, double step, bool full_turn) {
    RegularAxis r;
    r.start = lo;
    r.step = step;
    const double span = hi - lo;
    r.count = full_turn ? std::max(1, static_cast<int>(std::lround(360.0 / step))) : static_cast<int>(std::floor(span / step + 1e-9)) + 1;
    return r;
  };
  const bool both_wrap = a.wraps_lon() && b.wraps_lon();
  g.lon_deg = axis(o.lon_lo, o.lon_hi, std::max(std::abs(a.lon_deg.step), std::abs(b.lon_deg.step)), both_wrap);
  g.lat_deg = axis(o.lat_lo, o.lat_hi, std::max(std::abs(a.lat_deg.step), std::abs(b.lat_deg.step)), false);
  g.alt_m = axis(o.alt_lo, o.alt_hi, std::max(a.alt_m.step, b.alt_m.step), false);
  return g;
}

std::string common_grid_text(const VolumeGrid& c, const VolumeGrid& a, const VolumeGrid& b) {
  char buf[400];
  std::snprintf(buf, sizeof buf,
                "common grid %d x %d x %d: lon %.6g..%.6g step %.4g deg, lat %.6g..%.6g step %.4g deg, altitude %.0f..%.0f m step %.0f m "
                "(the coarser of A's %.4g/%.4g deg, %.0f m and B's %.4g/%.4g deg, %.0f m, over the region both hold)",
                c.lon_deg.count, c.lat_deg.count, c.alt_m.count, c.lon_deg.start, c.lon_deg.last(), c.lon_deg.step, c.lat_deg.start,
                c.lat_deg.last(), c.lat_deg.step, c.alt_m.start, c.alt_m.last(), c.alt_m.step, a.lon_deg.step, a.lat_deg.step, a.alt_m.step,
                b.lon_deg.step, b.lat_deg.step, b.alt_m.step);
  return buf;
}

TimeStepData resample_step(const VolumeGrid& from, const TimeStepData& data, const VolumeGrid& to) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  TimeStepData out;
  for (Field f : {Field::CloudFraction, Field::ExtinctionLiquid, Field::ExtinctionIce}) {
    if (data[f].empty()) continue;
    const VolumeSampler s(from, data[f]);
    std::vector<float>& o = out[f];
    o.resize(to.points());
    for (int k = 0; k < to.alt_m.count; ++k)
      for (int j = 0; j < to.lat_deg.count; ++j)
        for (int i = 0; i < to.lon_deg.count; ++i)
          o[to.index(i, j, k)] = static_cast<float>(s.sample(to.lat_deg.at(j), to.lon_deg.at(i), to.alt_m.at(k), nan));
  }
  if (data.ground_m.size() == from.columns()) {
    VolumeGrid flat = from;
    flat.alt_m.count = 1;
    const VolumeSampler s(flat, data.ground_m);
    out.ground_m.resize(to.columns());
    for (int j = 0; j < to.lat_deg.count; ++j)
      for (int i = 0; i < to.lon_deg.count; ++i)
        out.ground_m[to.column(i, j)] = static_cast<float>(s.sample(to.lat_deg.at(j), to.lon_deg.at(i), flat.alt_m.start, nan));
  }
  derive_maps(to, out);
  return out;
}

Comparison compare_steps(const VolumeGrid& grid_a, const TimeStepData& a, const VolumeGrid& grid_b, const TimeStepData& b,
                         const VolumeGrid& common, const MapOptions& options) {
  Comparison c;
  c.grid = common;
  c.a = resample_step(grid_a, a, common);
  c.b = resample_step(grid_b, b, common);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const std::size_t nc = common.columns();
  c.columns.assign(nc, Presence::None);
  for (auto* d : {&c.d_cover, &c.d_optical_depth, &c.d_base_m, &c.d_top_m}) d->assign(nc, nan);
  const Maps2D &ma = c.a.maps, &mb = c.b.maps;
  for (std::size_t i = 0; i < nc; ++i) {
    const bool ca = std::isfinite(ma.cloud_base_m[i]), cb = std::isfinite(mb.cloud_base_m[i]);
    c.columns[i] = static_cast<Presence>((ca ? 1 : 0) | (cb ? 2 : 0));
    c.d_cover[i] = mb.cloud_cover[i] - ma.cloud_cover[i];  // NaN where either has no data
    c.d_optical_depth[i] = mb.optical_depth[i] - ma.optical_depth[i];
    c.d_base_m[i] = mb.cloud_base_m[i] - ma.cloud_base_m[i];
    c.d_top_m[i] = mb.cloud_top_m[i] - ma.cloud_top_m[i];
  }
  auto cloudy = [&](const TimeStepData& d, std::size_t p) {
    auto v = [&](Field f) { return d[f].empty() || std::isnan(d[f][p]) ? 0.0 : double(d[f][p]); };
    const double ext = v(Field::ExtinctionLiquid) + v(Field::ExtinctionIce);
    const double frac = d[Field::CloudFraction].empty() || std::isnan(d[Field::CloudFraction][p]) ? (ext > 0.0 ? 1.0 : 0.0) : v(Field::CloudFraction);
    return map_cloudy(frac, ext, options);
  };
  c.points.assign(common.points(), Presence::None);
  for (std::size_t p = 0; p < common.points(); ++p) c.points[p] = static_cast<Presence>((cloudy(c.a, p) ? 1 : 0) | (cloudy(c.b, p) ? 2 : 0));
  return c;
}

TimeStepData presence_medium(const Comparison& c) {
  const GridMeanExtinction ma = grid_mean_extinction(c.grid, c.a), mb = grid_mean_extinction(c.grid, c.b);
  const std::size_t n = c.grid.points();
  TimeStepData out;
  out[Field::CloudFraction].assign(n, 0.0f);
  out[Field::ExtinctionLiquid].assign(n, 0.0f);
  out[Field::ExtinctionIce].assign(n, 0.0f);
  auto ext = [](const GridMeanExtinction& m, std::size_t p) {
    const float l = m.liquid_per_m[p], i = m.ice_per_m[p];
    return (std::isfinite(l) ? l : 0.0f) + (std::isfinite(i) ? i : 0.0f);
  };
  for (std::size_t p = 0; p < n; ++p) {
    float liquid = 0.0f, ice = 0.0f;
    switch (c.points[p]) {
      case Presence::OnlyA: liquid = ext(ma, p); break;
      case Presence::OnlyB: ice = ext(mb, p); break;
      case Presence::Both: liquid = ice = 0.5f * std::max(ext(ma, p), ext(mb, p)); break;
      default: break;
    }
    out[Field::ExtinctionLiquid][p] = liquid;
    out[Field::ExtinctionIce][p] = ice;
    out[Field::CloudFraction][p] = liquid + ice > 0.0f ? 1.0f : 0.0f;
  }
  out.ground_m = c.a.ground_m;
  derive_maps(c.grid, out);
  return out;
}

}  // namespace cv::core
