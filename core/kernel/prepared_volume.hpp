// A time step made ready to march, once: the grid-mean extinction and what every march derives from
// it (the extinction pyramid, the column optical depths, the layer that holds cloud, the largest
// extinction). The GPU uploads it, the CPU kernel reads it, the Monte Carlo and the bench share it.
#pragma once

#include <array>
#include <limits>
#include <memory>
#include <vector>

#include <glm/vec2.hpp>

#include "kernel/march_params.hpp"
#include "frame/camera.hpp"
#include "frame/sun.hpp"
#include "settings/march_settings.hpp"
#include "volume/grid_mean.hpp"
#include "volume/column_depth.hpp"
#include "volume/time_interpolation.hpp"
#include "volume/extinction_pyramid.hpp"
#include "kernel/weather_textures.hpp"

namespace cv::core {

// Floats per column of each layer of PreparedVolume::column_maps, and its layers.
inline constexpr std::size_t kColumnMapChannels = 4;
inline constexpr std::size_t kColumnMapLayers = 2;

struct PrebuiltMsSource;  // kernel/ms_source.hpp

struct PreparedVolume {
  VolumeGrid grid;
  GridMeanExtinction extinction;
  CloudLayer layer;               // the altitudes that hold cloud: the shell the marches intersect
  double sigma_max_per_m = 0.0;   // largest extinction (liquid + ice): sizes the sun marches' steps
  bool wraps = false, global_lat = false;
  ColumnDepth columns;            // vertical optical depth per column (the octave gate)
  // Per column, (optical depth, ground altitude m (0 without terrain), cumuliform and cirriform
  // memberships of the weather textures, spread into clear columns next to cloud) interleaved: the
  // kernel's four-channel u_column_tau (the octave gate reads .r, the layer masks .g, the modelled
  // cloud's type .b and .a). Then a second layer of four channels per column: the ice's part of
  // the optical depth (.r; the two-stream's sky light under a column takes each phase's mean cosine),
  // and three unused. u_column_tau is a two-layer 2-D array texture of these.
  std::vector<float> column_maps;
  ExtinctionPyramid pyramid;
  std::vector<glm::vec2> pyramid_packed;  // every level's (min, max), finest first, as the GPU reads them
  std::array<int, ExtinctionPyramid::kMaxLevels> level_offset{};  // first brick of each level in pyramid_packed
  // The 2-D weather textures of this medium (cover per layer, type, base, top; issue 18 item 1).
  // Where the file gives no cloud fraction, extinction.fraction holds the cover diagnosed from the
  // water (weather.cover_from_water), which the modelled cloud takes.
  WeatherTextures weather;
  // The instant this medium stands for (seconds since 1970-01-01 UTC, from the file's valid times;
  // NaN where the cache did not set it), and, where it was advected between two steps, the winds'
  // angular motion at that instant (core::angular_flow): the viewer's reprojection moves its history
  // by the flow times the time between two frames' media. Empty otherwise (a step itself, a linear
  // blend: nothing moves).
  double time_s = std::numeric_limits<double>::quiet_NaN();
  AngularFlow flow;
  // The two-stream source built ahead for one key (the viewer's prefetcher builds it on its thread
  // for the sun at this instant, so playback does not build it on the render thread), or null. The
  // marches take it where their key matches (ms_source_for) and build their own otherwise. Set
  // before the volume is shared, never after.
  std::shared_ptr<const PrebuiltMsSource> ms_prebuilt;
};

// With `weather` false the weather textures are left out (weather.nx == 0, the column maps' type
// channels 0, no cover diagnosed): only the modelled cloud reads them, and on a global 0.25 degree
// step they cost about half a second, so the data mode's time steps skip them.
PreparedVolume prepare_volume(const VolumeGrid& grid, GridMeanExtinction extinction, bool weather = true);

// Per cloud type and cover entry of the table (CV_DETAIL_TYPES rows of CV_DETAIL_COVERS + 1), the
// smallest ramp mean m(c) over the whole tile's row and every horizontal slice's row
// (shaders/common/detail.glsl): the kernel blends two slices' rows, so c / m(c) at any point is at
// most c over this. 0 where the table has no such row.
std::vector<double> detail_least_means(const std::vector<float>& table);

// The largest extinction the march kernel's medium can take with these settings, the tracking's
// majorant (1/m): the volume's largest node sum for the data's field; for the modelled cloud
// (march.glsl detail_factor) (1 - a) max s + a K max(s_i / c_i), K the table's largest c / m(c)
// (`detail_table` of shaders/common/detail.glsl, 2 floats per cover). Trilinear s / c is at most the
// largest s_i / c_i of a cell's nodes (the mediant inequality), and c / m(c) is largest at a table
// entry (convex over linear). Nodes with extinction but no fraction make it infinite.
double medium_majorant(const PreparedVolume& v, const MarchSettings& s, const std::vector<float>& detail_table);

// The pyramid's bricks for the medium the kernel draws with these settings, packed as
// PreparedVolume::pyramid_packed (the kernel's u_min_max: only the max, .y, is read): the prepared
// pyramid itself in the data mode; for the modelled cloud each brick's bound
// (1 - a) max s + a max(s_i / c_i) K(c_lo, c_hi) over the brick's dilated nodes, K the table's
// largest c / m(c) between the brick's smallest and largest cover (convex over linear: largest at
// a table entry, so the entries bracketing [c_lo, c_hi] bound it). A brick without cloud stays 0
// (the same empty space), a node with extinction but no fraction makes its bricks 3e38. So the
// tracking can use brick majorants, and the march's adapted steps its bounds, in this mode too.
std::vector<glm::vec2> medium_pyramid(const PreparedVolume& v, const MarchSettings& s, const std::vector<float>& detail_table);
inline PreparedVolume prepare_volume(const VolumeGrid& grid, const TimeStepData& data) {
  return prepare_volume(grid, grid_mean_extinction(grid, data));
}

// What of the medium a march leaves out (march_settings.def: the layer band, hide_liquid, hide_ice),
// for what is derived from the whole medium outside the march: the two-stream source and the octave
// gate's column optical depths are made without the hidden cloud, as the march samples it.
struct MediumMask {
  bool hide_liquid = false, hide_ice = false, band = false, sea_level = false;
  double bottom_m = 0.0, top_m = 0.0;  // the band's heights above the ground (or sea level)
  bool any() const { return hide_liquid || hide_ice || band; }
  // Whether a node at alt_m over ground at ground_m is in the band shown (the kernel's layer_shown).
  bool shown(double alt_m, double ground_m) const {
    const double h = sea_level ? alt_m : alt_m - ground_m;
    return !band || (h >= bottom_m && h < top_m);
  }
  bool operator==(const MediumMask&) const = default;
};
MediumMask medium_mask(const MarchSettings& s);

// The column map (optical depth, ground, types) the kernel reads as u_column_tau for a mask:
// the prepared one's ground, and the trapezoid over levels of what the mask shows (column_depth's
// rule, a hidden node counting 0). Without a mask, the prepared map itself.
std::vector<float> column_maps_for(const PreparedVolume& v, const MediumMask& mask);

// The march kernel's parameters for one frame: the camera (pixels of cam.width x cam.height), the
// sun, the settings, and the ground texture's size ((0, 0): the constant albedo).
kernel::MarchParams march_params(const PreparedVolume& v, const Camera& cam, const Sun& sun, const MarchSettings& s,
                                 glm::ivec2 ground_size = {0, 0});

}  // namespace cv::core
