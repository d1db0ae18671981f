// Whether a whole cloud layer lies in the Earth's shadow.
#include "reference/earth_shadow.hpp"

#include <algorithm>
#include <cmath>

#include <glm/glm.hpp>

#include "geo/geodesy.hpp"

namespace cv::core {
namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;
// Samples per boundary edge: the spacing between them is at most the edge's length / kEdgeSamples.
constexpr int kEdgeSamples = 2048;
// Kept off the threshold besides the spacing (radians, ~6 km at the surface): the GPU decides
// each sample's light in float, whose positions near the Earth round to ~0.5 m and whose
// directions to ~1e-7 rad; a layer this close to the terminator is simply marched per sample.
constexpr double kFloatMargin = 1e-3;
}  // namespace

bool layer_in_earth_shadow(const VolumeGrid& grid, const CloudLayer& layer, const glm::dvec3& to_sun) {
  if (layer.empty || grid.wraps_lon() || grid.lon_deg.count < 1 || grid.lat_deg.count < 1) return false;
  // The domain with the border cell the sampler fades over.
  const double west = grid.lon_deg.start - grid.lon_deg.step, east = grid.lon_deg.last() + grid.lon_deg.step;
  const double south = std::max(grid.lat_deg.start - grid.lat_deg.step, -90.0);
  const double north = std::min(grid.lat_deg.last() + grid.lat_deg.step, 90.0);
  if (east - west >= 360.0) return false;
  const glm::dvec3 sun = glm::normalize(to_sun);
  // The subsolar point inside the box: lit.
  const double sun_lat = std::asin(std::clamp(sun.z, -1.0, 1.0)) / kDeg;
  const double sun_lon = std::atan2(sun.y, sun.x) / kDeg;
  const double sun_east = std::fmod(std::fmod(sun_lon - west, 360.0) + 360.0, 360.0);  // degrees east of the west side
  if (sun_lat >= south && sun_lat <= north && sun_east <= east - west) return false;
  // In the shadow at radius r: angle from the antisolar point below asin(R / r), i.e. the angle
  // theta from the subsolar point above pi - asin(R / r). The layer's top is the hardest.
  const double r0 = grid.earth_radius_m, r = r0 + std::max(layer.top_m, 0.0);
  const double theta_min = kPi - std::asin(std::min(r0 / r, 1.0));
  // The smallest angle from the subsolar point over the boundary, sampled; a point between two
  // samples is within half their spacing of one (the angle is 1-Lipschitz along the boundary).
  double smallest = kPi;
  auto visit = [&](double lat_deg, double lon_deg) {
    const glm::dvec3 u = geo::sphere_to_ecef({lat_deg, lon_deg, 0.0}, 1.0);
    smallest = std::min(smallest, std::acos(std::clamp(glm::dot(u, sun), -1.0, 1.0)));
  };
  for (int i = 0; i <= kEdgeSamples; ++i) {
    const double f = static_cast<double>(i) / kEdgeSamples;
    const double lon = west + f * (east - west), lat = south + f * (north - south);
    visit(south, lon);
    visit(north, lon);
    visit(lat, west);
    visit(lat, east);
  }
  // The longest spacing: a meridian step, or a step along the parallel nearest the equator.
  const double equator_lat = south > 0.0 ? south : (north < 0.0 ? north : 0.0);
  const double spacing = std::max((north - south), (east - west) * std::cos(equator_lat * kDeg)) * kDeg / kEdgeSamples;
  return smallest - spacing - kFloatMargin > theta_min;
}

}  // namespace cv::core
