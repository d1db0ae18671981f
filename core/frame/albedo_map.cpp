// The ground map's identity (frame/albedo_map.hpp).
#include "frame/albedo_map.hpp"

namespace cv::core {

std::uint64_t albedo_map_id(const AlbedoMap& m) {
  std::uint64_t h = 1469598103934665603ull;  // FNV-1a, 64 bits
  auto add = [&h](const void* data, std::size_t n) {
    const auto* b = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 1099511628211ull;
  };
  add(&m.width, sizeof m.width);
  add(&m.height, sizeof m.height);
  if (!m.rgba.empty()) add(m.rgba.data(), m.rgba.size() * sizeof(float));
  return h == 0 ? 1 : h;
}

}  // namespace cv::core
