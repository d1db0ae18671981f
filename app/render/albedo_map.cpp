// Ground albedo images, decoded with stb_image.
#include "render/albedo_map.hpp"

#include <stb_image.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <stdexcept>

namespace cv::render {

core::AlbedoMap load_albedo_map(const std::string& path) {
  int w = 0, h = 0, channels = 0;
  std::unique_ptr<unsigned char, void (*)(void*)> data(stbi_load(path.c_str(), &w, &h, &channels, 3), stbi_image_free);
  if (!data) {
    throw std::runtime_error(path + ": cannot read the ground image (" + stbi_failure_reason() +
                             "), expected an equirectangular PNG or JPEG");
  }
  if (w < 2 || h < 2) throw std::runtime_error(path + ": the ground image is " + std::to_string(w) + " x " + std::to_string(h) +
                                               " pixels, expected at least 2 x 2");
  core::AlbedoMap m;
  m.width = w;
  m.height = h;
  m.rgb.resize(static_cast<std::size_t>(w) * h * 3);
  // The image stores sRGB-encoded reflectance; shading needs it linear.
  float lut[256];
  for (int i = 0; i < 256; ++i) {
    const double v = i / 255.0;
    lut[i] = static_cast<float>(v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4));
  }
  for (std::size_t i = 0; i < m.rgb.size(); ++i) m.rgb[i] = lut[data.get()[i]];
  return m;
}

std::string resolve_ground_texture(const std::string& setting) {
  if (setting == "none") return "";
  if (!setting.empty()) return setting;
  return std::filesystem::exists(kNaturalEarthRelief) ? kNaturalEarthRelief : "";
}

}  // namespace cv::render
