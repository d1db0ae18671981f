// The physics of the conversion, shared by every reader: one model column (levels bottom to top,
// grid-box-mean water) becomes in-cloud extinction, cloud fraction, winds, temperature and pressure
// on the volume's altitude grid, with the consistency counts the import report needs.
#pragma once

#include <array>
#include <limits>
#include <span>
#include <string>
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

// Counts over the model boxes a reader passed to place_column (the file's boxes for CF files read
// at their own rows; resampled columns x model levels for WRF, which counts its file boxes apart).
struct ColumnCounts {
  std::size_t water_without_cf = 0;              // water > 0 but cloud fraction below kZeroCloudFraction
  std::size_t water_without_cf_significant = 0;  // ... of which water > kZeroWater
  std::size_t cf_without_water = 0, nonmonotonic = 0;
  double most_water_without_cf = 0.0;
  void merge(const ColumnCounts& o);
};

// A cloud fraction below this is zero to within int16 packing (whose step is ~1.5e-5 over 0..1).
inline constexpr double kZeroCloudFraction = 1e-4;
// Water below this counts as none for the consistency checks: int16 packing leaves a step or two
// (~5e-8 kg/kg) where there is none, and 1e-7 kg/kg gives an optical depth of ~0.015 per km.
inline constexpr double kZeroWater = 1e-7;

// The levels of a row of columns, level-major (the value of level l in column x is at l * nx + x):
// the layout the file's slabs are read in and the volume's layers are written in, so neither
// side is transposed through a cache-hostile column buffer. Absent quantities as in LevelSample.
struct RowLevels {
  int nx = 0, nlev = 0;
  std::vector<double> z_m, p_pa, t_k, qv, cf, q_liquid, q_ice, u, v, w;
  // Sizes every array for nx columns of nlev levels (values are the caller's to write).
  void resize(int columns, int levels);
  std::size_t at(int l, int x) const { return static_cast<std::size_t>(l) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(x); }
};

// The value ranges of what place_row stored, per field (finite values only; the caller adds the
// points left without data as missing): the import report's "after" figures without a pass over
// the volume.
using StoredStats = std::array<core::ValueStats, core::kFieldCount>;

// A run of a layer's nodes that lie between the same pair of levels (lev: the upper level, -1
// where the nodes have none: NaN). Neighbouring columns' levels differ little in height, so a
// layer holds few runs, and within one the two levels' values are contiguous in the row's arrays.
struct LevelRun {
  int begin, end, lev;
};

// place_row's working arrays (a row's extinctions, its nodes' level pairs and weights, the runs, a
// layer row), kept by a caller that converts rows on threads of its own so that their pages are
// faulted in once, not once per thread.
struct PlaceRowScratch {
  std::vector<double> buffer, node_weight;
  std::vector<int> node_level;
  std::vector<LevelRun> runs;
  std::vector<std::size_t> layer_runs;
  std::vector<float> layer;
};

// Converts a row's levels and interpolates them linearly in altitude into columns x0 .. x0 + nx - 1
// of row y of `out` (below). Adds to `stored` when given. The first form keeps its working arrays
// per thread.
void place_row(const RowLevels& levels, const core::VolumeGrid& grid, int x0, int y, const ConversionOptions& options,
               core::TimeStepData& out, ColumnCounts& counts, StoredStats* stored = nullptr);
void place_row(const RowLevels& levels, const core::VolumeGrid& grid, int x0, int y, const ConversionOptions& options,
               core::TimeStepData& out, ColumnCounts& counts, StoredStats* stored, PlaceRowScratch& scratch);

// Converts the levels and interpolates them linearly in altitude into column (x, y) of `out`, whose
// fields were allocated by the caller (absent fields stay empty). Outside the column's levels,
// nothing is written (the NaN stays: no data is invented).
//
// What is interpolated is what the renderer uses: the grid-box-mean extinction (of the box's mean
// water) and the cloud fraction. The stored in-cloud extinction is their ratio at each node, so
// fraction x in-cloud extinction is exactly the interpolated grid-box mean. Water in a box whose
// fraction is below kZeroCloudFraction has no meaningful in-cloud value: it is left out (no cloud is
// invented there) and counted.
void place_column(std::span<LevelSample> levels, const core::VolumeGrid& grid, int x, int y,
                  const ConversionOptions& options, core::TimeStepData& out, ColumnCounts& counts);

// The regular altitude axis from the lowest to the highest model level: the spacing is dz_m, or
// the largest spacing not above dz_m that divides the span when `fit` (automatic spacing), so the
// top node sits on the highest level; with a fixed spacing the top node lies at or above it.
core::RegularAxis altitude_axis(double zmin_m, double zmax_m, double dz_m, bool fit);

// True when a valid time lies in the options' ISO range (ISO 8601 UTC strings of one format order
// as the times they name).
struct ImportOptions;
bool in_time_range(const core::ValidTime& t, const ImportOptions& options);

// Adds the report's consistency warnings for one time step.
void report_counts(const ColumnCounts& c, int time_index, core::ImportReport& report);
// The same, naming what was counted ("resampled points", "file boxes", ...).
void report_counts(const ColumnCounts& c, int time_index, const std::string& what, core::ImportReport& report);

}  // namespace cv::importers
