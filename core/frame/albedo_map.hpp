// The globe's ground as an image, for the march kernel to fetch (render::load_albedo_map decodes it
// and finds the water; core reads no images).
#pragma once

#include <vector>

namespace cv::core {

// An equirectangular ground image: per texel the linear albedo of its land (r, g, b) and the
// fraction of it that is water (a, 0..1: shaded as water, shaders/common/ground.glsl), rows from
// latitude 90 down to -90, columns from longitude -180 east to 180.
struct AlbedoMap {
  int width = 0, height = 0;
  std::vector<float> rgba;
};

}  // namespace cv::core
