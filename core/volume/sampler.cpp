// Trilinear sampling of volume fields.
#include "volume/sampler.hpp"

#include <cmath>

namespace cv::core {

VolumeSampler::VolumeSampler(const VolumeGrid& grid, const std::vector<float>& field)
    : grid_(grid), field_(field), wraps_(grid.wraps_lon()) {}

double VolumeSampler::lon_index(double lon_deg) const {
  const auto& a = grid_.lon_deg;
  // Degrees east of the first column, in [0, 360).
  double east = std::fmod(lon_deg - a.start, 360.0);
  if (east < 0.0) east += 360.0;
  const double f = east / a.step;
  if (wraps_) return f >= a.count ? f - a.count : f;
  const double last = a.count - 1;
  if (f <= last + 1e-9) return std::min(f, last);
  return -1.0;
}

double VolumeSampler::sample(double lat_deg, double lon_deg, double alt_m, double nodata) const {
  if (field_.empty() || !std::isfinite(lat_deg) || !std::isfinite(lon_deg) || !std::isfinite(alt_m)) return nodata;
  const auto& la = grid_.lat_deg;
  const auto& al = grid_.alt_m;
  const double fx = lon_index(lon_deg);
  if (fx < 0.0) return nodata;
  double fy = (lat_deg - la.start) / la.step;
  const double fz = (alt_m - al.start) / al.step;
  const double ny = la.count - 1, nz = al.count - 1;
  // A global grid's rows end at or near the poles: beyond its first and last rows the edge row
  // holds (no data is missing there); a regional grid has nothing beyond its rows.
  const bool global_lat = wraps_ && la.start - la.step < -90.0 + 1e-9 && la.last() + la.step > 90.0 - 1e-9;
  if (fy < 0.0 || fy > ny) {
    if (!global_lat) return nodata;
    fy = std::min(std::max(fy, 0.0), ny);
  }
  if (fz < -1e-9 || fz > nz + 1e-9) return nodata;
  const int x0 = static_cast<int>(std::floor(fx));
  const int y0 = std::min(static_cast<int>(std::floor(fy)), std::max(0, la.count - 2));
  const int z0 = std::min(static_cast<int>(std::floor(std::max(fz, 0.0))), std::max(0, al.count - 2));
  const int x1 = wraps_ ? (x0 + 1) % grid_.lon_deg.count : std::min(x0 + 1, grid_.lon_deg.count - 1);
  const int y1 = std::min(y0 + 1, la.count - 1), z1 = std::min(z0 + 1, al.count - 1);
  const double wx = fx - x0, wy = std::min(std::max(fy - y0, 0.0), 1.0), wz = std::min(std::max(fz - z0, 0.0), 1.0);
  auto at = [&](int x, int y, int z) {
    const double v = field_[grid_.index(x, y, z)];
    return std::isnan(v) ? nodata : v;
  };
  const double c00 = at(x0, y0, z0) + wx * (at(x1, y0, z0) - at(x0, y0, z0));
  const double c10 = at(x0, y1, z0) + wx * (at(x1, y1, z0) - at(x0, y1, z0));
  const double c01 = at(x0, y0, z1) + wx * (at(x1, y0, z1) - at(x0, y0, z1));
  const double c11 = at(x0, y1, z1) + wx * (at(x1, y1, z1) - at(x0, y1, z1));
  const double c0 = c00 + wy * (c10 - c00), c1 = c01 + wy * (c11 - c01);
  return c0 + wz * (c1 - c0);
}

}  // namespace cv::core
