// Probes for analysts: the column of a volume at a latitude and longitude, read through the same
// sampler the march reads its medium with (volume/sampler.hpp: bilinear across columns, levels at
// the grid's own altitudes), its cover, base, top and optical depth, and where along a view ray
// toward that column the light came from (the march kernel's own record of the ray).
#pragma once

#include <string>
#include <vector>

#include "kernel/prepared_volume.hpp"
#include "volume/cloud_volume.hpp"
#include "volume/grid_mean.hpp"

namespace cv::core {

// One grid level of a probed column. Cloud fields read no data as 0 (the march's rule); the
// others are NaN where the volume has no such field or no data there.
struct ProbeLevel {
  double alt_m = 0.0;
  double above_ground_m = 0.0;       // alt_m minus the ground (sea level where the terrain is unknown)
  double cloud_fraction = 0.0;       // 0..1 (1 where the volume has no fraction field and holds water)
  double ext_liquid_per_m = 0.0;     // in-cloud
  double ext_ice_per_m = 0.0;        // in-cloud
  double march_liquid_per_m = 0.0;   // grid-box mean (fraction x in-cloud): what the march samples
  double march_ice_per_m = 0.0;
  double temperature_k = 0.0, wind_u_m_s = 0.0, wind_v_m_s = 0.0, wind_w_m_s = 0.0;
  double pressure_pa = 0.0;          // where the file gives pressure (Field::Pressure), else NaN
};

struct ColumnProbe {
  double lat_deg = 0.0, lon_deg = 0.0;
  double ground_m = 0.0;             // NaN where the volume has no terrain
  std::vector<ProbeLevel> levels;    // bottom to top, one per grid level
  // The column's summary with derive_maps' rules (MapOptions: a level is cloudy from its fraction
  // and extinction thresholds; maximum-random overlap), on the sampled column: at a grid column it
  // is the volume's own 2-D maps. NaN base and top: no cloudy level.
  double cover = 0.0, base_m = 0.0, top_m = 0.0;
  // The vertical optical depth of the medium the march samples: the trapezoid over levels of the
  // grid-mean extinction (ColumnDepth's integral, bilinear across columns as ColumnDepth::at).
  double optical_depth = 0.0;
};

// Whether the grid holds the column (longitude taken modulo 360 on any grid).
bool grid_holds(const VolumeGrid& grid, double lat_deg, double lon_deg);
// "lat 40..55, lon 170..195": the grid's extent, for messages.
std::string grid_extent_text(const VolumeGrid& grid);

// The column at (lat, lon) of one step. `medium` is that step's grid-mean extinction
// (grid_mean_extinction(grid, data)). std::invalid_argument when the grid does not hold the column.
ColumnProbe probe_column(const CloudVolume& volume, const TimeStepData& data, const GridMeanExtinction& medium,
                         double lat_deg, double lon_deg, const MapOptions& options = {});

// The probe as `probe --csv` writes it and the viewer's probe panel saves it: the per-level table
// (a header, then one row per level, bottom to top; a field the volume lacks is left empty) and the
// column's summary (cover, base, top, optical depth, ground; empty where there is none).
std::string probe_levels_csv(const ColumnProbe& probe, const CloudVolume& volume);
std::string probe_summary_csv(const ColumnProbe& probe);

// Where the light came from along the view ray from a camera position to a point: the march
// kernel's own state for that one ray (one pixel looking straight at the point).
struct ViewRayProbe {
  double distance_to_target_m = 0.0;
  double first_cloud_m = -1.0;       // distance from the camera to the first step holding cloud (-1: none)
  double half_transmittance_m = -1.0;  // where the view transmittance fell to 0.5 (-1: it never did)
  double transmittance = 1.0;        // of the clouds along the whole ray
  double view_step_m = 0.0;          // the march's step: the first cloud is known to within one
};
ViewRayProbe probe_view_ray(const PreparedVolume& volume, double cam_lat_deg, double cam_lon_deg, double cam_alt_m,
                            double target_lat_deg, double target_lon_deg, double target_alt_m, double view_step_m);
// The view ray's record as the probe CSV's summary line continues it:
// ",first_cloud_m=...,half_transmittance_m=...,ray_transmittance=..." (empty where there is none).
std::string view_ray_csv(const ViewRayProbe& ray);

}  // namespace cv::core
