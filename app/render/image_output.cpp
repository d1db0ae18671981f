// Tonemapping and image files.
#include "render/image_output.hpp"

#include <stb_image_write.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "volume/volume_io.hpp"

namespace cv::render {
namespace {
// A filmic curve (Narkowicz's fit of the ACES reference tone scale): toe and shoulder, 1 at white.
double filmic(double x) { return std::clamp(x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0); }
double srgb(double linear) {
  return linear <= 0.0031308 ? 12.92 * linear : 1.055 * std::pow(linear, 1.0 / 2.4) - 0.055;
}
}  // namespace

std::vector<unsigned char> tonemap_srgb8(const std::vector<glm::vec4>& pixels, const ToneSettings& tone) {
  std::vector<unsigned char> out;
  out.reserve(pixels.size() * 3);
  for (const auto& p : pixels) {
    for (int c = 0; c < 3; ++c) {
      const double v = tone.exposure * p[c] + p.w * tone.background[c];
      const double e = std::isfinite(v) ? srgb(filmic(v)) : 1.0;  // a non-finite pixel shows white, never noise
      out.push_back(static_cast<unsigned char>(std::lround(std::clamp(e, 0.0, 1.0) * 255.0)));
    }
  }
  return out;
}

void write_png(const std::string& path, int width, int height, const std::vector<unsigned char>& rgb8) {
  core::write_file_atomically(path, [&](std::FILE* f) {
    // A C callback cannot throw: a short write shows in ferror() below.
    auto sink = [](void* ctx, void* data, int size) { std::fwrite(data, 1, static_cast<std::size_t>(size), static_cast<std::FILE*>(ctx)); };
    if (!stbi_write_png_to_func(sink, f, width, height, 3, rgb8.data(), width * 3)) throw std::runtime_error("PNG encoding failed");
    if (std::ferror(f)) throw std::runtime_error("write failed");
  });
}

void write_pfm(const std::string& path, int width, int height, const std::vector<glm::vec4>& pixels,
               const ToneSettings& tone) {
  core::write_file_atomically(path, [&](std::FILE* f) {
    // PFM stores rows bottom to top; a negative scale means little-endian.
    std::fprintf(f, "PF\n%d %d\n-1.0\n", width, height);
    std::vector<float> row(static_cast<std::size_t>(width) * 3);
    for (int y = height - 1; y >= 0; --y) {
      for (int x = 0; x < width; ++x) {
        const auto& p = pixels[static_cast<std::size_t>(y) * width + x];
        for (int c = 0; c < 3; ++c) row[static_cast<std::size_t>(x) * 3 + c] = static_cast<float>(p[c] + p.w * tone.background[c]);
      }
      if (std::fwrite(row.data(), sizeof(float), row.size(), f) != row.size()) throw std::runtime_error("write failed");
    }
  });
}

}  // namespace cv::render
