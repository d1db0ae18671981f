// Vertical sections along great circles.
#include "analysis/section.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "analysis/column_probe.hpp"
#include "volume/sampler.hpp"

namespace cv::core {

SectionField section_field(const CloudVolume& volume, const std::string& name) {
  SectionField f;
  if (name == "extinction") {
    f.march_extinction = true;
    return f;
  }
  std::string held;
  for (int i = 0; i < kFieldCount; ++i) {
    if (!volume.has_field[static_cast<std::size_t>(i)]) continue;
    if (name == field_name(static_cast<Field>(i))) {
      f.field = static_cast<Field>(i);
      return f;
    }
    held += std::string(", ") + field_name(static_cast<Field>(i));
  }
  throw std::invalid_argument("found \"" + name + "\", expected extinction or a field the volume holds" +
                              (held.empty() ? std::string(" (none)") : ": " + held.substr(2)));
}

double smallest_cell_m(const VolumeGrid& g) {
  const double deg = M_PI / 180.0 * g.earth_radius_m;
  // Meridians converge: the narrowest longitude cell is at the latitude farthest from the equator.
  const double far_lat = std::min(89.0, std::max(std::abs(g.lat_deg.start), std::abs(g.lat_deg.last())));
  return std::min(std::abs(g.lat_deg.step) * deg, std::abs(g.lon_deg.step) * deg * std::cos(far_lat * M_PI / 180.0));
}

Section vertical_section(const CloudVolume& volume, const TimeStepData& data, const GridMeanExtinction& medium,
                         const SectionField& field, double lat1, double lon1, double lat2, double lon2, int columns,
                         const std::vector<double>& alt_m, const MapOptions& options) {
  const VolumeGrid& g = volume.grid;
  const std::string extent = grid_extent_text(g);
  if (!grid_holds(g, lat1, lon1)) throw std::invalid_argument("the start lies outside the data (" + extent + ")");
  if (!grid_holds(g, lat2, lon2)) throw std::invalid_argument("the end lies outside the data (" + extent + ")");
  Section s;
  s.length_m = geo::great_circle_distance_m(lat1, lon1, lat2, lon2, g.earth_radius_m);
  const double cell = smallest_cell_m(g);
  if (!(s.length_m >= cell)) {
    char buf[200];
    std::snprintf(buf, sizeof buf, "the path is %.4g m long, expected at least one grid cell (%.4g m)", s.length_m, cell);
    throw std::invalid_argument(buf);
  }
  s.path = geo::great_circle_points(lat1, lon1, lat2, lon2, std::max(2, columns), g.earth_radius_m);
  s.alt_m = alt_m;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::size_t nr = alt_m.size();
  s.value.assign(s.path.size() * nr, nan);
  s.cloudy.assign(s.path.size() * nr, 0);
  s.ground_m.assign(s.path.size(), nan);
  VolumeGrid flat = g;
  flat.alt_m.count = 1;
  const bool has_ground = data.ground_m.size() == g.columns();
  const VolumeSampler cf(g, data[Field::CloudFraction]), el(g, data[Field::ExtinctionLiquid]), ei(g, data[Field::ExtinctionIce]);
  const VolumeSampler ml(g, medium.liquid_per_m), mi(g, medium.ice_per_m);
  const std::vector<float> none;
  const VolumeSampler fv(g, field.march_extinction ? none : data[field.field]);
  const bool has_cf = !data[Field::CloudFraction].empty();
  for (std::size_t i = 0; i < s.path.size(); ++i) {
    const geo::PathPoint& p = s.path[i];
    if (has_ground) s.ground_m[i] = VolumeSampler(flat, data.ground_m).sample(p.lat_deg, p.lon_deg, flat.alt_m.start, nan);
    for (std::size_t k = 0; k < nr; ++k) {
      const double a = alt_m[k];
      const double ext = el.sample(p.lat_deg, p.lon_deg, a, 0.0) + ei.sample(p.lat_deg, p.lon_deg, a, 0.0);
      const double frac = has_cf ? cf.sample(p.lat_deg, p.lon_deg, a, 0.0) : (ext > 0.0 ? 1.0 : 0.0);
      s.cloudy[i * nr + k] = map_cloudy(frac, ext, options) ? 1 : 0;
      if (field.march_extinction) {
        // No data reads as no cloud in the march; outside the grid's levels there is nothing.
        const bool in = a >= g.alt_m.start - 1e-6 && a <= g.alt_m.last() + 1e-6;
        s.value[i * nr + k] = in ? ml.sample(p.lat_deg, p.lon_deg, a, 0.0) + mi.sample(p.lat_deg, p.lon_deg, a, 0.0) : nan;
      } else {
        s.value[i * nr + k] = fv.sample(p.lat_deg, p.lon_deg, a, nan);
      }
    }
  }
  return s;
}

}  // namespace cv::core
