// Column and view-ray probes, read through the march's own sampler and kernel.
#include "analysis/column_probe.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "frame/camera.hpp"
#include "frame/sun.hpp"
#include "geo/geodesy.hpp"
#include "reference/raymarcher.hpp"
#include "settings/march_settings.hpp"
#include "volume/sampler.hpp"

namespace cv::core {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string num(double v, const char* fmt = "%.6g") {
  if (!std::isfinite(v)) return "";
  char buf[48];
  std::snprintf(buf, sizeof buf, fmt, v);
  return buf;
}
}  // namespace

std::string probe_levels_csv(const ColumnProbe& p, const CloudVolume& vol) {
  const bool has[] = {vol.has_field[static_cast<int>(Field::Temperature)], vol.has_field[static_cast<int>(Field::WindU)],
                      vol.has_field[static_cast<int>(Field::WindV)], vol.has_field[static_cast<int>(Field::WindW)],
                      vol.has_field[static_cast<int>(Field::Pressure)]};
  std::string table = "alt_m,above_ground_m,cloud_fraction,ext_liquid_per_m,ext_ice_per_m,march_liquid_per_m,march_ice_per_m,temperature_k,"
                      "wind_u_m_s,wind_v_m_s,wind_w_m_s,pressure_hpa\n";
  for (const auto& l : p.levels) {
    table += num(l.alt_m, "%.1f") + "," + num(l.above_ground_m, "%.1f") + "," + num(l.cloud_fraction, "%.6g") + "," + num(l.ext_liquid_per_m, "%.6g") +
             "," + num(l.ext_ice_per_m, "%.6g") + "," + num(l.march_liquid_per_m, "%.6g") + "," + num(l.march_ice_per_m, "%.6g") + "," +
             (has[0] ? num(l.temperature_k, "%.3f") : "") + "," + (has[1] ? num(l.wind_u_m_s, "%.3f") : "") + "," +
             (has[2] ? num(l.wind_v_m_s, "%.3f") : "") + "," + (has[3] ? num(l.wind_w_m_s, "%.4f") : "") + "," +
             (has[4] ? num(l.pressure_pa / 100.0, "%.2f") : "") + "\n";
  }
  return table;
}

std::string probe_summary_csv(const ColumnProbe& p) {
  return "# cover=" + num(p.cover, "%.6g") + ",base_m=" + num(p.base_m, "%.1f") + ",top_m=" + num(p.top_m, "%.1f") +
         ",optical_depth=" + num(p.optical_depth, "%.6g") + ",ground_m=" + num(p.ground_m, "%.1f");
}

std::string view_ray_csv(const ViewRayProbe& ray) {
  return ",first_cloud_m=" + (ray.first_cloud_m >= 0 ? num(ray.first_cloud_m, "%.1f") : "") + ",half_transmittance_m=" +
         (ray.half_transmittance_m >= 0 ? num(ray.half_transmittance_m, "%.1f") : "") + ",ray_transmittance=" +
         num(ray.transmittance, "%.6g");
}

bool grid_holds(const VolumeGrid& g, double lat_deg, double lon_deg) {
  if (!std::isfinite(lat_deg) || !std::isfinite(lon_deg) || g.lon_deg.count < 1 || g.lat_deg.count < 1) return false;
  if (lat_deg < g.lat_deg.start - 1e-9 || lat_deg > g.lat_deg.last() + 1e-9) return false;
  if (g.wraps_lon()) return true;
  const double east = std::fmod(std::fmod(lon_deg - g.lon_deg.start, 360.0) + 360.0, 360.0);
  const double span = g.lon_deg.last() - g.lon_deg.start;
  return east <= span + 1e-9 || east >= 360.0 - 1e-9;
}

std::string grid_extent_text(const VolumeGrid& g) {
  char buf[160];
  if (g.wraps_lon()) {
    std::snprintf(buf, sizeof buf, "lat %.6g..%.6g, all longitudes", g.lat_deg.start, g.lat_deg.last());
  } else {
    std::snprintf(buf, sizeof buf, "lat %.6g..%.6g, lon %.6g..%.6g", g.lat_deg.start, g.lat_deg.last(), g.lon_deg.start,
                  g.lon_deg.last());
  }
  return buf;
}

