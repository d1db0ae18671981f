// OpenVDB export for graphics teams (issue 16): a time step's medium (grid-mean liquid and ice
// extinction, cloud fraction) resampled onto voxels in metres in a local tangent frame at the
// region's centre, with the frame and units in each grid's metadata. OpenVDB is PRIVATE to cv_vdb.
#pragma once

#include <string>

#include "io/output_file.hpp"

#include <glm/vec3.hpp>

#include "volume/cloud_volume.hpp"
#include "volume/grid_mean.hpp"

namespace cv::vdb {

// The local tangent frame: x east, y north, z up, metres, origin on the sphere (altitude 0) at the
// grid's centre; voxels of size voxel_m (the grid's cell at the centre, and its vertical spacing).
struct TangentFrame {
  double lat0_deg = 0.0, lon0_deg = 0.0, earth_radius_m = 0.0;
  glm::dvec3 voxel_m{1.0};
  glm::dvec3 origin_ecef{0.0}, east{1, 0, 0}, north{0, 1, 0}, up{0, 0, 1};
  glm::dvec3 to_ecef(const glm::dvec3& local_m) const { return origin_ecef + local_m.x * east + local_m.y * north + local_m.z * up; }
};
TangentFrame tangent_frame(const core::VolumeGrid& grid);

struct VdbSummary {
  std::size_t active_voxels[3] = {0, 0, 0};  // extinction_liquid, extinction_ice, cloud_fraction
  double seconds = 0.0;
};

// Writes `step` of `grid` as `path` into `group` (nothing appears at `path` before the group is
// committed, so a volume and its VDB files are written together or not at all): FloatGrids "extinction_liquid" and "extinction_ice" (grid-box mean, 1/m: what the
// renderer marches) and "cloud_fraction" (0..1) where the volume has it, fog volumes whose voxel
// centres sample the volume trilinearly in its lon/lat/altitude index space; voxels outside the
// volume, with no data, or 0 stay inactive. Metadata on each grid: units, frame, origin_lat_deg,
// origin_lon_deg, earth_radius_m, valid_utc.
VdbSummary write_vdb(core::OutputGroup& group, const std::string& path, const core::VolumeGrid& grid, const core::TimeStepData& step,
                     const std::array<bool, core::kFieldCount>& has_field, const std::string& valid_utc);
// The same from the renderer's own medium: grid-mean extinction (for an instant between forecast
// steps, what core::interpolate_extinction made of the two neighbours), and the cloud fraction
// where one is given (nullptr: no cloud_fraction grid; interpolation carries extinction only).
VdbSummary write_vdb(core::OutputGroup& group, const std::string& path, const core::VolumeGrid& grid, const core::GridMeanExtinction& mean,
                     const std::vector<float>* cloud_fraction, const std::string& valid_utc);

}  // namespace cv::vdb
