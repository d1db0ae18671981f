// The physics of the conversion, shared by every reader: one model column (levels bottom to top,
// grid-box-mean water) becomes in-cloud extinction, cloud fraction, winds and temperature on the
// volume's altitude grid, with the consistency counts the import report needs.
#pragma once

#include <limits>
#include <span>
#include <vector>

#include "volume/cloud_volume.hpp"

namespace cv::importers {

inline constexpr double kRdJPerKgK = 287.05;
inline constexpr double kG0MPerS2 = 9.80665;

// One model level of one column. Absent quantities are NaN (water, fraction, winds) or set from a
// fallback by the reader (temperature, humidity).
struct LevelSample {
  double z_m = std::numeric_limits<double>::quiet_NaN();  // geometric altitude above the sphere
  double p_pa = 0.0;
  double t_k = 0.0;
  double qv = 0.0;  // specific humidity, kg/kg
  double cf = std::numeric_limits<double>::quiet_NaN();
  double q_liquid = std::numeric_limits<double>::quiet_NaN();  // grid-box mean, kg/kg (already clamped >= 0)
  double q_ice = std::numeric_limits<double>::quiet_NaN();
  double u = std::numeric_limits<double>::quiet_NaN();  // earth-relative, m/s
  double v = std::numeric_limits<double>::quiet_NaN();
  double w = std::numeric_limits<double>::quiet_NaN();
};

struct ConversionOptions {
  double r_eff_liquid_um = 10.0;
  double r_eff_ice_um = 0.0;  // 0 = temperature-dependent
};

struct ColumnCounts {
  std::size_t water_without_cf = 0, cf_without_water = 0, nonmonotonic = 0;
  double most_water_without_cf = 0.0;
};

// Converts the levels and interpolates them linearly in altitude into column (x, y) of `out`, whose
// fields were allocated by the caller (absent fields stay empty). Outside the column's levels,
// nothing is written (the NaN stays: no data is invented).
void place_column(std::span<LevelSample> levels, const core::VolumeGrid& grid, int x, int y,
                  const ConversionOptions& options, core::TimeStepData& out, ColumnCounts& counts);

// True when a valid time lies in the options' ISO range (ISO 8601 UTC strings of one format order
// as the times they name).
struct ImportOptions;
bool in_time_range(const core::ValidTime& t, const ImportOptions& options);

// Adds the report's consistency warnings for one time step.
void report_counts(const ColumnCounts& c, int time_index, core::ImportReport& report);

}  // namespace cv::importers
