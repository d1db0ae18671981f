// Tonemapping and image files.
#include "render/image_output.hpp"

#include <stb_image.h>
#include <stb_image_write.h>

#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <cerrno>
#include <cstdio>
#include <cstring>
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

namespace {
// The texel below output pixel o of m when n texels stretch over m pixels (present.frag texel_below).
int texel_below(int o, int n, int m, int& i1, float& t) {
  const float f = std::clamp((static_cast<float>(o) + 0.5f) * static_cast<float>(n) / static_cast<float>(m) - 0.5f, 0.0f,
                             static_cast<float>(n - 1));
  const int i0 = static_cast<int>(f);
  i1 = std::min(i0 + 1, n - 1);
  t = f - static_cast<float>(i0);
  return i0;
}
glm::vec4 lerp_texels(const glm::vec4& a, const glm::vec4& b, float t) { return t > 0.0f ? glm::mix(a, b, t) : a; }
}  // namespace

std::vector<glm::vec4> upscale_linear(const std::vector<glm::vec4>& in, int iw, int ih, int ow, int oh) {
  if (in.size() != static_cast<std::size_t>(iw) * ih || iw < 1 || ih < 1 || ow < 1 || oh < 1) {
    throw std::invalid_argument("upscale_linear: the image is not of the size given");
  }
  std::vector<glm::vec4> out(static_cast<std::size_t>(ow) * oh);
  auto at = [&](int x, int y) { return in[static_cast<std::size_t>(y) * iw + x]; };
  for (int y = 0; y < oh; ++y) {
    int y1;
    float ty;
    const int y0 = texel_below(y, ih, oh, y1, ty);
    for (int x = 0; x < ow; ++x) {
      int x1;
      float tx;
      const int x0 = texel_below(x, iw, ow, x1, tx);
      const glm::vec4 top = lerp_texels(at(x0, y0), at(x1, y0), tx), bottom = lerp_texels(at(x0, y1), at(x1, y1), tx);
      out[static_cast<std::size_t>(y) * ow + x] = lerp_texels(top, bottom, ty);
    }
  }
  return out;
}

double auto_exposure(const std::vector<glm::vec4>& linear) { return auto_exposure_if_lit(linear).value_or(kDefaultExposure); }

std::vector<int> exposure_probe_frames(int n) {
  std::vector<int> k;
  if (n <= 0) return k;
  if (n <= 5) {
    for (int i = 0; i < n; ++i) k.push_back(i);
    return k;
  }
  for (int q = 0; q <= 4; ++q) k.push_back(static_cast<int>((static_cast<long long>(n - 1) * q + 2) / 4));
  k.erase(std::unique(k.begin(), k.end()), k.end());
  return k;
}

double sequence_exposure(const std::vector<std::optional<double>>& probe_exposures) {
  std::optional<double> least;
  for (const auto& e : probe_exposures) {
    if (e && (!least || *e < *least)) least = e;
  }
  return least.value_or(kDefaultExposure);
}

std::optional<double> auto_exposure_if_lit(const std::vector<glm::vec4>& linear) {
  std::vector<double> y;
  y.reserve(linear.size());
  for (const auto& p : linear) {
    const double l = 0.2126 * p.x + 0.7152 * p.y + 0.0722 * p.z;
    if (std::isfinite(l) && l > 0.0) y.push_back(l);
  }
  if (y.empty()) return std::nullopt;
  const std::size_t k = std::min(y.size() - 1, static_cast<std::size_t>(0.99 * static_cast<double>(y.size())));
  std::nth_element(y.begin(), y.begin() + static_cast<std::ptrdiff_t>(k), y.end());
  // filmic(x) = 0.8: (2.51 - 2.43 t) x^2 + (0.03 - 0.59 t) x - 0.14 t = 0, its positive root.
  constexpr double t = 0.8;
  const double a = 2.51 - 2.43 * t, b = 0.03 - 0.59 * t, c = -0.14 * t;
  const double x = (-b + std::sqrt(b * b - 4.0 * a * c)) / (2.0 * a);
  return std::clamp(x / y[k], 1e-6, 1e6);
}

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

