// The kernel's tracking and path (shaders/kernel/tracking.glsl, path.glsl) compiled as C++ in double
// over the march kernel's medium, with the Monte Carlo's counter-based random stream: the paths the
// Monte Carlo reference traces, the same code the GPU path tracer runs in float.
#pragma once

#include "kernel/march_kernel.hpp"
#include "reference/path_rng.hpp"

#include <vector>

namespace cv::kernel::f64 {

#define CV_FN inline
#define CV_IN(T) const T&
#define CV_OUT(T) T&
#define CV_INOUT(T) T&

struct TrackKernel : MarchKernel {
  using TrackRng = core::PathRng;
  static double track_uniform(TrackRng& rng) { return rng.uniform(); }
  static uint track_bits(TrackRng& rng) { return rng.bits32(); }
  double u_track_majorant = 0.0;  // the volume's largest extinction, 1/m
  bool u_track_bricks = false;    // the pyramid's brick bounds instead (MonteCarloSettings::brick_majorants)
  int u_path_max_bounces = 1000;  // MonteCarloSettings::max_bounces
  int u_path_roulette_after = 4;  // MonteCarloSettings::roulette_after
  bool u_path_peak_mis = true;    // MonteCarloSettings::peak_mis

#define CV_PATH_SPLIT 1
#include "kernel/tracking.glsl"
#include "kernel/path.glsl"
#undef CV_PATH_SPLIT

  // The branches the peak technique splits off (path.glsl, CV_PATH_SPLIT), per thread: a path and
  // its branches are traced by one thread, one after the other.
  static std::vector<PathState>& path_branches() {
    static thread_local std::vector<PathState> v;
    return v;
  }
  static bool path_room() { return true; }  // no bound: the one-sample fallback is the GPU's
  static void path_split(const PathState& b) { path_branches().push_back(b); }
  static bool path_pop(PathState& b) {
    auto& v = path_branches();
    if (v.empty()) return false;
    b = v.back();
    v.pop_back();
    return true;
  }
};

#undef CV_FN
#undef CV_IN
#undef CV_OUT
#undef CV_INOUT

}  // namespace cv::kernel::f64
