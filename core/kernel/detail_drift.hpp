// The modelled cloud's sub-grid detail carried by the wind (docs/physics.md, "The detail moves with
// the wind"). The detail's noise is displaced, level by level, by the time integral of that level's
// mean horizontal wind, so in an animation the sub-grid shapes travel with the cloud. One
// displacement per level keeps the cell's share of the noise exact: each horizontal slice of a cell
// holds whole periodic tiles, and a shift of a periodic slice leaves its values' distribution as it
// was, so every cell keeps the data's cover and mean extinction at every instant.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "kernel/march_params.hpp"
#include "scene/instant.hpp"
#include "volume/cloud_volume.hpp"

namespace cv::core {

struct PreparedVolume;

// Per level k, the mean horizontal wind of one time step as a rate in grid cells per second: values
// 2k (along the longitude index, eastward) and 2k + 1 (along the latitude index, northward). The
// mean is weighted by the grid-mean extinction times cos(latitude) on a level that holds cloud, so
// the detail follows the cloud-bearing air, and by cos(latitude) on a level without cloud. The
// eastward angular rate u / (R cos(lat)) weighted by area is sum(w u) / (R sum(w cos(lat))): finite
// at the poles. Nodes without wind (NaN) are left out; a file without horizontal winds gives zeros.
std::vector<double> level_drift_rate(const VolumeGrid& grid, const TimeStepData& data);

// The detail's displacement at `at` (grid cells, 2 per level as above) since the file's first step:
// the integral of the level rates, linear in time between steps, so the displacement is continuous
// in time and moves at the interpolated wind's rate. Reads (once per volume, memoised in
// DetailDrift) the winds of every step up to at.step1. Files without valid UTC times do not move.
class DetailDrift {
 public:
  std::vector<double> at(CloudVolume& volume, const Instant& instant);

 private:
  const std::vector<double>& rate(CloudVolume& volume, std::size_t step);
  const CloudVolume* volume_ = nullptr;
  std::vector<std::vector<double>> rates_;  // per step, empty until read
};

// The kernel's u_detail_shift texels (2 floats per level, in noise tiles) for a prepared volume and
// frame parameters: the drift times the tiles per cell (p.u_detail_tiles), reduced modulo one tile
// (so float keeps it to about 1e-6 of a tile however far the cloud has travelled) and unwrapped from
// level to level, so the kernel's linear blend between two levels never crosses a tile's seam. Zeros
// without a drift.
std::vector<float> detail_shift_texels(const PreparedVolume& v, const kernel::MarchParams& p);

// One line for the user: how far the wind has carried the detail since the file's first step at the
// level that holds the most cloud (km east and north, at the grid's middle latitude); empty without
// a drift.
std::string detail_drift_note(const PreparedVolume& v, const std::string& first_step);

}  // namespace cv::core
