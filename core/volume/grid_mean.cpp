// Grid-mean extinction and what is derived from it.
#include "volume/grid_mean.hpp"

#include <algorithm>

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
