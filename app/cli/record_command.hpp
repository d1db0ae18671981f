// `cloudviewer record`: a scene's camera path rendered headlessly to numbered PNG frames and an
// H.264 MP4, resumable, by frame range for batch schedulers, or assembled from frames on disk.
#pragma once

#include <string>
#include <vector>

namespace cv::cli {

int cmd_record(const std::vector<std::string>& args);
const char* record_usage();

}  // namespace cv::cli
