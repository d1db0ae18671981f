// `cloudviewer bench`: error against run time of the GPU raymarcher on the standard scenes, against
// cached Monte Carlo references, for a sweep of quality settings and the seed documents' presets.
#pragma once

#include <string>
#include <vector>

namespace cv::cli {

// The usage lines of `bench` (for the command's help).
const char* bench_usage();

// Runs `bench` with its arguments; throws UsageError for bad input.
int cmd_bench(const std::vector<std::string>& args);

}  // namespace cv::cli
