// The sun march's bounds.
#include "kernel/march_limits.hpp"

#include <algorithm>
#include <cmath>

#include <glm/glm.hpp>

#include "physics/physics.hpp"

namespace cv::core {
namespace {
namespace p64 = cv::physics::f64;
}  // namespace

double sun_step_limit_m(const VolumeGrid& grid, const CloudLayer& layer, const MarchSettings& settings) {
  const glm::dvec3 start(grid.lon_deg.start, grid.lat_deg.start, grid.alt_m.start);
  const glm::dvec3 step(grid.lon_deg.step, grid.lat_deg.step, grid.alt_m.step);
  const glm::dvec3 count(grid.lon_deg.count, grid.lat_deg.count, grid.alt_m.count);
  const double floor_m = layer.empty ? grid.alt_m.start : layer.bottom_m;
  return p64::sun_step_limit_m(settings.quality.max_sun_step_m, start, step, count, grid.earth_radius_m + std::max(floor_m, 0.0));
}

int max_sun_march_steps(int sun_steps, double max_step_m, double r0_m, double bottom_m, double top_m,
                        double mu_sun_min) {
  const int ss = std::max(sun_steps, 1);
  const double rb = r0_m + std::max(bottom_m, 0.0), rt = r0_m + std::max(top_m, bottom_m);
  if (mu_sun_min > 0.0) {
    // One segment, up through the top; 2 more steps for float rounding on the GPU.
    const double mu = std::min(mu_sun_min, 1.0);
    const double len_m = -rb * mu + std::sqrt(std::max(rb * rb * mu * mu + rt * rt - rb * rb, 0.0));
    const double steps = max_step_m > 0.0 ? std::max(static_cast<double>(ss), std::ceil(len_m / max_step_m)) : ss;
    return static_cast<int>(std::min(steps, static_cast<double>(std::max(p64::CV_SUN_SEGMENT_STEPS_MAX, ss)))) + 2;
  }
  if (!(max_step_m > 0.0)) return 2 * ss;
  const double chord_m = 2.0 * std::sqrt(std::max(rt * rt - rb * rb, 0.0));
  // Segments of lengths L0 + L1 <= chord: both at sun_steps (2 ss), one of them longer
  // (ss + L/step + 1), or both (chord/step + 2); 2 more for float rounding on the GPU.
  const double by_length = static_cast<double>(ss) + std::ceil(chord_m / max_step_m) + 4.0;
  const int cap = 2 * std::max(p64::CV_SUN_SEGMENT_STEPS_MAX, ss);
  return static_cast<int>(std::min(static_cast<double>(cap), std::max(2.0 * ss, by_length)));
}

}  // namespace cv::core
