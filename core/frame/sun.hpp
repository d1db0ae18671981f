// The sun of a frame.
#pragma once

#include <glm/vec3.hpp>

namespace cv::core {

// The sun by its subsolar point (where it stands at the zenith) and the irradiance it delivers
// perpendicular to its rays at the top of the cloud layer (per channel, W/m2 or relative units).
struct Sun {
  double subsolar_lat_deg = 0.0, subsolar_lon_deg = 0.0;
  glm::dvec3 irradiance{1.0, 1.0, 1.0};
};

}  // namespace cv::core
