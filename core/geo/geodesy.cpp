// Geodesy: spherical Earth through the shared physics core, WGS84 through GeographicLib.
#include "geo/geodesy.hpp"

#include <cmath>

#include <GeographicLib/Geocentric.hpp>
#include <GeographicLib/Geodesic.hpp>
#include <GeographicLib/GeodesicLine.hpp>

#include "physics/physics.hpp"

namespace cv::geo {
namespace {
constexpr double kDegToRad = 3.14159265358979323846 / 180.0;
constexpr double kRadToDeg = 180.0 / 3.14159265358979323846;

EnuFrame frame_at(double lat_deg, double lon_deg) {
  EnuFrame f;
  physics::f64::enu_frame(lat_deg * kDegToRad, lon_deg * kDegToRad, f.east, f.north, f.up);
  return f;
}
}  // namespace

glm::dvec3 sphere_to_ecef(const Geodetic& p, double radius_m) {
  return physics::f64::sphere_to_ecef(p.lat_deg * kDegToRad, p.lon_deg * kDegToRad, p.alt_m, radius_m);
}

Geodetic ecef_to_sphere(const glm::dvec3& ecef_m, double radius_m) {
  const glm::dvec3 g = physics::f64::ecef_to_sphere(ecef_m, radius_m);
  return {g.x * kRadToDeg, g.y * kRadToDeg, g.z};
}

EnuFrame sphere_enu(double lat_deg, double lon_deg) { return frame_at(lat_deg, lon_deg); }

glm::dvec3 wgs84_to_ecef(const Geodetic& p) {
  glm::dvec3 out;
  GeographicLib::Geocentric::WGS84().Forward(p.lat_deg, p.lon_deg, p.alt_m, out.x, out.y, out.z);
  return out;
}

Geodetic ecef_to_wgs84(const glm::dvec3& ecef_m) {
  Geodetic g;
  GeographicLib::Geocentric::WGS84().Reverse(ecef_m.x, ecef_m.y, ecef_m.z, g.lat_deg, g.lon_deg, g.alt_m);
  return g;
}

// On the ellipsoid the normal (up) is along the geodetic latitude, so the ENU frame has the same
// form as on the sphere with geodetic latitude; only positions differ.
EnuFrame wgs84_enu(double lat_deg, double lon_deg) { return frame_at(lat_deg, lon_deg); }

double wgs84_geodesic_distance_m(double lat1_deg, double lon1_deg, double lat2_deg, double lon2_deg) {
  double s12 = 0.0;
  GeographicLib::Geodesic::WGS84().Inverse(lat1_deg, lon1_deg, lat2_deg, lon2_deg, s12);
  return s12;
}

double great_circle_distance_m(double lat1_deg, double lon1_deg, double lat2_deg, double lon2_deg, double radius_m) {
  double s12 = 0.0;
  GeographicLib::Geodesic(radius_m, 0.0).Inverse(lat1_deg, lon1_deg, lat2_deg, lon2_deg, s12);
  return s12;
}

std::vector<PathPoint> great_circle_points(double lat1_deg, double lon1_deg, double lat2_deg, double lon2_deg, int count,
                                           double radius_m) {
  const GeographicLib::Geodesic sphere(radius_m, 0.0);
  const GeographicLib::GeodesicLine line = sphere.InverseLine(lat1_deg, lon1_deg, lat2_deg, lon2_deg);
  std::vector<PathPoint> out;
  const int n = count < 2 ? 2 : count;
  out.reserve(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    PathPoint p;
    p.distance_m = line.Distance() * i / (n - 1);
    line.Position(p.distance_m, p.lat_deg, p.lon_deg);
    out.push_back(p);
  }
  return out;
}

double wrap_lon_deg(double lon_deg) {
  double w = std::fmod(lon_deg + 180.0, 360.0);
  if (w < 0.0) w += 360.0;
  return w - 180.0;
}

}  // namespace cv::geo
