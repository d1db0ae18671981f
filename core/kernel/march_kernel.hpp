// The march kernel (shaders/kernel/march.glsl) compiled as C++ in double: the CPU reference runs the
// very code the GPU runs. Textures are small views with GLSL's texelFetch and textureSize; the
// parameters are MarchParams' members, read by their GLSL names; the counters and the program
// switches are members too.
#pragma once

#include <cstddef>

#include <glm/glm.hpp>

#include "kernel/march_params.hpp"
#include "kernel/march_stats.glsl"
#include "kernel/ms_beam.glsl"
#include "kernel/ms_slab.glsl"
#include "physics/physics.hpp"

namespace cv::kernel {

// A 3-D texture of floats with 1 or 2 channels, x fastest (an R32F or RG32F texture on the GPU).
struct sampler3D {
  const float* texels = nullptr;
  glm::ivec3 size{0};
  int channels = 1;
};
// A 2-D texture of floats with 1 to 4 channels, x fastest, row 0 first (R32F, RG32F, RGB32F or RGBA32F).
struct sampler2D {
  const float* texels = nullptr;
  glm::ivec2 size{0};
  int channels = 1;
};
// As GLSL: a missing channel reads 0, alpha 1. Indices are the kernel's to keep in range.
inline glm::dvec4 texelFetch(const sampler3D& t, glm::ivec3 p, int) {
  const std::size_t i = (static_cast<std::size_t>(p.z) * t.size.y + p.y) * t.size.x + p.x;
  if (t.channels == 2) return glm::dvec4(t.texels[2 * i], t.texels[2 * i + 1], 0.0, 1.0);
  if (t.channels == 4) return glm::dvec4(t.texels[4 * i], t.texels[4 * i + 1], t.texels[4 * i + 2], t.texels[4 * i + 3]);
  return glm::dvec4(t.texels[i], 0.0, 0.0, 1.0);
}
inline glm::dvec4 texelFetch(const sampler2D& t, glm::ivec2 p, int) {
  const std::size_t i = (static_cast<std::size_t>(p.y) * t.size.x + p.x) * t.channels;
  if (t.channels == 1) return glm::dvec4(t.texels[i], 0.0, 0.0, 1.0);
  if (t.channels == 2) return glm::dvec4(t.texels[i], t.texels[i + 1], 0.0, 1.0);
  if (t.channels == 3) return glm::dvec4(t.texels[i], t.texels[i + 1], t.texels[i + 2], 1.0);
  return glm::dvec4(t.texels[i], t.texels[i + 1], t.texels[i + 2], t.texels[i + 3]);
}
// A 2-D array texture: `size.z` layers of size.x x size.y texels, layer after layer.
struct sampler2DArray {
  const float* texels = nullptr;
  glm::ivec3 size{0};
  int channels = 1;
};
inline glm::dvec4 texelFetch(const sampler2DArray& t, glm::ivec3 p, int) {
  const sampler2D layer{t.texels + static_cast<std::size_t>(p.z) * t.size.y * t.size.x * t.channels, {t.size.x, t.size.y}, t.channels};
  return texelFetch(layer, glm::ivec2(p.x, p.y), 0);
}
inline glm::ivec3 textureSize(const sampler3D& t, int) { return t.size; }
inline glm::ivec2 textureSize(const sampler2D& t, int) { return t.size; }

namespace f64 {
using namespace cv::physics::f64;

#define CV_FN inline
#define CV_IN(T) const T&
#define CV_OUT(T) T&
#define CV_INOUT(T) T&

struct MarchKernel : MarchParams {
  sampler3D u_liquid, u_ice, u_noise_low, u_noise_high, u_ms_moments, u_ms_horizontal, u_fraction;
  sampler2DArray u_column_tau;
  sampler2D u_jitter_mask, u_ground, u_depth, u_opaque, u_tl_distance, u_tl_color, u_detail_table, u_detail_shift;
  const glm::vec2* u_min_max = nullptr;
  const float* u_ms_beam_table = nullptr;  // the droplets' beam table (ms_beam_table), read by the two-stream march with the Mie phase
  const float* u_ms_slab_table = nullptr;  // the higher-order source's slab table (ms_slab_table), liquid then ice, read with u_ms_slab
  // The program switches (compile-time constants on the GPU).
  bool kSkipEmpty = true, kAdaptive = false, kAtmosphere = false, kGlobe = false, kNoise = false, kTwoStream = false,
       kTranslucent = false, kLayerMask = true,  // the CPU pays nothing for a uniform branch: the mask follows u_mask_band
       kTint = true,                             // and the tint follows u_tint
       kModelled = false,
       kSlab = false;  // the two-stream's diffuse light shaped by the slab tables (u_ms_slab_table)

#include "kernel/march.glsl"

  uint g_stats[CV_STAT_COUNT] = {};
};

#undef CV_FN
#undef CV_IN
#undef CV_OUT
#undef CV_INOUT

}  // namespace f64
}  // namespace cv::kernel
