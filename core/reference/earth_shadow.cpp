// Whether a whole cloud layer lies in the Earth's shadow.
#include "reference/earth_shadow.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

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

// The domain with the border cell the sampler fades over; false for a grid all the way round.
struct Box {
  double west, east, south, north;
};
bool domain_box(const VolumeGrid& grid, Box& b) {
  if (grid.wraps_lon() || grid.lon_deg.count < 1 || grid.lat_deg.count < 1) return false;
  b.west = grid.lon_deg.start - grid.lon_deg.step, b.east = grid.lon_deg.last() + grid.lon_deg.step;
  b.south = std::max(grid.lat_deg.start - grid.lat_deg.step, -90.0);
  b.north = std::min(grid.lat_deg.last() + grid.lat_deg.step, 90.0);
  return b.east - b.west < 360.0;
}

// Whether a point (lat, lon in degrees) lies in the box, longitudes taken east of its west side.
bool in_box(const Box& b, double lat_deg, double lon_deg) {
  const double east_of_west = std::fmod(std::fmod(lon_deg - b.west, 360.0) + 360.0, 360.0);
  return lat_deg >= b.south && lat_deg <= b.north && east_of_west <= b.east - b.west;
}

// Visits kEdgeSamples + 1 points along each side of the box; returns the longest spacing between
// neighbours (radians of arc): a meridian step, or a step along the parallel nearest the equator.
template <class Visit>
double visit_boundary(const Box& b, Visit&& visit) {
  for (int i = 0; i <= kEdgeSamples; ++i) {
    const double f = static_cast<double>(i) / kEdgeSamples;
    const double lon = b.west + f * (b.east - b.west), lat = b.south + f * (b.north - b.south);
    visit(b.south, lon);
    visit(b.north, lon);
    visit(lat, b.west);
    visit(lat, b.east);
  }
  const double equator_lat = b.south > 0.0 ? b.south : (b.north < 0.0 ? b.north : 0.0);
  return std::max((b.north - b.south), (b.east - b.west) * std::cos(equator_lat * kDeg)) * kDeg / kEdgeSamples;
}

}  // namespace

double smallest_sun_cosine(const VolumeGrid& grid, const glm::dvec3& to_sun) {
  Box b;
  if (!domain_box(grid, b)) return -1.0;
  const glm::dvec3 sun = glm::normalize(to_sun);
  // The largest angle from the subsolar point over a box lies on its boundary unless the
  // antisolar point is inside it.
  if (in_box(b, -std::asin(std::clamp(sun.z, -1.0, 1.0)) / kDeg, std::atan2(-sun.y, -sun.x) / kDeg)) return -1.0;
  double largest = 0.0;
  const double spacing = visit_boundary(b, [&](double lat_deg, double lon_deg) {
    const glm::dvec3 u = geo::sphere_to_ecef({lat_deg, lon_deg, 0.0}, 1.0);
    largest = std::max(largest, std::acos(std::clamp(glm::dot(u, sun), -1.0, 1.0)));
  });
  return std::cos(std::min(largest + spacing + kFloatMargin, kPi));
}

double largest_sun_cosine(const VolumeGrid& grid, const glm::dvec3& to_sun) {
  Box b;
  if (!domain_box(grid, b)) return 1.0;
  const glm::dvec3 sun = glm::normalize(to_sun);
  // The smallest angle from the subsolar point over a box lies on its boundary unless the
  // subsolar point is inside it.
  if (in_box(b, std::asin(std::clamp(sun.z, -1.0, 1.0)) / kDeg, std::atan2(sun.y, sun.x) / kDeg)) return 1.0;
  double smallest = kPi;
  const double spacing = visit_boundary(b, [&](double lat_deg, double lon_deg) {
    const glm::dvec3 u = geo::sphere_to_ecef({lat_deg, lon_deg, 0.0}, 1.0);
    smallest = std::min(smallest, std::acos(std::clamp(glm::dot(u, sun), -1.0, 1.0)));
  });
  return std::cos(std::max(smallest - spacing - kFloatMargin, 0.0));
}

double highest_sun_elevation_deg(const VolumeGrid& grid, const glm::dvec3& to_sun) {
  return 90.0 - std::acos(std::clamp(largest_sun_cosine(grid, to_sun), -1.0, 1.0)) / kDeg;
}

std::string low_sun_words(double highest_deg) {
  char text[160];
  if (highest_deg >= 0.0) {
    std::snprintf(text, sizeof text, "the sun stands at most %.1f degrees above the horizon over the data (dawn or dusk there)", highest_deg);
  } else {
    std::snprintf(text, sizeof text, "the sun stands below the horizon over all the data, at least %.1f degrees below it (%s there)",
                  -highest_deg, highest_deg >= -18.0 ? "twilight" : "night");
  }
  return text;
}

bool layer_in_earth_shadow(const VolumeGrid& grid, const CloudLayer& layer, const glm::dvec3& to_sun) {
  Box b;
  if (layer.empty || !domain_box(grid, b)) return false;
  const glm::dvec3 sun = glm::normalize(to_sun);
  // The subsolar point inside the box: lit.
  if (in_box(b, std::asin(std::clamp(sun.z, -1.0, 1.0)) / kDeg, std::atan2(sun.y, sun.x) / kDeg)) return false;
  // In the shadow at radius r: angle from the antisolar point below asin(R / r), i.e. the angle
  // theta from the subsolar point above pi - asin(R / r). The layer's top is the hardest.
  const double r0 = grid.earth_radius_m, r = r0 + std::max(layer.top_m, 0.0);
  const double theta_min = kPi - std::asin(std::min(r0 / r, 1.0));
  // The smallest angle from the subsolar point over the boundary, sampled; a point between two
  // samples is within half their spacing of one (the angle is 1-Lipschitz along the boundary).
  double smallest = kPi;
  const double spacing = visit_boundary(b, [&](double lat_deg, double lon_deg) {
    const glm::dvec3 u = geo::sphere_to_ecef({lat_deg, lon_deg, 0.0}, 1.0);
    smallest = std::min(smallest, std::acos(std::clamp(glm::dot(u, sun), -1.0, 1.0)));
  });
  return smallest - spacing - kFloatMargin > theta_min;
}

}  // namespace cv::core
