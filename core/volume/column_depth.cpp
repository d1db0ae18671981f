// Vertical optical depth per grid column.
#include "volume/column_depth.hpp"

#include <cmath>

#include "physics/physics.hpp"
#include "volume/sampler.hpp"

namespace cv::core {

ColumnDepth column_depth(const VolumeGrid& grid, const std::vector<float>& liquid_per_m,
                         const std::vector<float>& ice_per_m) {
  ColumnDepth c;
  c.nx = grid.lon_deg.count;
  c.ny = grid.lat_deg.count;
  c.tau.assign(grid.columns(), 0.0f);
  const int nz = grid.alt_m.count;
  const double dz_m = grid.alt_m.step;
  auto sigma = [&](std::size_t i) {
    return (liquid_per_m.empty() ? 0.0 : double(liquid_per_m[i])) + (ice_per_m.empty() ? 0.0 : double(ice_per_m[i]));
  };
  for (int y = 0; y < c.ny; ++y) {
    for (int x = 0; x < c.nx; ++x) {
      // Trapezoid: every level counts fully but the two ends, which count half (one level: none,
      // the sampler has no interval to interpolate over).
      double sum = 0.0;
      for (int k = 0; k < nz; ++k) {
        const double v = sigma(grid.index(x, y, k));
        sum += k == 0 || k == nz - 1 ? 0.5 * v : v;
      }
      c.tau[static_cast<std::size_t>(y) * c.nx + x] = nz > 1 ? static_cast<float>(sum * dz_m) : 0.0f;
    }
  }
  return c;
}

double ColumnDepth::at(const VolumeGrid& grid, double lat_deg, double lon_deg) const {
  if (tau.empty() || !std::isfinite(lat_deg) || !std::isfinite(lon_deg)) return 0.0;
  namespace p64 = physics::f64;
  const glm::dvec3 start(grid.lon_deg.start, grid.lat_deg.start, grid.alt_m.start);
  const glm::dvec3 step(grid.lon_deg.step, grid.lat_deg.step, grid.alt_m.step);
  const glm::dvec3 count(grid.lon_deg.count, grid.lat_deg.count, grid.alt_m.count);
  const bool wraps = grid.wraps_lon();
  const std::vector<float> none;
  glm::dvec3 f;
  // At the lowest level's altitude: only the horizontal indices are wanted.
  if (!p64::volume_coords(lat_deg, lon_deg, grid.alt_m.start, start, step, count, wraps,
                          VolumeSampler(grid, none).global_lat(), f)) {
    return 0.0;
  }
  double wx, wy;
  const int x0 = p64::volume_fetch_index(f.x, nx, wx), y0 = p64::volume_fetch_index(f.y, ny, wy);
  const int x1 = wraps ? (x0 + 1) % nx : x0 + 1, y1 = y0 + 1;
  auto node = [&](int x, int y) {
    return x < 0 || x >= nx || y < 0 || y >= ny ? 0.0 : double(tau[static_cast<std::size_t>(y) * nx + x]);
  };
  const double c0 = node(x0, y0) + wx * (node(x1, y0) - node(x0, y0));
  const double c1 = node(x0, y1) + wx * (node(x1, y1) - node(x0, y1));
  return c0 + wy * (c1 - c0);
}

}  // namespace cv::core
