// Automatic camera framing, ISO date-time parsing and the scene's sun.
#include "scene/framing.hpp"

#include <algorithm>
#include <cmath>
#include <regex>
#include <stdexcept>

#include <glm/glm.hpp>

#include "geo/geodesy.hpp"
#include "geo/solar.hpp"

namespace cv::core {
namespace {
constexpr double kDegPerRad = 180.0 / 3.14159265358979323846;

bool leap(std::int64_t y) { return (y % 4 == 0 && y % 100 != 0) || y % 400 == 0; }

// Days from 0001-01-01 to 1 January of year y >= 1 (Gregorian leap rule throughout).
std::int64_t days_before_year(std::int64_t y) {
  const std::int64_t n = y - 1;
  return 365 * n + n / 4 - n / 100 + n / 400;
}
}  // namespace

Camera auto_camera(const VolumeGrid& g, int width, int height) {
  Camera cam;
  cam.width = width;
  cam.height = height;
  const double span = g.lat_deg.last() - g.lat_deg.start;
  const double lat_c = g.lat_deg.start + 0.5 * span, lon_c = g.lon_deg.start + 0.5 * (g.lon_deg.last() - g.lon_deg.start);
  cam.lat_deg = std::max(-89.0, g.lat_deg.start - 0.1 * span);
  cam.lon_deg = lon_c;
  cam.alt_m = 90000.0 * span;
  const glm::dvec3 eye = geo::sphere_to_ecef({cam.lat_deg, cam.lon_deg, cam.alt_m}, g.earth_radius_m);
  const glm::dvec3 target = geo::sphere_to_ecef({lat_c, lon_c, g.alt_m.start}, g.earth_radius_m);
  const glm::dvec3 dir = glm::normalize(target - eye);
  const geo::EnuFrame f = geo::sphere_enu(cam.lat_deg, cam.lon_deg);
  cam.pitch_deg = std::asin(glm::dot(dir, f.up)) * kDegPerRad;
  cam.heading_deg = std::atan2(glm::dot(dir, f.east), glm::dot(dir, f.north)) * kDegPerRad;
  cam.fov_deg = 60.0;
  return cam;
}

std::optional<std::int64_t> parse_iso_utc(const std::string& text) {
  static const std::regex iso(R"(^(\d{4})-(\d{2})-(\d{2})[T ](\d{2}):(\d{2})(?::(\d{2})(?:\.\d+)?)?Z?$)");
  std::smatch m;
  if (!std::regex_match(text, m, iso)) return std::nullopt;
  const std::int64_t y = std::stoll(m[1]);
  const int mo = std::stoi(m[2]), d = std::stoi(m[3]), h = std::stoi(m[4]), mi = std::stoi(m[5]);
  const int s = m[6].matched ? std::stoi(m[6]) : 0;
  static const int days_in[12] = {31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
  if (y < 1 || mo < 1 || mo > 12) return std::nullopt;
  const int dmax = days_in[mo - 1] + (mo == 2 && leap(y) ? 1 : 0);
  if (d < 1 || d > dmax || h > 23 || mi > 59 || s > 60) return std::nullopt;
  std::int64_t days = days_before_year(y) - days_before_year(1970) + d - 1;
  for (int k = 1; k < mo; ++k) days += days_in[k - 1] + (k == 2 && leap(y) ? 1 : 0);
  return days * 86400 + h * 3600 + mi * 60 + s;
}

const char* sun_mode_name(SunMode m) {
  switch (m) {
    case SunMode::ValidTime: return "valid_time";
    case SunMode::DateTime: return "datetime";
    case SunMode::Manual: return "manual";
    case SunMode::LocalNoon: return "local_noon";
  }
  return "valid_time";
}

bool parse_sun_mode(const std::string& text, SunMode& out) {
  for (SunMode m : {SunMode::ValidTime, SunMode::DateTime, SunMode::Manual, SunMode::LocalNoon}) {
    if (text == sun_mode_name(m)) {
      out = m;
      return true;
    }
  }
  return false;
}

Sun resolve_sun(const SunSpec& spec, const std::optional<std::int64_t>& valid_time_unix_s, double fallback_lon_deg) {
  Sun s;
  s.irradiance = glm::dvec3(spec.irradiance);
  std::optional<std::int64_t> when;
  switch (spec.mode) {
    case SunMode::Manual:
      s.subsolar_lat_deg = spec.subsolar_lat_deg;
      s.subsolar_lon_deg = spec.subsolar_lon_deg;
      return s;
    case SunMode::DateTime:
      when = parse_iso_utc(spec.datetime_utc);
      if (!when) throw std::invalid_argument("found '" + spec.datetime_utc + "', expected a UTC date-time YYYY-MM-DDThh:mm:ssZ");
      break;
    case SunMode::ValidTime:
      when = valid_time_unix_s;
      break;
    case SunMode::LocalNoon:  // the season's declination, the hour always noon over the camera
      s.subsolar_lat_deg = valid_time_unix_s ? geo::subsolar_point(*valid_time_unix_s).lat_deg : 0.0;
      s.subsolar_lon_deg = fallback_lon_deg;
      return s;
  }
  if (when) {
    const geo::SubsolarPoint sp = geo::subsolar_point(*when);
    s.subsolar_lat_deg = sp.lat_deg;
    s.subsolar_lon_deg = sp.lon_deg;
  } else {
    s.subsolar_lon_deg = fallback_lon_deg;  // no time known: noon over the given longitude
  }
  return s;
}

}  // namespace cv::core
