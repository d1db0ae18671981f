// A cumulus-like bubble of liquid (optical depth ~20 through its core) at 3 km over (0, 0) on a
// 4 x 4 degree box, optionally under a thin ice layer at 8-9.5 km: the render tests' small scene.
#pragma once

#include <cmath>

#include "volume/cloud_volume.hpp"

namespace cv::test {

struct BubbleScene {
  core::VolumeGrid grid;
  core::TimeStepData data;
  explicit BubbleScene(bool ice_layer = true) {
    grid.lon_deg = {-2.0, 0.1, 41};
    grid.lat_deg = {-2.0, 0.1, 41};
    grid.alt_m = {500.0, 250.0, 41};
    data[core::Field::ExtinctionLiquid].assign(grid.points(), 0.0f);
    if (ice_layer) data[core::Field::ExtinctionIce].assign(grid.points(), 0.0f);
    for (int k = 0; k < grid.alt_m.count; ++k)
      for (int j = 0; j < grid.lat_deg.count; ++j)
        for (int i = 0; i < grid.lon_deg.count; ++i) {
          const double x = grid.lon_deg.at(i), y = grid.lat_deg.at(j), z = grid.alt_m.at(k);
          const double r2 = (x * x + y * y) / 0.25 + (z - 3000.0) * (z - 3000.0) / (1500.0 * 1500.0);
          data[core::Field::ExtinctionLiquid][grid.index(i, j, k)] = static_cast<float>(0.02 * std::exp(-2.0 * r2));
          if (ice_layer && z > 8000.0 && z < 9500.0) data[core::Field::ExtinctionIce][grid.index(i, j, k)] = 2e-4f;
        }
  }
};

}  // namespace cv::test
