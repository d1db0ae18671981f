// What the processor and the operating system allow, for code that picks a vector path at run
// time (the build targets plain x86-64).
#pragma once

namespace cv::core {

// AVX usable: the processor has it and the operating system saves the YMM registers, and the
// baseline paths are not asked for (below).
bool cpu_has_avx();
// AVX with F16C (the half-float conversions), on the same terms.
bool cpu_has_avx_f16c();

// The baseline x86-64 paths (SSE2 and scalar) instead of the AVX ones, as on a processor without
// AVX: for the whole process when CLOUDVIEWER_CPU=baseline is set, or from set_baseline_cpu(true)
// until it is called with false. The vector and baseline paths give the same bits, and this is
// how that is checked on a machine that has AVX (and how a user rules the vector paths out).
void set_baseline_cpu(bool on);
bool baseline_cpu();

// The lanes set in a vector compare's movemask (up to eight), without the POPCNT instruction,
// which the AVX paths are not chosen by.
inline unsigned mask_lanes(unsigned mask) {
  constexpr unsigned char kBits[16] = {0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4};
  return kBits[mask & 15u] + kBits[(mask >> 4) & 15u];
}

}  // namespace cv::core
