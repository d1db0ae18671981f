// The globe's ground albedo as an image, for the march kernel to fetch (render::load_albedo_map
// decodes it; core reads no images).
#pragma once

#include <vector>

namespace cv::core {

// An equirectangular ground albedo image: linear rgb per texel, rows from latitude 90 down to -90,
// columns from longitude -180 east to 180.
struct AlbedoMap {
  int width = 0, height = 0;
  std::vector<float> rgb;
};

}  // namespace cv::core
