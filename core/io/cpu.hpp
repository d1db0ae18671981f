// What the processor and the operating system allow, for code that picks a vector path at run
// time (the build targets plain x86-64).
#pragma once

namespace cv::core {

// AVX usable: the processor has it and the operating system saves the YMM registers.
bool cpu_has_avx();
// AVX with F16C (the half-float conversions).
bool cpu_has_avx_f16c();

}  // namespace cv::core
