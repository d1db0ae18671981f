// `cloudviewer time-error`: interpolation between forecast steps measured against held-back steps.
#pragma once

#include <string>
#include <vector>

namespace cv::cli {

const char* time_error_usage();
int cmd_time_error(const std::vector<std::string>& args);

}  // namespace cv::cli
