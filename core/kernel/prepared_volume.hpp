// A time step made ready to march, once: the grid-mean extinction and what every march derives from
// it (the extinction pyramid, the column optical depths, the layer that holds cloud, the largest
// extinction). The GPU uploads it, the CPU kernel reads it, the Monte Carlo and the bench share it.
#pragma once

#include <array>
#include <memory>
#include <vector>

#include <glm/vec2.hpp>

#include "kernel/march_params.hpp"
#include "frame/camera.hpp"
#include "frame/sun.hpp"
#include "settings/march_settings.hpp"
#include "volume/grid_mean.hpp"
#include "volume/column_depth.hpp"
#include "volume/extinction_pyramid.hpp"

namespace cv::core {

struct PreparedVolume {
  VolumeGrid grid;
  GridMeanExtinction extinction;
  CloudLayer layer;               // the altitudes that hold cloud: the shell the marches intersect
  double sigma_max_per_m = 0.0;   // largest extinction (liquid + ice): sizes the sun marches' steps
  bool wraps = false, global_lat = false;
  ColumnDepth columns;            // vertical optical depth per column (the octave gate)
  // Per column, (optical depth, ground altitude m, 0 without terrain) interleaved: the kernel's
  // two-channel u_column_tau (the octave gate reads .r, the layer masks .g).
  std::vector<float> column_maps;
  ExtinctionPyramid pyramid;
  std::vector<glm::vec2> pyramid_packed;  // every level's (min, max), finest first, as the GPU reads them
  std::array<int, ExtinctionPyramid::kMaxLevels> level_offset{};  // first brick of each level in pyramid_packed
};

PreparedVolume prepare_volume(const VolumeGrid& grid, GridMeanExtinction extinction);
inline PreparedVolume prepare_volume(const VolumeGrid& grid, const TimeStepData& data) {
  return prepare_volume(grid, grid_mean_extinction(grid, data));
}

// The march kernel's parameters for one frame: the camera (pixels of cam.width x cam.height), the
// sun, the settings, and the ground texture's size ((0, 0): the constant albedo).
kernel::MarchParams march_params(const PreparedVolume& v, const Camera& cam, const Sun& sun, const MarchSettings& s,
                                 glm::ivec2 ground_size = {0, 0});

}  // namespace cv::core
