// Low-precision solar coordinates (Astronomical Almanac, section C) and Greenwich mean sidereal time.
#include "geo/solar.hpp"

#include <cmath>

#include "geo/geodesy.hpp"

namespace cv::geo {

SubsolarPoint subsolar_point(std::int64_t unix_s) {
  constexpr double kDeg = 3.14159265358979323846 / 180.0;
  const double n = static_cast<double>(unix_s) / 86400.0 + 2440587.5 - 2451545.0;  // days from J2000.0
  const double mean_lon = 280.460 + 0.9856474 * n;
  const double anomaly = (357.528 + 0.9856003 * n) * kDeg;
  const double ecl_lon = (mean_lon + 1.915 * std::sin(anomaly) + 0.020 * std::sin(2.0 * anomaly)) * kDeg;
  const double obliquity = (23.439 - 0.0000004 * n) * kDeg;
  const double ra = std::atan2(std::cos(obliquity) * std::sin(ecl_lon), std::cos(ecl_lon));
  const double dec = std::asin(std::sin(obliquity) * std::sin(ecl_lon));
  const double gmst_h = 18.697374558 + 24.06570982441908 * n;
  SubsolarPoint s;
  s.lat_deg = dec / kDeg;
  s.lon_deg = wrap_lon_deg(ra / kDeg - 15.0 * gmst_h);
  return s;
}

}  // namespace cv::geo
