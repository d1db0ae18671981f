// A small rasterizer for the benchmark's plots: error (log) against time (log) as an RGB8 image,
// with decade ticks labelled by a built-in 3x5 digit font and the Pareto front drawn as a line.
// Pure pixels: the caller writes the PNG (core reads and writes no images).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "bench/metrics.hpp"

namespace cv::core {}

namespace cv::bench {
// The bench works on core's types throughout (it was core::bench before it moved up to app/).
using namespace cv::core;

struct PlotPoint {
  TimeError p;
  int kind = 0;  // 0: a sweep configuration, 1: one of our presets, 2: a seed document's preset, 3: the path tracer
};

struct Rgb8Image {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;  // rows top to bottom
};

// Points with non-finite or non-positive coordinates are left out. `front` holds indices into
// `pts`, sorted by time. The axes span the points' decades (at least one).
Rgb8Image plot_error_vs_time(const std::vector<PlotPoint>& pts, const std::vector<std::size_t>& front, int width,
                             int height);

}  // namespace cv::bench
