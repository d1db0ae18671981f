// What the processor and the operating system allow, for code that picks a vector path at run
// time (the build targets plain x86-64).
#pragma once

namespace cv::core {

// AVX usable: the processor has it and the operating system saves the YMM registers.
bool cpu_has_avx();
// AVX with F16C (the half-float conversions).
bool cpu_has_avx_f16c();

// The lanes set in a vector compare's movemask (up to eight), without the POPCNT instruction,
// which the AVX paths are not chosen by.
inline unsigned mask_lanes(unsigned mask) {
  constexpr unsigned char kBits[16] = {0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4};
  return kBits[mask & 15u] + kBits[(mask >> 4) & 15u];
}

}  // namespace cv::core
