// Where the sun stands: the subsolar point at a UTC instant, from the low-precision solar
// coordinates of the Astronomical Almanac (about 0.01 degree in declination, 1900-2100).
#pragma once

#include <cstdint>

namespace cv::geo {

struct SubsolarPoint {
  double lat_deg = 0.0;  // the sun's declination
  double lon_deg = 0.0;  // where it is local apparent noon, in [-180, 180)
};

SubsolarPoint subsolar_point(std::int64_t unix_s);

}  // namespace cv::geo
