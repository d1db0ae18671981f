// The kernel's tracking (shaders/kernel/tracking.glsl) compiled as C++ in double over the march
// kernel's medium, with the Monte Carlo's counter-based random stream: what the Monte Carlo
// reference walks its paths with.
#pragma once

#include "kernel/march_kernel.hpp"
#include "reference/path_rng.hpp"

namespace cv::kernel::f64 {

#define CV_FN inline
#define CV_IN(T) const T&
#define CV_OUT(T) T&
#define CV_INOUT(T) T&

struct TrackKernel : MarchKernel {
  using TrackRng = core::PathRng;
  static double track_uniform(TrackRng& rng) { return rng.uniform(); }
  double u_track_majorant = 0.0;  // the volume's largest extinction, 1/m
  bool u_track_bricks = false;    // the pyramid's brick bounds instead (MonteCarloSettings::brick_majorants)

#include "kernel/tracking.glsl"
};

#undef CV_FN
#undef CV_IN
#undef CV_OUT
#undef CV_INOUT

}  // namespace cv::kernel::f64
