// What the CF reader finds in a file: its axes (by standard_name, units, axis and positive; by name
// only when the values confirm it) and the variables for each role.
#pragma once

#include <string>
#include <vector>

#include "cf_time.hpp"
#include "nc_file.hpp"
#include "volume/cloud_volume.hpp"

namespace cv::importers {

enum class Role { CloudFraction, Liquid, Ice, Geopotential, GeopotentialHeight, Temperature, Humidity, U, V, Omega };
inline constexpr int kRoleCount = 10;
const char* role_name(Role r);

struct Axis {
  int dim = -1;                // index into NcFile::dims()
  const NcVar* var = nullptr;  // its coordinate variable, if any
  std::vector<double> values;
  std::string how;             // how it was recognised, for the report
};

struct CfLayout {
  Axis lon, lat, vertical, time;
  double pressure_scale_to_pa = 0.0;  // 0 when the vertical axis is not pressure
  std::vector<core::ValidTime> times;
  bool times_uneven = false;
  const NcVar* roles[kRoleCount] = {};
  std::vector<std::string> notes;
};

// Detects the layout; throws ImportError naming what is missing or inconsistent.
CfLayout detect_cf_layout(const NcFile& f);

}  // namespace cv::importers
