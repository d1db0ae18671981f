// The viewer's derived quantities: the sun from the scene's spec, the march size, change detection.
#include "viewer/viewer_state.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>

#include "geo/solar.hpp"

namespace cv::viewer {

std::int64_t parse_iso_utc(const std::string& text) {
  int y = 0, mo = 0, d = 0, h = 0, mi = 0, s = 0, used = 0;
  const int n = std::sscanf(text.c_str(), "%4d-%2d-%2dT%2d:%2d%n:%2d%n", &y, &mo, &d, &h, &mi, &used, &s, &used);
  std::string rest = n >= 5 ? text.substr(static_cast<std::size_t>(used)) : text;
  if (rest == "Z") rest.clear();
  if (n < 5 || !rest.empty() || mo < 1 || mo > 12 || d < 1 || d > 31 || h > 23 || mi > 59 || s > 60) {
    throw ViewerInputError("date/time: found '" + text + "', expected YYYY-MM-DDThh:mm[:ss]Z in UTC");
  }
  std::tm tm{};
  tm.tm_year = y - 1900;
  tm.tm_mon = mo - 1;
  tm.tm_mday = d;
  tm.tm_hour = h;
  tm.tm_min = mi;
  tm.tm_sec = s;
  return static_cast<std::int64_t>(timegm(&tm));  // UTC, unlike mktime
}

core::Sun resolve_sun(const core::Scene& scene, const core::CloudVolume& volume) {
  core::Sun sun;
  sun.irradiance = glm::dvec3(scene.sun.irradiance);
  const std::size_t step = static_cast<std::size_t>(std::max(0, scene.time_step));
  switch (scene.sun.mode) {
    case core::SunMode::Manual:
      sun.subsolar_lat_deg = scene.sun.subsolar_lat_deg;
      sun.subsolar_lon_deg = scene.sun.subsolar_lon_deg;
      return sun;
    case core::SunMode::DateTime: {
      const geo::SubsolarPoint p = geo::subsolar_point(parse_iso_utc(scene.sun.datetime_utc));
      sun.subsolar_lat_deg = p.lat_deg;
      sun.subsolar_lon_deg = p.lon_deg;
      return sun;
    }
    case core::SunMode::ValidTime:
      break;
  }
  // A valid time without a 'T' is a bare step index (the file had no usable time axis).
  if (step < volume.times.size() && volume.times[step].iso_utc.find('T') != std::string::npos) {
    const geo::SubsolarPoint p = geo::subsolar_point(volume.times[step].unix_s);
    sun.subsolar_lat_deg = p.lat_deg;
    sun.subsolar_lon_deg = p.lon_deg;
  } else if (scene.camera) {
    sun.subsolar_lon_deg = scene.camera->lon_deg;
  }
  return sun;
}

void march_size(const core::Scene& scene, int window_w, int window_h, int& w, int& h) {
  const double s = std::clamp(scene.render.resolution_scale, 0.05, 1.0);
  w = std::max(1, static_cast<int>(std::lround(window_w * s)));
  h = std::max(1, static_cast<int>(std::lround(window_h * s)));
}

namespace {
bool same_camera(const std::optional<core::Camera>& a, const std::optional<core::Camera>& b) {
  if (a.has_value() != b.has_value()) return false;
  if (!a) return true;
  return a->lat_deg == b->lat_deg && a->lon_deg == b->lon_deg && a->alt_m == b->alt_m && a->heading_deg == b->heading_deg &&
         a->pitch_deg == b->pitch_deg && a->fov_deg == b->fov_deg && a->width == b->width && a->height == b->height;
}
bool same_settings(const core::MarchSettings& a, const core::MarchSettings& b) {
  // `frame` is the accumulation's own counter, not a setting.
  return a.view_step_m == b.view_step_m && a.sun_steps == b.sun_steps && a.octaves == b.octaves && a.octave_a == b.octave_a &&
         a.octave_b == b.octave_b && a.octave_c == b.octave_c && a.droplet_diameter_um == b.droplet_diameter_um &&
         a.ice_g == b.ice_g;
}
}  // namespace

bool same_march(const core::Scene& a, const core::Scene& b) {
  return a.data.path == b.data.path && a.time_step == b.time_step && same_camera(a.camera, b.camera) && a.width == b.width &&
         a.height == b.height && a.sun.mode == b.sun.mode && a.sun.datetime_utc == b.sun.datetime_utc &&
         a.sun.subsolar_lat_deg == b.sun.subsolar_lat_deg && a.sun.subsolar_lon_deg == b.sun.subsolar_lon_deg &&
         a.sun.irradiance == b.sun.irradiance && same_settings(a.render.march, b.render.march) &&
         a.render.resolution_scale == b.render.resolution_scale;
}

}  // namespace cv::viewer
