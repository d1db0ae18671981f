// Grid-mean extinction and what is derived from it.
#include "volume/grid_mean.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "geo/geodesy.hpp"

namespace cv::core {

double largest_extinction(const GridMeanExtinction& medium) {
  double m = 0.0;
  for (std::size_t i = 0; i < std::max(medium.liquid_per_m.size(), medium.ice_per_m.size()); ++i) {
    m = std::max(m, (i < medium.liquid_per_m.size() ? double(medium.liquid_per_m[i]) : 0.0) +
                        (i < medium.ice_per_m.size() ? double(medium.ice_per_m[i]) : 0.0));
  }
  return m;
}

std::vector<float> lapse_rates(const VolumeGrid& grid, const TimeStepData& data) {
  const auto& t = data[Field::Temperature];
  if (t.size() != grid.points()) return {};
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::vector<float> out(grid.columns(), nan);
  for (int j = 0; j < grid.lat_deg.count; ++j) {
    for (int i = 0; i < grid.lon_deg.count; ++i) {
      const std::size_t col = grid.column(i, j);
      const double ground = col < data.ground_m.size() && std::isfinite(data.ground_m[col]) ? data.ground_m[col] : 0.0;
      // The lowest level at or above the ground with a temperature, then the first at least 3 km
      // above it with one.
      int k0 = -1;
      for (int k = 0; k < grid.alt_m.count && k0 < 0; ++k) {
        if (grid.alt_m.at(k) >= ground && std::isfinite(t[grid.index(i, j, k)])) k0 = k;
      }
      if (k0 < 0) continue;
      for (int k = k0 + 1; k < grid.alt_m.count; ++k) {
        const double dz = grid.alt_m.at(k) - grid.alt_m.at(k0);
        if (dz < 3000.0 - 1e-6 || !std::isfinite(t[grid.index(i, j, k)])) continue;
        out[col] = static_cast<float>((double(t[grid.index(i, j, k0)]) - double(t[grid.index(i, j, k)])) / dz * 1000.0);
        break;
      }
    }
  }
  return out;
}

GridMeanExtinction grid_mean_extinction(const VolumeGrid& grid, const TimeStepData& data) {
  GridMeanExtinction m;
  const auto& cf = data[Field::CloudFraction];
  auto product = [&](const std::vector<float>& ext, std::vector<float>& out) {
    out.assign(grid.points(), 0.0f);
    if (ext.empty()) return;
    for (std::size_t p = 0; p < out.size(); ++p) {
      const float c = cf.empty() ? 1.0f : cf[p];
      const float v = c * ext[p];
      // NaN, negative and fill values (netCDF's 9.96921e36 left in a field, or a product with one)
      // are no data: no cloud. The comparison is false for NaN.
      out[p] = v >= 0.0f && v < kMaxGridMeanExtinctionPerM ? v : 0.0f;
    }
  };
  product(data[Field::ExtinctionLiquid], m.liquid_per_m);
  product(data[Field::ExtinctionIce], m.ice_per_m);
  if (data.ground_m.size() == grid.columns()) m.ground_m = data.ground_m;
  if (cf.size() == grid.points()) {
    m.fraction.resize(cf.size());
    for (std::size_t p = 0; p < cf.size(); ++p) m.fraction[p] = cf[p] > 0.0f ? std::min(cf[p], 1.0f) : 0.0f;  // NaN -> 0
  }
  m.lapse_k_per_km = lapse_rates(grid, data);
  return m;
}

CloudLayer cloud_layer(const VolumeGrid& grid, const GridMeanExtinction& medium) {
  const std::size_t per_level = grid.columns();
  int lo = -1, hi = -1;
  for (int k = 0; k < grid.alt_m.count; ++k) {
    bool any = false;
    for (const std::vector<float>* f : {&medium.liquid_per_m, &medium.ice_per_m}) {
      if (f->empty()) continue;
      const auto first = f->begin() + static_cast<std::ptrdiff_t>(per_level * k);
      any = any || std::any_of(first, first + static_cast<std::ptrdiff_t>(per_level), [](float v) { return v > 0.0f; });
    }
    if (any) {
      if (lo < 0) lo = k;
      hi = k;
    }
  }
  CloudLayer l;
  if (lo < 0) return l;
  l.empty = false;
  l.bottom_m = grid.alt_m.at(std::max(lo - 1, 0));
  l.top_m = grid.alt_m.at(std::min(hi + 1, grid.alt_m.count - 1));
  return l;
}

glm::dvec3 grid_centre_ecef(const VolumeGrid& grid) {
  const double lat = grid.lat_deg.start + 0.5 * (grid.lat_deg.last() - grid.lat_deg.start);
  const double lon = grid.lon_deg.start + 0.5 * (grid.lon_deg.last() - grid.lon_deg.start);
  return geo::sphere_to_ecef({lat, lon, 0.0}, grid.earth_radius_m);
}

}  // namespace cv::core
