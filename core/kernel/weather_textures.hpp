// The weather textures (issue 18 item 1; docs/physics.md "Weather textures"): per column of a
// prepared medium, the 2-D maps the seeds' cloud models start from (cover per layer, cloud type,
// base and top) and a vertical profile per type. Built by prepare_volume from the medium it
// prepares, so at an instant between steps they are made from the interpolated fields, as the 3-D
// medium is. Where the file has no cloud fraction, the cover is diagnosed from the water here
// (diagnosed_fraction) and the modelled cloud takes it.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "volume/cloud_volume.hpp"
#include "volume/grid_mean.hpp"

namespace cv::core {

enum class CloudType : std::uint8_t { None = 0, Stratiform = 1, Cumuliform = 2, Cirriform = 3 };
const char* cloud_type_name(CloudType t);

// What the classifier reads of one cloud layer (a run of cloudy levels in a column).
struct CloudLayerTraits {
  double thickness_m = 0.0;         // from the run's lowest to its highest level, plus one level spacing
  double base_above_ground_m = 0.0; // the run's lowest level above the ground (sea level without terrain)
  double ice_share = 0.0;           // ice's share of the run's optical depth (0..1)
  double mean_cover = 1.0;          // the run's mean cloud fraction over its levels
  double lapse_k_per_km = 0.0;      // the column's 0-3 km lapse rate; NaN without temperature
};

// Soft memberships (stratiform, cumuliform, cirriform), summing to 1; the formulas are in
// docs/physics.md. Continuous in every input, so the maps interpolate without jumps.
std::array<double, 3> cloud_type_memberships(const CloudLayerTraits& t);
CloudType dominant_type(const std::array<double, 3>& memberships);

// The vertical profile of a type at normalised height eta in the layer (0 at its base, 1 at its
// top): the in-cloud water's shape with height, in [0, 1].
double type_profile(CloudType t, double eta);

// In-cloud extinctions a cloud typically holds (1/m), from which the cover is diagnosed where the
// file gives none: liquid water 0.13 g/m3 in droplets of 10 um (3 LWC / (2 rho_w r_e)), ice 0.01
// g/m3 in crystals of 30 um.
inline constexpr double kTypicalLiquidExtinctionPerM = 0.02;
inline constexpr double kTypicalIceExtinctionPerM = 5e-4;

struct WeatherTextures {
  int nx = 0, ny = 0;  // longitude fastest, as the grid's columns
  // Maximum-random overlap (MaxRandomOverlap) of the cloudy levels' cover: all, and per layer by
  // height above the ground (below 2 km, 2-6 km, above 6 km; MapOptions), 0 in a clear column.
  std::vector<float> cover, cover_low, cover_mid, cover_high;
  // Lowest and highest cloudy level (m above sea level), NaN in a clear column.
  std::vector<float> base_m, top_m;
  // Ice's share of the column's optical depth (0..1), NaN in a clear column.
  std::vector<float> ice_share;
  // The column's main layer (the run of cloudy levels with the largest optical depth): its type and
  // the memberships (stratiform, cumuliform, cirriform) interleaved, 3 per column (0 when clear).
  std::vector<CloudType> type;
  std::vector<float> memberships;
  bool cover_from_water = false;     // the file gave no cloud fraction: the covers are diagnosed
  bool heights_above_ground = false; // the layers are measured from the terrain (else sea level)
  bool has_lapse_rate = false;       // the classifier had temperatures (the convective signal)
  double build_ms = 0.0;             // the cost of building them (and the diagnosed cover)
  // Cloudy columns of each type (indexed by CloudType), for the reports.
  std::array<std::size_t, 4> columns_of_type{};
};

// The cover per node diagnosed from the water where a file gives no cloud fraction:
// c = min(1, max(s_l / S_l(eta), s_i / S_i(eta))), S(eta) = S_typical (0.25 + 0.75 P_type(eta)),
// with eta and the type those of the node's layer (docs/physics.md).
std::vector<float> diagnosed_fraction(const VolumeGrid& grid, const GridMeanExtinction& medium);

// The textures of a medium (its fraction, or the diagnosed one when `fraction_diagnosed`).
WeatherTextures weather_textures(const VolumeGrid& grid, const GridMeanExtinction& medium, bool fraction_diagnosed);

// The modelled cloud's type per column (2 floats per column: cumuliform and cirriform memberships;
// stratiform is the rest): the textures' memberships, and in a clear column the mean of its cloudy
// neighbours' (3 x 3, two passes, the longitudes wrapping where the grid does), so the cells at a
// cloud's edge, whose corners reach clear columns, take the cloud's type. 0 (stratiform) far from cloud.
std::vector<float> detail_type_memberships(const VolumeGrid& grid, const WeatherTextures& w);

// The textures at the grid column nearest (lat, lon) (longitude taken modulo 360), as one line for
// `probe`: the type and its memberships, the covers, base, top and ice share. Empty when the
// textures were left out or the point is outside the grid.
std::string weather_at_text(const VolumeGrid& grid, const WeatherTextures& w, double lat_deg, double lon_deg);

// One line for the reports: the cloudy columns' types and whence the cover came.
std::string weather_textures_note(const WeatherTextures& w);

}  // namespace cv::core
