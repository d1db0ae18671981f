// Bounds on the sun march that both marchers and the GPU's dispatch sizing take once per frame.
#pragma once

#include "settings/march_settings.hpp"
#include "volume/grid_mean.hpp"

namespace cv::core {

// The longest a sun step may be (m) for this grid and layer: settings.max_sun_step_m, or where
// that is 0 the grid's horizontal cell size at the layer's floor (sun_step_limit_m in
// shaders/common/march_control.glsl). Both marchers take it from here, once per frame.
double sun_step_limit_m(const VolumeGrid& grid, const CloudLayer& layer, const MarchSettings& settings);

// At most how many sun steps one sun march takes over both its shell segments through the layer
// [bottom_m, top_m] above the sphere of radius r0_m: each segment takes sun_steps or
// ceil(length / max_step_m) (at most CV_SUN_SEGMENT_STEPS_MAX), and the two segments of a line
// through a shell are together no longer than its chord tangent to the floor,
// 2 sqrt(r_top^2 - r_bottom^2), so at most max(2 sun_steps, sun_steps + chord / max_step_m + 2),
// 2 more for rounding. Sizes llvmpipe's dispatches.
// mu_sun_min > 0 (smallest_sun_cosine in reference/earth_shadow.hpp): every sample that holds cloud
// sees the sun at least that high, so its sun ray leaves the shell through the top in one segment
// no longer than the path from the floor at that cosine, -rb mu + sqrt(rb^2 mu^2 + rt^2 - rb^2):
// a high sun then sizes the dispatches for its own short marches, not for a grazing one.
int max_sun_march_steps(int sun_steps, double max_step_m, double r0_m, double bottom_m, double top_m,
                        double mu_sun_min = -1.0);

}  // namespace cv::core
