// Trilinear sampling of volume fields.
#include "volume/sampler.hpp"

#include <algorithm>
#include <cmath>

#include "physics/physics.hpp"

namespace cv::core {

VolumeSampler::VolumeSampler(const VolumeGrid& grid, const std::vector<float>& field)
    : grid_(grid), field_(field), wraps_(grid.wraps_lon()) {}

bool VolumeSampler::global_lat() const {
  const auto& la = grid_.lat_deg;
  return wraps_ && la.start - la.step < -90.0 + 1e-9 && la.last() + la.step > 90.0 - 1e-9;
}

double VolumeSampler::sample(double lat_deg, double lon_deg, double alt_m, double nodata) const {
  if (field_.empty() || !std::isfinite(lat_deg) || !std::isfinite(lon_deg) || !std::isfinite(alt_m)) return nodata;
  const glm::dvec3 start(grid_.lon_deg.start, grid_.lat_deg.start, grid_.alt_m.start);
  const glm::dvec3 step(grid_.lon_deg.step, grid_.lat_deg.step, grid_.alt_m.step);
  const glm::dvec3 count(grid_.lon_deg.count, grid_.lat_deg.count, grid_.alt_m.count);
  glm::dvec3 f;
  if (!physics::f64::volume_coords(lat_deg, lon_deg, alt_m, start, step, count, wraps_, global_lat(), f)) return nodata;
  const int nx = grid_.lon_deg.count, ny = grid_.lat_deg.count, nz = grid_.alt_m.count;
  double wx, wy, wz;
  const int x0 = physics::f64::volume_fetch_index(f.x, nx, wx);
  const int y0 = physics::f64::volume_fetch_index(f.y, ny, wy);
  const int z0 = physics::f64::volume_fetch_index(f.z, nz, wz);
  const int x1 = wraps_ ? (x0 + 1) % nx : x0 + 1;
  const int y1 = y0 + 1, z1 = std::min(z0 + 1, nz - 1);
  // Nodes beyond a regional grid's sides (index -1 or n) are its border: no data.
  auto at = [&](int x, int y, int z) {
    if (x < 0 || x >= nx || y < 0 || y >= ny) return nodata;
    const double v = field_[grid_.index(x, y, z)];
    return std::isnan(v) ? nodata : v;
  };
  // A corner of weight 0 takes no part (so a gap beside a node does not hide the node's own value
  // when nodata is NaN); at weight 1 the far corner alone.
  auto lerp = [](double a, double b, double w) { return w == 0.0 ? a : w == 1.0 ? b : a + w * (b - a); };
  const double c00 = lerp(at(x0, y0, z0), at(x1, y0, z0), wx);
  const double c10 = lerp(at(x0, y1, z0), at(x1, y1, z0), wx);
  const double c01 = lerp(at(x0, y0, z1), at(x1, y0, z1), wx);
  const double c11 = lerp(at(x0, y1, z1), at(x1, y1, z1), wx);
  return lerp(lerp(c00, c10, wy), lerp(c01, c11, wy), wz);
}

}  // namespace cv::core
