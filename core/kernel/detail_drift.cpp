// The modelled cloud's detail carried by the level-mean winds.
#include "kernel/detail_drift.hpp"

#include <cmath>

#include <algorithm>
#include <cstdio>

#include "kernel/prepared_volume.hpp"
#include "volume/grid_mean.hpp"

namespace cv::core {

std::vector<double> level_drift_rate(const VolumeGrid& grid, const TimeStepData& data) {
  const int nx = grid.lon_deg.count, ny = grid.lat_deg.count, nz = grid.alt_m.count;
  std::vector<double> out(2 * std::size_t(std::max(nz, 0)), 0.0);
  const std::vector<float>& u = data[Field::WindU];
  const std::vector<float>& v = data[Field::WindV];
  if (u.size() != grid.points() || v.size() != grid.points()) return out;
  const GridMeanExtinction e = grid_mean_extinction(grid, data);
  const double deg = 3.14159265358979323846 / 180.0;
  const double r = grid.earth_radius_m;
  const double step_x = std::abs(grid.lon_deg.step) * deg, step_y = std::abs(grid.lat_deg.step) * deg;
  if (!(step_x > 0.0) || !(step_y > 0.0) || !(r > 0.0)) return out;
  std::vector<double> cos_lat(static_cast<std::size_t>(ny));
  for (int j = 0; j < ny; ++j) cos_lat[std::size_t(j)] = std::max(std::cos(grid.lat_deg.at(j) * deg), 0.0);
  for (int k = 0; k < nz; ++k) {
    // Two passes' sums at once: weighted by cloud (c_) and by area alone (a_).
    double c_u = 0.0, c_v = 0.0, c_w = 0.0, a_u = 0.0, a_v = 0.0, a_w = 0.0;
    for (int j = 0; j < ny; ++j) {
      const double cl = cos_lat[std::size_t(j)];
      for (int i = 0; i < nx; ++i) {
        const std::size_t p = grid.index(i, j, k);
        const double uu = u[p], vv = v[p];
        if (!std::isfinite(uu) || !std::isfinite(vv) || std::abs(uu) > 1000.0 || std::abs(vv) > 1000.0) continue;  // no data, or a fill value
        const double s = double(e.liquid_per_m[p]) + double(e.ice_per_m[p]);
        // u / (R cos lat) weighted by s cos lat is s u / R: the cosine cancels.
        c_u += s * uu, c_v += s * cl * vv, c_w += s * cl;
        a_u += uu, a_v += cl * vv, a_w += cl;
      }
    }
    const bool cloudy = c_w > 0.0;
    const double su = cloudy ? c_u : a_u, sv = cloudy ? c_v : a_v, sw = cloudy ? c_w : a_w;
    if (!(sw > 0.0)) continue;
    out[2 * std::size_t(k)] = su / (r * sw) / step_x * (grid.lon_deg.step < 0.0 ? -1.0 : 1.0);
    out[2 * std::size_t(k) + 1] = sv / (r * sw) / step_y * (grid.lat_deg.step < 0.0 ? -1.0 : 1.0);
  }
  return out;
}

const std::vector<double>& DetailDrift::rate(CloudVolume& volume, std::size_t step) {
  if (volume_ != &volume || rates_.size() != volume.times.size()) {
    volume_ = &volume;
    rates_.assign(volume.times.size(), {});
  }
  if (rates_[step].empty()) rates_[step] = level_drift_rate(volume.grid, volume.step(step));
  return rates_[step];
}

std::vector<double> DetailDrift::at(CloudVolume& volume, const Instant& instant) {
  const std::size_t levels = std::size_t(std::max(volume.grid.alt_m.count, 0));
  std::vector<double> d(2 * levels, 0.0);
  if (volume.times.empty() || !times_known(volume.times)) return d;
  const std::size_t last = std::min(std::max(instant.step0, instant.step1), volume.times.size() - 1);
  // The trapezoid over whole gaps up to step0 (exact for rates linear in time), then the part of the
  // gap to the instant: gap x (f r0 + f^2 (r1 - r0) / 2), whose rate is r0 + f (r1 - r0).
  for (std::size_t j = 0; j < instant.step0 && j + 1 <= last; ++j) {
    const double dt = double(volume.times[j + 1].unix_s - volume.times[j].unix_s);
    if (!(dt > 0.0)) continue;
    const std::vector<double>& r0 = rate(volume, j);
    const std::vector<double>& r1 = rate(volume, j + 1);
    for (std::size_t i = 0; i < d.size(); ++i) d[i] += 0.5 * dt * (r0[i] + r1[i]);
  }
  if (instant.between() && instant.gap_s > 0.0) {
    const double f = std::clamp(instant.fraction, 0.0, 1.0);
    const std::vector<double>& r0 = rate(volume, instant.step0);
    const std::vector<double>& r1 = rate(volume, instant.step1);
    for (std::size_t i = 0; i < d.size(); ++i) d[i] += instant.gap_s * (f * r0[i] + 0.5 * f * f * (r1[i] - r0[i]));
  }
  return d;
}

std::vector<float> detail_shift_texels(const PreparedVolume& v, const kernel::MarchParams& p) {
  const std::size_t levels = std::size_t(std::max(v.grid.alt_m.count, 0));
  std::vector<float> out(2 * levels, 0.0f);
  if (v.extinction.detail_drift_cells.size() != out.size()) return out;
  const double tiles[2] = {p.u_detail_tiles.x, p.u_detail_tiles.y};
  for (std::size_t k = 0; k < levels; ++k) {
    for (int a = 0; a < 2; ++a) {
      const double t = v.extinction.detail_drift_cells[2 * k + std::size_t(a)] * tiles[a];
      double m = std::isfinite(t) ? t - std::floor(t) : 0.0;  // in [0, 1)
      if (k > 0) {  // within half a tile of the level below: the blend between them takes the short way
        const double below = out[2 * (k - 1) + std::size_t(a)];
        m += std::round(below - m);
      }
      out[2 * k + std::size_t(a)] = static_cast<float>(m);
    }
  }
  return out;
}

std::string detail_drift_note(const PreparedVolume& v, const std::string& first_step) {
  const VolumeGrid& g = v.grid;
  const std::vector<double>& d = v.extinction.detail_drift_cells;
  if (d.size() != 2 * std::size_t(std::max(g.alt_m.count, 0)) || d.empty()) return {};
  int cloudiest = 0;
  double most = -1.0;
  for (int k = 0; k < g.alt_m.count; ++k) {
    double sum = 0.0;
    for (std::size_t c = 0; c < g.columns(); ++c) {
      const std::size_t i = std::size_t(k) * g.columns() + c;
      sum += double(v.extinction.liquid_per_m[i]) + double(v.extinction.ice_per_m[i]);
    }
    if (sum > most) most = sum, cloudiest = k;
  }
  const double deg = 3.14159265358979323846 / 180.0;
  const double mid_lat = g.lat_deg.start + 0.5 * g.lat_deg.step * (g.lat_deg.count - 1);
  const double east_km = d[2 * std::size_t(cloudiest)] * g.lon_deg.step * deg * g.earth_radius_m * std::cos(mid_lat * deg) / 1e3;
  const double north_km = d[2 * std::size_t(cloudiest) + 1] * g.lat_deg.step * deg * g.earth_radius_m / 1e3;
  char line[240];
  std::snprintf(line, sizeof line,
                "the detail moves with the wind: carried %.0f km east and %.0f km north since %s at %.1f km, the cloudiest "
                "level (each level by its own mean wind)",
                east_km, north_km, first_step.c_str(), g.alt_m.at(cloudiest) / 1e3);
  return line;
}

}  // namespace cv::core
