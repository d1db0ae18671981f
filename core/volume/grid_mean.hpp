// The renderer's medium from a time step's fields: grid-box-mean extinction, and the layer, bound
// and centre every march derives from it (core::prepare_volume keeps them per time step).
#pragma once

#include <vector>

#include <glm/vec3.hpp>

#include "volume/cloud_volume.hpp"

namespace cv::core {

// The renderer's medium: grid-box-mean extinction (cloud fraction x in-cloud extinction) of
// liquid and of ice per grid node, no data as 0. Both the CPU reference and the GPU interpolate
// these products, never the factors separately.
struct GridMeanExtinction {
  std::vector<float> liquid_per_m, ice_per_m;
  // The ground's altitude per column (m; the step's TimeStepData::ground_m), empty without terrain:
  // layer masks measure heights above it (march_settings.def, layer_bottom_m).
  std::vector<float> ground_m{};
  // The cloud fraction per node (0..1; NaN as 0), empty where the file has none: the modelled
  // cloud (cloud_model "modelled", march.glsl detail_factor) makes that share of each cell cloudy.
  std::vector<float> fraction{};
  // Per column, the temperature lapse rate from the lowest level above the ground to 3 km above it
  // (K/km; NaN where the column lacks temperatures), empty where the file has none: the weather
  // textures' convective signal (core/kernel/weather_textures).
  std::vector<float> lapse_k_per_km{};
  // The modelled cloud's detail displacement at this instant (grid cells along the longitude and
  // latitude indices, 2 per level; core/kernel/detail_drift), empty where nobody asked: it stays still.
  std::vector<double> detail_drift_cells{};
};
// Extinctions from this up are not data but fill values left in a field (netCDF's default float
// fill is 9.96921e36): the densest fog is ~0.1 /m, and float sums of sigma x phase (up to 1.6e5 /sr
// at g = 0.999) x step would overflow to Inf near 1e33 /m. grid_mean_extinction takes them as no cloud.
constexpr float kMaxGridMeanExtinctionPerM = 1e6f;
// cloud fraction x in-cloud extinction per node; NaN, negative and >= kMaxGridMeanExtinctionPerM -> 0.
GridMeanExtinction grid_mean_extinction(const VolumeGrid& grid, const TimeStepData& data);
// The per-column lapse rates of GridMeanExtinction::lapse_k_per_km; empty without temperatures.
std::vector<float> lapse_rates(const VolumeGrid& grid, const TimeStepData& data);

// The altitudes between which a volume holds cloud: from the level below its lowest level with any
// extinction to the level above its highest (trilinear sampling reads cloud between those), so the
// marchers intersect this thinner shell and never step through layers that hold nothing. `empty`
// when no node holds cloud: then nothing is marched at all.
struct CloudLayer {
  double bottom_m = 0.0, top_m = 0.0;
  bool empty = true;
};
CloudLayer cloud_layer(const VolumeGrid& grid, const GridMeanExtinction& medium);

// The largest extinction (liquid + ice, 1/m) of any node: a bound on what sampling can return,
// which sizes the sun marches' steps (MarchSettings::max_sun_step_optical_depth).
double largest_extinction(const GridMeanExtinction& medium);

// The centre of a volume on the sphere (altitude 0), Earth-centred, metres: the erosion noise's
// anchor (noise_anchor) for this grid, the same on the CPU and the GPU.
glm::dvec3 grid_centre_ecef(const VolumeGrid& grid);

}  // namespace cv::core
