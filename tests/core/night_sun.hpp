// Test helpers: a sun placed relative to a point, and one just past the terminator of a standard
// scene's cloud layer (core::layer_in_earth_shadow), for the night tests on the CPU and the GPU.
#pragma once

#include <cmath>

#include <glm/glm.hpp>

#include "geo/geodesy.hpp"
#include "reference/earth_shadow.hpp"
#include "bench/standard_scenes.hpp"
#include "reference/raymarcher.hpp"

namespace cv::test {

inline constexpr double kNightDeg = 3.14159265358979323846 / 180.0;

// The sun direction at angular distance theta (deg) from (lat, lon), toward the given azimuth.
inline glm::dvec3 sun_at(double lat_deg, double lon_deg, double theta_deg, double azimuth_deg) {
  const cv::geo::EnuFrame f = cv::geo::sphere_enu(lat_deg, lon_deg);
  const glm::dvec3 dir = std::sin(azimuth_deg * kNightDeg) * f.east + std::cos(azimuth_deg * kNightDeg) * f.north;
  return std::cos(theta_deg * kNightDeg) * f.up + std::sin(theta_deg * kNightDeg) * dir;
}

// The sun just far enough past the terminator that the layer of a standard scene is dark; the air
// above it (to 60 km) is still sunlit there, so the sky in the image is not black.
inline core::Sun sun_just_down(const bench::StandardScene& sc) {
  const core::CloudLayer layer = core::cloud_layer(sc.grid, core::grid_mean_extinction(sc.grid, sc.data));
  const double lat = sc.grid.lat_deg.start + 0.5 * (sc.grid.lat_deg.last() - sc.grid.lat_deg.start);
  const double lon = sc.grid.lon_deg.start + 0.5 * (sc.grid.lon_deg.last() - sc.grid.lon_deg.start);
  double theta = 90.0;
  while (!core::layer_in_earth_shadow(sc.grid, layer, sun_at(lat, lon, theta, 90.0)) && theta < 180.0) theta += 0.1;
  const glm::dvec3 s = sun_at(lat, lon, theta + 0.3, 90.0);
  core::Sun sun = sc.sun;
  sun.subsolar_lat_deg = std::asin(s.z) / kNightDeg;
  sun.subsolar_lon_deg = std::atan2(s.y, s.x) / kNightDeg;
  return sun;
}

}  // namespace cv::test