ColumnProbe probe_column(const CloudVolume& volume, const TimeStepData& data, const GridMeanExtinction& medium, double lat_deg,
                         double lon_deg, const MapOptions& options) {
  const VolumeGrid& g = volume.grid;
  if (!grid_holds(g, lat_deg, lon_deg)) {
    throw std::invalid_argument("the point lies outside the data (" + grid_extent_text(g) + ")");
  }
  ColumnProbe c;
  c.lat_deg = lat_deg;
  c.lon_deg = lon_deg;
  // The ground: a one-level grid of the same columns, through the same sampler.
  c.ground_m = kNaN;
  if (data.ground_m.size() == g.columns()) {
    VolumeGrid flat = g;
    flat.alt_m.count = 1;
    c.ground_m = VolumeSampler(flat, data.ground_m).sample(lat_deg, lon_deg, flat.alt_m.start, kNaN);
  }
  const double ground = std::isfinite(c.ground_m) ? c.ground_m : 0.0;
  const std::vector<float> none;
  auto field = [&](Field f) -> const std::vector<float>& { return data[f]; };
  const VolumeSampler cf(g, field(Field::CloudFraction)), el(g, field(Field::ExtinctionLiquid)), ei(g, field(Field::ExtinctionIce));
  const VolumeSampler ml(g, medium.liquid_per_m), mi(g, medium.ice_per_m);
  const VolumeSampler t(g, field(Field::Temperature)), u(g, field(Field::WindU)), v(g, field(Field::WindV)), w(g, field(Field::WindW));
  const VolumeSampler pr(g, field(Field::Pressure));
  const bool has_cf = !field(Field::CloudFraction).empty();
  MaxRandomOverlap overlap;
  c.base_m = c.top_m = kNaN;
  std::vector<bool> have(static_cast<std::size_t>(g.alt_m.count), false);
  c.levels.resize(static_cast<std::size_t>(g.alt_m.count));
  for (int k = 0; k < g.alt_m.count; ++k) {
    ProbeLevel& l = c.levels[static_cast<std::size_t>(k)];
    const double alt = g.alt_m.at(k);
    l.alt_m = alt;
    l.above_ground_m = alt - ground;
    l.ext_liquid_per_m = el.sample(lat_deg, lon_deg, alt, 0.0);
    l.ext_ice_per_m = ei.sample(lat_deg, lon_deg, alt, 0.0);
    const double ext = l.ext_liquid_per_m + l.ext_ice_per_m;
    // Without a fraction field, water fills its box (derive_maps' rule).
    l.cloud_fraction = has_cf ? cf.sample(lat_deg, lon_deg, alt, 0.0) : (ext > 0.0 ? 1.0 : 0.0);
    l.march_liquid_per_m = ml.sample(lat_deg, lon_deg, alt, 0.0);
    l.march_ice_per_m = mi.sample(lat_deg, lon_deg, alt, 0.0);
    l.temperature_k = t.sample(lat_deg, lon_deg, alt, kNaN);
    l.wind_u_m_s = u.sample(lat_deg, lon_deg, alt, kNaN);
    l.wind_v_m_s = v.sample(lat_deg, lon_deg, alt, kNaN);
    l.wind_w_m_s = w.sample(lat_deg, lon_deg, alt, kNaN);
    l.pressure_pa = pr.sample(lat_deg, lon_deg, alt, kNaN);
    // A level without data in any cloud field is left out of the summary, as derive_maps leaves it.
    have[static_cast<std::size_t>(k)] = std::isfinite(cf.sample(lat_deg, lon_deg, alt, kNaN)) ||
                                        std::isfinite(el.sample(lat_deg, lon_deg, alt, kNaN)) ||
                                        std::isfinite(ei.sample(lat_deg, lon_deg, alt, kNaN));
  }
  // Top down, as derive_maps walks a column.
  for (int k = g.alt_m.count - 1; k >= 0; --k) {
    const ProbeLevel& l = c.levels[static_cast<std::size_t>(k)];
    if (!have[static_cast<std::size_t>(k)]) continue;
    if (map_cloudy(l.cloud_fraction, l.ext_liquid_per_m + l.ext_ice_per_m, options)) {
      overlap.add(l.cloud_fraction);
      if (std::isnan(c.top_m)) c.top_m = l.alt_m;
      c.base_m = l.alt_m;
    } else {
      overlap.gap();
    }
  }
  c.cover = overlap.cover();
  // The trapezoid of the sampled grid-mean extinction (column_depth's rule: the ends count half).
  const int nz = g.alt_m.count;
  double sum = 0.0;
  for (int k = 0; k < nz; ++k) {
    const ProbeLevel& l = c.levels[static_cast<std::size_t>(k)];
    const double s = l.march_liquid_per_m + l.march_ice_per_m;
    sum += k == 0 || k == nz - 1 ? 0.5 * s : s;
  }
  c.optical_depth = nz > 1 ? sum * g.alt_m.step : 0.0;
  return c;
}

ViewRayProbe probe_view_ray(const PreparedVolume& volume, double cam_lat_deg, double cam_lon_deg, double cam_alt_m,
                            double target_lat_deg, double target_lon_deg, double target_alt_m, double view_step_m) {
  if (!(view_step_m > 0.0)) throw std::invalid_argument("probe_view_ray: the view step must be > 0");
  const double r0 = volume.grid.earth_radius_m;
  const glm::dvec3 from = geo::sphere_to_ecef({cam_lat_deg, cam_lon_deg, cam_alt_m}, r0);
  const glm::dvec3 to = geo::sphere_to_ecef({target_lat_deg, target_lon_deg, target_alt_m}, r0);
  const glm::dvec3 d = to - from;
  const double dist = glm::length(d);
  if (!(dist > 0.0)) throw std::invalid_argument("the camera stands at the probed point: no view ray");
  // One pixel whose ray is the camera's forward axis, turned toward the point.
  const geo::EnuFrame f = geo::sphere_enu(cam_lat_deg, cam_lon_deg);
  const glm::dvec3 n = d / dist;
  Camera cam;
  cam.lat_deg = cam_lat_deg;
  cam.lon_deg = cam_lon_deg;
  cam.alt_m = cam_alt_m;
  cam.heading_deg = std::atan2(glm::dot(n, f.east), glm::dot(n, f.north)) * 180.0 / M_PI;
  cam.pitch_deg = std::asin(std::clamp(glm::dot(n, f.up), -1.0, 1.0)) * 180.0 / M_PI;
  cam.fov_deg = 1.0;
  cam.width = cam.height = 1;
  MarchSettings s;
  s.quality.view_step_m = view_step_m;
  s.quality.min_transmittance = 0.0;  // follow the ray to its end: the transmittance is wanted whole
  const ReferenceImage img = render_reference(volume, cam, Sun{}, s);
  ViewRayProbe p;
  p.distance_to_target_m = dist;
  p.view_step_m = view_step_m;
  p.transmittance = img.transmittance[0];
  p.first_cloud_m = img.first_cloud_m[0] < 1e38 ? img.first_cloud_m[0] : -1.0;
  p.half_transmittance_m = img.cloud_depth_m[0] < 1e38 ? img.cloud_depth_m[0] : -1.0;
  return p;
}

}  // namespace cv::core
