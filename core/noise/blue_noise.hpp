// A tileable 2-D blue-noise mask made with the void-and-cluster method (Ulichney 1993): the
// per-pixel offsets of the march's steps (shaders/common/rng.glsl blue_noise_jitter), read from
// this array by the CPU reference and from the same values in a texture by the GPU.
#pragma once

#include <cstdint>
#include <vector>

namespace cv::core {

// n x n values, x fastest. Value (x, y) is rank(x, y) / n^2: every rank 0 .. n^2-1 appears once,
// so the values are uniform on [0, 1) and exact in float (n^2 <= 2^24). The mask repeats with
// period n in both axes without a seam: its filter wraps around.
struct BlueNoiseMask {
  int n = 0;
  std::vector<float> values;
  // Any integer pixel, taken modulo n (the image tiles the mask).
  float at(unsigned x, unsigned y) const {
    const unsigned un = static_cast<unsigned>(n);
    return values[static_cast<std::size_t>(y % un) * un + x % un];
  }
};

// Void and cluster on an n x n torus with a Gaussian filter of `sigma_px` pixels; the initial
// binary pattern (n^2 / 10 points) is drawn from `seed`, so the result is deterministic.
// O(n^4): about n = 64 at start-up; n must be 4 .. 4096 (std::invalid_argument otherwise).
BlueNoiseMask make_blue_noise(int n, std::uint32_t seed = 1, double sigma_px = 1.5);

// The renderer's mask (64 x 64, seed 1), made on first use and kept for the process: the CPU
// reference and GpuRaymarcher both take it from here. Thread-safe.
const BlueNoiseMask& step_jitter_mask();

}  // namespace cv::core
