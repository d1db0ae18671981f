// The vertical optical depth of the clouds per grid column (liquid + ice), for the octave gate
// (shaders/common/octaves.glsl): computed once per volume, sampled horizontally as the medium is.
#pragma once

#include <vector>

#include "volume/cloud_volume.hpp"

namespace cv::core {

struct ColumnDepth {
  int nx = 0, ny = 0;      // columns along longitude and latitude, as the grid
  std::vector<float> tau;  // vertical optical depth (dimensionless) per column, longitude fastest

  // The optical depth of the column at a point, bilinear between the four columns around it with
  // the 3-D sampler's horizontal rules (volume_coords, volume_fetch_index): longitude wraps on
  // global grids, latitude clamps at the pole rows, a regional grid fades to 0 over one cell
  // beyond its sides; 0 outside. the march kernel's column_tau reads the uploaded map the same way.
  double at(const VolumeGrid& grid, double lat_deg, double lon_deg) const;
};

// The trapezoid over levels of liquid + ice (1/m) times the level spacing (m): the exact integral
// of the sampler's piecewise-linear profile in altitude. Either field may be empty (none).
ColumnDepth column_depth(const VolumeGrid& grid, const std::vector<float>& liquid_per_m,
                         const std::vector<float>& ice_per_m);

}  // namespace cv::core
