// What the CF reader finds in a file: its axes (by standard_name, units, axis and positive; by name
// only when the values confirm it) and the variables for each role.
#pragma once

#include <string>
#include <vector>

#include "cf_time.hpp"
#include "nc_file.hpp"
#include "volume/cloud_volume.hpp"

namespace cv::importers {

enum class Role {
  CloudFraction, Liquid, Ice, Geopotential, GeopotentialHeight, Temperature, Humidity, U, V, Omega, UpwardVelocity,
  Snow,              // added to the ice, as the WRF reader does with QSNOW
  RelativeHumidity,  // read only for a diagnosed cloud (--diagnose-cloud)
};
inline constexpr int kRoleCount = 13;

// The kinds of vertical coordinate the CF reader understands.
enum class Vertical { Pressure, Height, Hybrid };
const char* role_name(Role r);

struct Axis {
  int dim = -1;                // index into NcFile::dims()
  const NcVar* var = nullptr;  // its coordinate variable, if any
  std::vector<double> values;
  std::string how;             // how it was recognised, for the report
};

struct CfLayout {
  Axis lon, lat, vertical, time;
  Vertical vertical_kind = Vertical::Pressure;
  double pressure_scale_to_pa = 0.0;  // pressure levels: file unit -> Pa
  double height_scale_to_m = 0.0;     // height levels: file unit -> m
  bool height_above_ground = false;   // standard_name "height" (above the surface), not "altitude"
  // Hybrid sigma-pressure levels: p_k = a_pa[k] + b[k] ps (a_pa is a k p0, or ap k), file order.
  std::vector<double> hybrid_a_pa, hybrid_b;
  const NcVar* surface_pressure = nullptr;     // 2-D (or with time): Pa
  bool surface_pressure_is_log = false;        // IFS lnsp: ln(ps / Pa)
  const NcVar* surface_geopotential = nullptr; // 2-D (or with time): m2/s2, or surface altitude in m
  double surface_geopotential_scale = 1.0;     // 9.80665 when the variable is an altitude in m
  std::vector<core::ValidTime> times;
  bool times_uneven = false;
  const NcVar* roles[kRoleCount] = {};
  // Multiplier from each role variable's units to the SI (or 0..1) values the conversion takes:
  // 0.01 for a cloud fraction or relative humidity in %, 1e-3 for water in g/kg.
  double role_scale[kRoleCount] = {1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1};
  // Precipitation recognised in the file (rain, graupel): not part of the cloud volume.
  std::vector<std::string> precipitation;
  std::vector<std::string> notes;
};

// Detects the layout; throws ImportError naming what is missing or inconsistent.
CfLayout detect_cf_layout(const NcFile& f);

// True when the layout has a cloud fraction, liquid, ice or snow variable.
bool has_cloud(const CfLayout& L);

}  // namespace cv::importers
