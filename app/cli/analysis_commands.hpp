// The analysts' headless commands (issue 17): `probe` (a column and a view ray), `section` (a
// field along a great circle against altitude) and `series` (a column's summary against valid time).
#pragma once

#include <string>
#include <vector>

namespace cv::cli {

const char* probe_usage();
const char* section_usage();
const char* series_usage();
const char* compare_usage();
int cmd_probe(const std::vector<std::string>& args);
int cmd_section(const std::vector<std::string>& args);
int cmd_series(const std::vector<std::string>& args);
int cmd_compare(const std::vector<std::string>& args);

}  // namespace cv::cli
