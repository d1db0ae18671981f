// Geodesy: the spherical-Earth helpers of the physics core against GeographicLib (on a sphere,
// f = 0), WGS84 round trips, local frames, and geopotential to height.
#include <gtest/gtest.h>

#include <cmath>

#include <GeographicLib/Geocentric.hpp>

#include "geo/geodesy.hpp"
#include "physics/physics.hpp"

namespace {
using namespace cv::geo;

TEST(Geodesy, SphereMatchesGeographicLibWithZeroFlattening) {
  const GeographicLib::Geocentric sphere(kEarthRadiusM, 0.0);
  for (double lat = -90; lat <= 90; lat += 7.5) {
    for (double lon = -180; lon < 180; lon += 15) {
      for (double alt : {0.0, 0.1, 1e4, 4e8}) {
        double x, y, z;
        sphere.Forward(lat, lon, alt, x, y, z);
        const glm::dvec3 p = sphere_to_ecef({lat, lon, alt});
        const double tol = 1e-9 * (kEarthRadiusM + alt);
        EXPECT_NEAR(p.x, x, tol);
        EXPECT_NEAR(p.y, y, tol);
        EXPECT_NEAR(p.z, z, tol);
        const Geodetic back = ecef_to_sphere(p);
        EXPECT_NEAR(back.lat_deg, lat, 1e-9);
        if (std::abs(lat) < 90) {
          EXPECT_NEAR(wrap_lon_deg(back.lon_deg - lon), 0.0, 1e-9);
        }
        EXPECT_NEAR(back.alt_m, alt, 1e-6 + 1e-15 * alt);
      }
    }
  }
}

TEST(Geodesy, Wgs84RoundTripAndKnownValues) {
  // The equator at 0E is one semi-major axis from the centre; the pole is at the semi-minor axis.
  glm::dvec3 p = wgs84_to_ecef({0, 0, 0});
  EXPECT_NEAR(p.x, 6378137.0, 1e-6);
  p = wgs84_to_ecef({90, 0, 0});
  EXPECT_NEAR(p.z, 6356752.314245, 1e-5);
  for (double lat : {-89.9, -45.0, 0.0, 30.0, 89.9}) {
    const Geodetic g = ecef_to_wgs84(wgs84_to_ecef({lat, 123.4, 5000.0}));
    EXPECT_NEAR(g.lat_deg, lat, 1e-10);
    EXPECT_NEAR(g.lon_deg, 123.4, 1e-10);
    EXPECT_NEAR(g.alt_m, 5000.0, 1e-6);
  }
  // One degree of longitude on the equator: a * pi / 180.
  EXPECT_NEAR(wgs84_geodesic_distance_m(0, 0, 0, 1), 6378137.0 * 3.14159265358979323846 / 180.0, 1e-6);
}

TEST(Geodesy, LocalFramesAreOrthonormalAndRightHanded) {
  for (double lat : {-90.0, -60.0, 0.0, 45.0, 90.0}) {
    for (double lon : {-180.0, -10.0, 0.0, 179.9}) {
      const EnuFrame f = sphere_enu(lat, lon);
      EXPECT_NEAR(glm::length(f.east), 1.0, 1e-15);
      EXPECT_NEAR(glm::length(f.north), 1.0, 1e-15);
      EXPECT_NEAR(glm::dot(f.east, f.north), 0.0, 1e-15);
      EXPECT_NEAR(glm::length(glm::cross(f.east, f.north) - f.up), 0.0, 1e-15);
      const glm::dvec3 radial = glm::normalize(sphere_to_ecef({lat, lon, 100.0}));
      EXPECT_NEAR(glm::length(radial - f.up), 0.0, 1e-12);
      // On the ellipsoid, up is the normal: moving along it changes only the height.
      const EnuFrame w = wgs84_enu(lat, lon);
      const Geodetic moved = ecef_to_wgs84(wgs84_to_ecef({lat, lon, 0.0}) + 1000.0 * w.up);
      EXPECT_NEAR(moved.alt_m, 1000.0, 1e-6);
    }
  }
}

TEST(Geodesy, WrapLongitude) {
  EXPECT_DOUBLE_EQ(wrap_lon_deg(190.0), -170.0);
  EXPECT_DOUBLE_EQ(wrap_lon_deg(-180.0), -180.0);
  EXPECT_DOUBLE_EQ(wrap_lon_deg(180.0), -180.0);
  EXPECT_DOUBLE_EQ(wrap_lon_deg(359.5), -0.5);
  EXPECT_DOUBLE_EQ(wrap_lon_deg(-540.0), -180.0);
}

TEST(Geodesy, GeopotentialToHeight) {
  // z = Phi R / (g0 R - Phi): about 16 m above Phi / g0 at 10 km.
  const double phi = 9.80665 * 10000.0;
  const double z = cv::physics::f64::geopotential_to_height_m(phi, kEarthRadiusM);
  EXPECT_NEAR(z, 10000.0 * kEarthRadiusM / (kEarthRadiusM - 10000.0), 1e-9);
  EXPECT_NEAR(z - 10000.0, 15.72, 0.01);
  EXPECT_DOUBLE_EQ(cv::physics::f64::geopotential_to_height_m(0.0, kEarthRadiusM), 0.0);
}

}  // namespace

#include "geo/solar.hpp"

namespace {

std::int64_t utc(int y, int m, int d, int h, int mi) {
  // Days from 1970-01-01 to y-m-d (proleptic Gregorian), then the time of day.
  const int yy = y - (m <= 2);
  const long era = (yy >= 0 ? yy : yy - 399) / 400;
  const long yoe = yy - era * 400;
  const long doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
  const long days = era * 146097 + yoe * 365 + yoe / 4 - yoe / 100 + doy - 719468;
  return static_cast<std::int64_t>(days) * 86400 + h * 3600 + mi * 60;
}

TEST(Solar, SolsticesEquinoxAndLocalNoon) {
  using cv::geo::subsolar_point;
  // Almanac instants of 2024: June solstice 20 Jun 20:51 UTC, December solstice 21 Dec 09:21,
  // March equinox 20 Mar 03:06.
  EXPECT_NEAR(subsolar_point(utc(2024, 6, 20, 20, 51)).lat_deg, 23.44, 0.02);
  EXPECT_NEAR(subsolar_point(utc(2024, 12, 21, 9, 21)).lat_deg, -23.44, 0.02);
  EXPECT_NEAR(subsolar_point(utc(2024, 3, 20, 3, 6)).lat_deg, 0.0, 0.02);
  // At 12:00 UTC the sun stands over Greenwich within the equation of time (at most ~16 minutes,
  // 4 degrees): on 3 November it runs ~16 min fast, putting noon at 4.1 degrees west.
  EXPECT_NEAR(subsolar_point(utc(2024, 11, 3, 12, 0)).lon_deg, -4.1, 0.15);
  // And the sun moves west 15 degrees an hour.
  const double a = subsolar_point(utc(2024, 1, 15, 0, 0)).lon_deg, b = subsolar_point(utc(2024, 1, 15, 1, 0)).lon_deg;
  EXPECT_NEAR(cv::geo::wrap_lon_deg(a - b), 15.0, 0.01);
}

}  // namespace
