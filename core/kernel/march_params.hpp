// The march kernel's parameters on the C++ side: in double for the CPU kernel (MarchParams), packed
// to float in std140 layout for the GPU's uniform block (MarchParamsStd140, layout checked below),
// and the program variant a march needs (MarchVariant). All three come from the one list in
// shaders/kernel/march_params.glsl.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

namespace cv::core {
struct MarchSettings;
}

namespace cv::kernel {


// std140 (OpenGL 4.5 spec, 7.6.2.2): scalars align to 4, two-vectors to 8, three- and
// four-vectors to 16; array elements to 16 each. Bools are 4-byte words.
namespace std140 {
template <class T> struct Map;
template <> struct Map<double> {
  using type = float;
  static constexpr std::size_t align = 4, size = 4;
  static type convert(double v) { return static_cast<float>(v); }
};
template <> struct Map<glm::dvec2> {
  using type = glm::vec2;
  static constexpr std::size_t align = 8, size = 8;
  static type convert(const glm::dvec2& v) { return type(v); }
};
template <> struct Map<glm::dvec3> {
  using type = glm::vec3;
  static constexpr std::size_t align = 16, size = 12;
  static type convert(const glm::dvec3& v) { return type(v); }
};
template <> struct Map<int> {
  using type = std::int32_t;
  static constexpr std::size_t align = 4, size = 4;
  static type convert(int v) { return v; }
};
template <> struct Map<bool> {
  using type = std::uint32_t;
  static constexpr std::size_t align = 4, size = 4;
  static type convert(bool v) { return v ? 1u : 0u; }
};
template <> struct Map<glm::ivec2> {
  using type = glm::ivec2;
  static constexpr std::size_t align = 8, size = 8;
  static type convert(const glm::ivec2& v) { return v; }
};
template <> struct Map<glm::ivec4> {
  using type = glm::ivec4;
  static constexpr std::size_t align = 16, size = 16;
  static type convert(const glm::ivec4& v) { return v; }
};
constexpr std::size_t align_up(std::size_t offset, std::size_t align) { return (offset + align - 1) / align * align; }
}  // namespace std140

// The dialect's types as the parameter list names them, in double.
namespace params {
using real = double;
using real2 = glm::dvec2;
using real3 = glm::dvec3;
using ivec2 = glm::ivec2;
using ivec4 = glm::ivec4;

// The kernel's parameters in double: what the CPU kernel reads, and what the GPU's block is packed from.
struct MarchParams {
#define CV_PARAM(T, name) T name{};
#define CV_PARAM_ARRAY(T, name, N) T name[N]{};
#include "kernel/march_params.glsl"
#undef CV_PARAM
#undef CV_PARAM_ARRAY
};

// The uniform block MarchParams of shaders/render/raymarch.comp, byte for byte.
struct MarchParamsStd140 {
#define CV_PARAM(T, name) alignas(std140::Map<T>::align) typename std140::Map<T>::type name;
#define CV_PARAM_ARRAY(T, name, N) alignas(16) typename std140::Map<T>::type name[N];
#include "kernel/march_params.glsl"
#undef CV_PARAM
#undef CV_PARAM_ARRAY
};

// Each member where std140's rules put it, walked independently of the C++ layout (a test also
// holds these offsets against the driver's own, tests/render/march_params_test.cpp).
constexpr bool std140_layout_matches() {
  std::size_t off = 0;
#define CV_PARAM(T, name)                                                         \
  off = std140::align_up(off, std140::Map<T>::align);               \
  if (offsetof(MarchParamsStd140, name) != off) return false;                     \
  off += std140::Map<T>::size;
#define CV_PARAM_ARRAY(T, name, N)                                                \
  if (std140::Map<T>::size != 16) return false;                     \
  off = std140::align_up(off, 16);                                                \
  if (offsetof(MarchParamsStd140, name) != off) return false;                     \
  off += 16 * (N);
#include "kernel/march_params.glsl"
#undef CV_PARAM
#undef CV_PARAM_ARRAY
  return std140::align_up(off, 16) == sizeof(MarchParamsStd140);
}
static_assert(std140_layout_matches(), "MarchParamsStd140 does not follow std140: see shaders/kernel/march_params.glsl");

MarchParamsStd140 pack_std140(const MarchParams& p);
}  // namespace params
using params::MarchParams;
using params::MarchParamsStd140;
using params::pack_std140;

// The compile-time switches of a march program (raymarch.comp's CV_* defines). The CPU kernel takes
// the same switches as members.
struct MarchVariant {
  bool noise = false;       // sub-grid erosion (noise_amount > 0)
  bool skip_empty = true;   // jump empty bricks
  bool adaptive = false;    // divide view steps by optical depth
  bool atmosphere = false;  // the air: sun colour, sky in-scatter, ambient light
  bool globe = false;       // the ground where a ray meets it
  bool two_stream = false;  // multiple scattering from the two-stream source, not the octave sum
  bool translucent = false; // translucent geometry composited among the samples (set by the caller: not a setting)
  bool layer_mask = false;  // a height band masks the medium (layer_bottom_m / layer_top_m set)
  bool tint = false;        // false colour by liquid and ice (tint_liquid / tint_ice set)
  bool modelled = false;    // the modelled cloud (cloud_model "modelled")
  bool slab = false;        // with two_stream: the diffuse light shaped by the slab tables (diffuse_shape "slab")
  static MarchVariant of(const core::MarchSettings& s);
  // A small integer naming the variant (a bit per switch), for caches of compiled programs.
  unsigned key() const;
  static constexpr unsigned kCount = 2048;
  std::vector<std::pair<std::string, std::string>> defines() const;
};

}  // namespace cv::kernel
