// Turning linear radiance into pictures: exposure and a filmic tonemap to 8-bit sRGB PNG, and the
// linear values themselves as PFM (float) for analysis. Both written atomically.
#pragma once

#include <string>
#include <vector>

#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

namespace cv::render {

struct ToneSettings {
  double exposure = 1.0;                                     // radiance multiplier before the curve
  glm::dvec3 background{0.015, 0.02, 0.035};                 // seen through the clouds' transmittance
};

// Bilinear upscaling of an iw x ih image (rgb radiance, a transmittance; rows top to bottom) to
// ow x oh in linear radiance, pixel centres mapped onto texel centres and clamped at the edges; a
// weight of 0 takes the nearer texel alone. Written in float exactly as the viewer's present.frag,
// so the viewer shows what `render` writes.
std::vector<glm::vec4> upscale_linear(const std::vector<glm::vec4>& in, int iw, int ih, int ow, int oh);

// rgb = radiance, a = transmittance, rows top to bottom; composited over the background.
std::vector<unsigned char> tonemap_srgb8(const std::vector<glm::vec4>& pixels, const ToneSettings& tone);
void write_png(const std::string& path, int width, int height, const std::vector<unsigned char>& rgb8);
// Portable float map (3 channels, linear radiance composited over the background).
void write_pfm(const std::string& path, int width, int height, const std::vector<glm::vec4>& pixels,
               const ToneSettings& tone);

}  // namespace cv::render
