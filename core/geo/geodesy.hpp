// Geodesy for cloudviewer: the spherical Earth the renderer draws (through the shared physics
// core) and the WGS84 ellipsoid (through GeographicLib) where the difference matters.
#pragma once

#include <vector>

#include <glm/vec3.hpp>

namespace cv::geo {

// Mean Earth radius of the spherical model, metres (same value as CV_EARTH_RADIUS_M in GLSL).
inline constexpr double kEarthRadiusM = 6371000.0;

// Latitude and longitude in degrees, altitude in metres above the surface of the model in use.
struct Geodetic {
  double lat_deg = 0.0;
  double lon_deg = 0.0;
  double alt_m = 0.0;
};

// Local east, north and up unit vectors in Earth-centred coordinates.
struct EnuFrame {
  glm::dvec3 east;
  glm::dvec3 north;
  glm::dvec3 up;
};

// Spherical Earth of radius radius_m: Earth-centred, Earth-fixed metres (x to 0N 0E, z to the pole).
glm::dvec3 sphere_to_ecef(const Geodetic& p, double radius_m = kEarthRadiusM);
Geodetic ecef_to_sphere(const glm::dvec3& ecef_m, double radius_m = kEarthRadiusM);
EnuFrame sphere_enu(double lat_deg, double lon_deg);

// WGS84 ellipsoid (GeographicLib): geodetic latitude, height above the ellipsoid.
glm::dvec3 wgs84_to_ecef(const Geodetic& p);
Geodetic ecef_to_wgs84(const glm::dvec3& ecef_m);
EnuFrame wgs84_enu(double lat_deg, double lon_deg);

// Length of the shortest path on the WGS84 ellipsoid between two points, metres.
double wgs84_geodesic_distance_m(double lat1_deg, double lon1_deg, double lat2_deg, double lon2_deg);

// The great circle on the sphere of radius radius_m (GeographicLib's geodesic with flattening 0)
// from point 1 to point 2: its length (m), and `count` points evenly along it, ends included
// (count >= 2), each with its distance from point 1 in alt_m's place.
double great_circle_distance_m(double lat1_deg, double lon1_deg, double lat2_deg, double lon2_deg, double radius_m = kEarthRadiusM);
struct PathPoint {
  double lat_deg = 0.0, lon_deg = 0.0, distance_m = 0.0;
};
std::vector<PathPoint> great_circle_points(double lat1_deg, double lon1_deg, double lat2_deg, double lon2_deg, int count,
                                           double radius_m = kEarthRadiusM);

// Longitude wrapped into [-180, 180).
double wrap_lon_deg(double lon_deg);

}  // namespace cv::geo
