// The extinction pyramid: built from the grid-mean extinction, queried by the CPU reference.
#include "volume/extinction_pyramid.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "physics/physics.hpp"
#include "volume/sampler.hpp"

namespace cv::core {
namespace p64 = cv::physics::f64;

ExtinctionPyramid::ExtinctionPyramid(const VolumeGrid& grid, const std::vector<float>& liquid_per_m,
                                     const std::vector<float>& ice_per_m, int levels)
    : grid_(grid), wraps_(grid.wraps_lon()) {
  const std::vector<float> none;
  global_lat_ = VolumeSampler(grid, none).global_lat();
  const int gx = grid.lon_deg.count, gy = grid.lat_deg.count, gz = grid.alt_m.count;
  if (gx <= 0 || gy <= 0 || gz <= 0) return;
  auto value = [&](std::size_t p) {
    double v = 0.0;
    if (!liquid_per_m.empty() && std::isfinite(liquid_per_m[p])) v += std::max(0.0f, liquid_per_m[p]);
    if (!ice_per_m.empty() && std::isfinite(ice_per_m[p])) v += std::max(0.0f, ice_per_m[p]);
    return static_cast<float>(v);
  };
  // Level 0, separably: the min/max over the dilated node range along x, then y, then z.
  Level l0;
  l0.nodes = kFinestNodes;
  const int B = kFinestNodes;
  l0.nx = (gx + B - 1) / B;
  l0.ny = (gy + B - 1) / B;
  l0.nz = (gz + B - 1) / B;
  const float inf = std::numeric_limits<float>::infinity();
  // Per (brick x, node y, node z).
  std::vector<glm::vec2> ax(std::size_t(l0.nx) * gy * gz, glm::vec2(inf, -inf));
  for (int z = 0; z < gz; ++z)
    for (int y = 0; y < gy; ++y)
      for (int bx = 0; bx < l0.nx; ++bx) {
        glm::vec2 mm(inf, -inf);
        for (int x = bx * B - 1; x <= bx * B + B + 1; ++x) {
          int xi = x;
          if (wraps_) xi = ((x % gx) + gx) % gx;
          else if (x < 0 || x >= gx) xi = std::clamp(x, 0, gx - 1);
          const float v = value(grid.index(xi, y, z));
          mm = glm::vec2(std::min(mm.x, v), std::max(mm.y, v));
        }
        ax[(std::size_t(z) * gy + y) * l0.nx + bx] = mm;
      }
  std::vector<glm::vec2> ay(std::size_t(l0.nx) * l0.ny * gz, glm::vec2(inf, -inf));
  for (int z = 0; z < gz; ++z)
    for (int by = 0; by < l0.ny; ++by)
      for (int y = std::max(0, by * B - 1); y <= std::min(gy - 1, by * B + B + 1); ++y)
        for (int bx = 0; bx < l0.nx; ++bx) {
          glm::vec2& o = ay[(std::size_t(z) * l0.ny + by) * l0.nx + bx];
          const glm::vec2 v = ax[(std::size_t(z) * gy + y) * l0.nx + bx];
          o = glm::vec2(std::min(o.x, v.x), std::max(o.y, v.y));
        }
  l0.min_max.assign(std::size_t(l0.nx) * l0.ny * l0.nz, glm::vec2(inf, -inf));
  for (int bz = 0; bz < l0.nz; ++bz)
    for (int z = std::max(0, bz * B - 1); z <= std::min(gz - 1, bz * B + B + 1); ++z)
      for (int by = 0; by < l0.ny; ++by)
        for (int bx = 0; bx < l0.nx; ++bx) {
          glm::vec2& o = l0.min_max[l0.index(bx, by, bz)];
          const glm::vec2 v = ay[(std::size_t(z) * l0.ny + by) * l0.nx + bx];
          o = glm::vec2(std::min(o.x, v.x), std::max(o.y, v.y));
        }
  levels_.push_back(std::move(l0));
  // Coarser levels: 2 x 2 x 2 children each (the union of the children's dilated ranges covers the
  // parent's).
  for (int li = 1; li < std::clamp(levels, 1, kMaxLevels); ++li) {
    const Level& c = levels_.back();
    Level l;
    l.nodes = c.nodes * 2;
    l.nx = (c.nx + 1) / 2;
    l.ny = (c.ny + 1) / 2;
    l.nz = (c.nz + 1) / 2;
    l.min_max.assign(std::size_t(l.nx) * l.ny * l.nz, glm::vec2(inf, -inf));
    for (int z = 0; z < c.nz; ++z)
      for (int y = 0; y < c.ny; ++y)
        for (int x = 0; x < c.nx; ++x) {
          glm::vec2& o = l.min_max[l.index(x / 2, y / 2, z / 2)];
          const glm::vec2 v = c.min_max[c.index(x, y, z)];
          o = glm::vec2(std::min(o.x, v.x), std::max(o.y, v.y));
        }
    levels_.push_back(std::move(l));
  }
}

ExtinctionPyramid::Space ExtinctionPyramid::at(const glm::dvec3& p, const glm::dvec3& dir) const {
  Space s;
  if (levels_.empty()) return s;  // no pyramid: nothing known, never skip
  constexpr double kDeg = 3.14159265358979323846 / 180.0;
  const double r0 = grid_.earth_radius_m;
  const glm::dvec3 geo = p64::ecef_to_sphere(p, r0);
  const double lat = geo.x / kDeg, lon = geo.y / kDeg, alt = geo.z;
  const glm::dvec3 start(grid_.lon_deg.start, grid_.lat_deg.start, grid_.alt_m.start);
  const glm::dvec3 step(grid_.lon_deg.step, grid_.lat_deg.step, grid_.alt_m.step);
  const glm::dvec3 count(grid_.lon_deg.count, grid_.lat_deg.count, grid_.alt_m.count);
  const double r = glm::length(p), mu_up = glm::dot(dir, p) / r;
  const glm::dvec3 g = p64::march_grid_index(lat, lon, alt, start, step, count, wraps_, global_lat_);
  // Coarsest first: the largest empty brick gives the longest jump.
  for (int li = static_cast<int>(levels_.size()) - 1; li >= 0; --li) {
    const Level& l = levels_[static_cast<std::size_t>(li)];
    const glm::dvec3 nb(l.nx, l.ny, l.nz);
    const glm::dvec3 b = p64::march_brick(g, l.nodes);
    const double extent = p64::march_brick_exit_m(lat, r, mu_up, g, b, l.nodes, nb, start, step, global_lat_, r0);
    if (!p64::march_brick_inside(b, nb)) {
      s.empty = true;
      s.extent_m = extent;
      return s;
    }
    const glm::vec2 mm = l.min_max[l.index(static_cast<int>(b.x), static_cast<int>(b.y), static_cast<int>(b.z))];
    if (mm.y <= 0.0f) {
      s.empty = true;
      s.extent_m = extent;
      return s;
    }
    if (li == 0) {
      s.sigma_max_per_m = mm.y;
      s.extent_m = extent;
    }
  }
  return s;
}

}  // namespace cv::core
