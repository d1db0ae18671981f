// The globe's ground as an image, for the march kernel to fetch (render::load_albedo_map decodes it
// and finds the water; core reads no images).
#pragma once

#include <cstdint>
#include <vector>

namespace cv::core {

// An equirectangular ground image: per texel the linear albedo of its land (r, g, b) and the
// fraction of it that is water (a, 0..1: shaded as water, shaders/common/ground.glsl), rows from
// latitude 90 down to -90, columns from longitude -180 east to 180.
struct AlbedoMap {
  int width = 0, height = 0;
  std::vector<float> rgba;
  // What the map holds, for keys that must tell maps apart (the two-stream source's): a hash of its
  // size and texels (albedo_map_id). 0: not given, the map's address tells it apart.
  std::uint64_t id = 0;
};

// A hash of the map's size and texels (FNV-1a over their bytes), never 0.
std::uint64_t albedo_map_id(const AlbedoMap& m);

}  // namespace cv::core
