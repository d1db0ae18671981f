// The Monte Carlo's random stream per (seed, pixel, sample): counter-based, so any thread computes
// any sample and a reference extended later continues exactly where it stopped.
#pragma once

#include <cstdint>

namespace cv::core {

class PathRng {
 public:
  PathRng(std::uint64_t seed, std::uint64_t pixel, std::uint64_t sample)
      : key_(mix64(mix64(seed + kGolden) ^ mix64(pixel * 0xD1B54A32D192ED03ull + 1) ^ mix64(sample * kGolden + 7))) {}
  double uniform() { return static_cast<double>(mix64(key_ + (++counter_) * kGolden) >> 11) * 0x1.0p-53; }  // [0, 1)
  std::uint32_t bits32() { return static_cast<std::uint32_t>(mix64(key_ + (++counter_) * kGolden) >> 32); }

 private:
  // splitmix64's finaliser: a bijective 64-bit mix with full avalanche.
  static std::uint64_t mix64(std::uint64_t z) {
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  static constexpr std::uint64_t kGolden = 0x9E3779B97F4A7C15ull;
  std::uint64_t key_, counter_ = 0;
};

}  // namespace cv::core