void encode_png(std::FILE* f, int width, int height, const std::vector<unsigned char>& rgb8) {
  // A C callback cannot throw: a short write shows in ferror() below.
  auto sink = [](void* ctx, void* data, int size) { std::fwrite(data, 1, static_cast<std::size_t>(size), static_cast<std::FILE*>(ctx)); };
  if (!stbi_write_png_to_func(sink, f, width, height, 3, rgb8.data(), width * 3)) throw std::runtime_error("PNG encoding failed");
  if (std::ferror(f)) throw core::WriteError(std::string("write failed (") + std::strerror(errno) + ")");
}

void write_png(const std::string& path, int width, int height, const std::vector<unsigned char>& rgb8) {
  core::write_file_atomically(path, [&](std::FILE* f) { encode_png(f, width, height, rgb8); });
}

namespace {
// PFM stores rows bottom to top; a negative scale means little-endian (floats as the host has them).
void encode_pfm_channels(std::FILE* f, int width, int height, const std::vector<glm::vec4>& pixels, int first, int channels) {
  std::fprintf(f, "%s\n%d %d\n-1.0\n", channels == 3 ? "PF" : "Pf", width, height);
  std::vector<float> row(static_cast<std::size_t>(width) * channels);
  for (int y = height - 1; y >= 0; --y) {
    for (int x = 0; x < width; ++x) {
      const auto& p = pixels[static_cast<std::size_t>(y) * width + x];
      for (int c = 0; c < channels; ++c) row[static_cast<std::size_t>(x) * channels + c] = p[first + c];
    }
    if (std::fwrite(row.data(), sizeof(float), row.size(), f) != row.size()) {
      throw core::WriteError(std::string("write failed (") + std::strerror(errno) + ")");
    }
  }
}
}  // namespace

void encode_pfm(std::FILE* f, int width, int height, const std::vector<glm::vec4>& pixels) {
  encode_pfm_channels(f, width, height, pixels, 0, 3);
}
void encode_pfm_transmittance(std::FILE* f, int width, int height, const std::vector<glm::vec4>& pixels) {
  encode_pfm_channels(f, width, height, pixels, 3, 1);
}

void write_pfm(const std::string& path, int width, int height, const std::vector<glm::vec4>& pixels) {
  core::write_file_atomically(path, [&](std::FILE* f) { encode_pfm(f, width, height, pixels); });
}

void write_pfm_transmittance(const std::string& path, int width, int height, const std::vector<glm::vec4>& pixels) {
  core::write_file_atomically(path, [&](std::FILE* f) { encode_pfm_transmittance(f, width, height, pixels); });
}

std::string transmittance_pfm_path(const std::string& radiance_pfm) {
  const std::string ext = ".pfm";
  const bool has_ext = radiance_pfm.size() > ext.size() &&
                       radiance_pfm.compare(radiance_pfm.size() - ext.size(), ext.size(), ext) == 0;
  return (has_ext ? radiance_pfm.substr(0, radiance_pfm.size() - ext.size()) : radiance_pfm) + ".transmittance.pfm";
}

void check_finite_pixels(const std::vector<glm::vec4>& pixels, int width, const std::string& what) {
  std::size_t bad = 0, first_bad = 0;
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    const auto& p = pixels[i];
    if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z) && std::isfinite(p.w)) && bad++ == 0) first_bad = i;
  }
  if (bad == 0) return;
  const std::size_t w = static_cast<std::size_t>(std::max(width, 1));
  throw std::runtime_error(what + ": " + std::to_string(bad) + " of " + std::to_string(pixels.size()) +
                           " pixels came out not finite (the first at x " + std::to_string(first_bad % w) + ", y " +
                           std::to_string(first_bad / w) + "), expected finite radiance; nothing written");
}

bool png_decodes_at_size(const std::string& path, int width, int height) {
  int w = 0, h = 0, channels = 0;
  unsigned char* data = stbi_load(path.c_str(), &w, &h, &channels, 3);
  if (!data) return false;
  stbi_image_free(data);
  return w == width && h == height;
}

}  // namespace cv::render
