// The one definition of "the value of a field at (latitude, longitude, altitude)": trilinear in
// the grid's index space, used by the CPU reference and matched by the GPU's texture sampling
// (longitude repeats on global grids, latitude clamps at the pole rows, no data elsewhere).
#pragma once

#include <vector>

#include "volume/cloud_volume.hpp"

namespace cv::core {

class VolumeSampler {
 public:
  // `field` is one of a TimeStepData's fields (longitude fastest); it must outlive the sampler.
  VolumeSampler(const VolumeGrid& grid, const std::vector<float>& field);

  // The field at a point. Outside the grid, and for corners holding NaN (no data), `nodata` is
  // used: 0 for extinction (no cloud known), NaN to see the gaps.
  double sample(double lat_deg, double lon_deg, double alt_m, double nodata) const;

  // Whether the grid's rows reach the poles (then latitude clamps to the edge rows).
  bool global_lat() const;

 private:
  const VolumeGrid& grid_;
  const std::vector<float>& field_;
  bool wraps_;
};

}  // namespace cv::core
