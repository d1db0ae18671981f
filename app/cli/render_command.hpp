// `cloudviewer render`: a NetCDF file, .cvvol volume or scene file to a PNG, headless (EGL).
#pragma once

#include <string>
#include <vector>

namespace cv::cli {

// The usage lines of `render` (for the command's help).
const char* render_usage();

// Runs `render` with its arguments; throws UsageError / core::SceneError for bad input.
int cmd_render(const std::vector<std::string>& args);

}  // namespace cv::cli
