// Loading the globe's ground albedo: an equirectangular image (the Natural Earth relief from
// Debian's python-cartopy-data) decoded with stb_image into linear albedo for the GPU and the CPU
// reference alike.
#pragma once

#include <string>

#include "frame/albedo_map.hpp"

namespace cv::render {

// Where python-cartopy-data installs the Natural Earth relief (720 x 360, lon -180..180).
constexpr const char* kNaturalEarthRelief = "/usr/share/cartopy/data/raster/natural_earth/50-natural-earth-1-downsampled.png";

// Decodes an 8-bit image (PNG, JPEG, ...) and turns its sRGB values into linear albedo. Throws
// std::runtime_error naming the file and what was wrong.
core::AlbedoMap load_albedo_map(const std::string& path);

// The texture a scene's ground_texture setting names: empty means the Natural Earth relief where it
// is installed (else the constant albedo), "none" the constant albedo, anything else is a path.
std::string resolve_ground_texture(const std::string& setting);

}  // namespace cv::render
