// The shader feature permutations, named in one typed place. A program is compiled with only the
// features a scene uses; each becomes `#define CV_FEATURE_<NAME> 1` in the prelude.
#pragma once

#include <cstdint>
#include <string>

namespace cv::render {

enum class ShaderFeature : std::uint32_t {
  MultipleScattering = 1u << 0,  // octaves beyond the first
  MiePhase = 1u << 1,            // approximate Mie for liquid (else Henyey-Greenstein)
  IcePhase = 1u << 2,            // a separate phase function for ice
  SunShadow = 1u << 3,           // secondary march toward the sun
  NoiseDetail = 1u << 4,         // sub-grid erosion noise
  EmptySpaceSkip = 1u << 5,      // min/max pyramid traversal
  SkyAmbient = 1u << 6,          // ambient sky term
};

// The prelude macro name of a single feature, e.g. "CV_FEATURE_MIE_PHASE".
const char* feature_macro(ShaderFeature f);

class ShaderFeatures {
 public:
  ShaderFeatures() = default;
  ShaderFeatures(std::initializer_list<ShaderFeature> list) {
    for (ShaderFeature f : list) set(f);
  }
  ShaderFeatures& set(ShaderFeature f, bool on = true) {
    bits_ = on ? (bits_ | static_cast<std::uint32_t>(f)) : (bits_ & ~static_cast<std::uint32_t>(f));
    return *this;
  }
  bool has(ShaderFeature f) const { return (bits_ & static_cast<std::uint32_t>(f)) != 0; }
  std::uint32_t bits() const { return bits_; }
  // One `#define CV_FEATURE_... 1` line per feature that is on.
  std::string defines() const;

 private:
  std::uint32_t bits_ = 0;
};

}  // namespace cv::render
