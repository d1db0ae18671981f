// The physics core for C++: the same GLSL files the GPU runs (shaders/common), instantiated in
// float (cv::physics::f32, to compare with the GPU) and double (cv::physics::f64, for references).
#pragma once

#include <cmath>
#include <cstdint>

#include <glm/glm.hpp>

// The GLSL-compatible dialect of shaders/common: see shaders/common/README.md.
#define CV_FN inline
#define CV_IN(T) const T&
#define CV_OUT(T) T&
#define CV_INOUT(T) T&
#define precise

namespace cv::physics {

namespace f32 {
using namespace glm;
using real = float;
using real2 = glm::vec2;
using real3 = glm::vec3;
using real4 = glm::vec4;
using uint = std::uint32_t;
using std::abs, std::atan, std::cos, std::exp, std::log, std::pow, std::sin, std::sqrt, std::tan;
inline real atan(real y, real x) { return std::atan2(y, x); }
constexpr real CV_SPLITTER = 4097.0f;  // 2^12 + 1 splits a 24-bit significand
#include "common/physics.glsl"
}  // namespace f32

namespace f64 {
using namespace glm;
using real = double;
using real2 = glm::dvec2;
using real3 = glm::dvec3;
using real4 = glm::dvec4;
using uint = std::uint32_t;
using std::abs, std::atan, std::cos, std::exp, std::log, std::pow, std::sin, std::sqrt, std::tan;
inline real atan(real y, real x) { return std::atan2(y, x); }
constexpr real CV_SPLITTER = 134217729.0;  // 2^27 + 1 splits a 53-bit significand
#include "common/physics.glsl"
}  // namespace f64

}  // namespace cv::physics

#undef precise
#undef CV_FN
#undef CV_IN
#undef CV_OUT
#undef CV_INOUT
