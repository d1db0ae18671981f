// Resolving a scene against its data for one frame.
#include "scene/frame_spec.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "scene/framing.hpp"
#include "scene/quality.hpp"

namespace cv::core {

void march_size(int width, int height, double resolution_scale, int& march_w, int& march_h) {
  const double s = std::clamp(resolution_scale, 0.01, 1.0);
  march_w = std::max(1, static_cast<int>(std::lround(width * s)));
  march_h = std::max(1, static_cast<int>(std::lround(height * s)));
}

FrameSpec resolve_frame(const Scene& scene, const CloudVolume& volume) {
  if (scene.time_step < 0 || static_cast<std::size_t>(scene.time_step) >= volume.times.size()) {
    throw std::out_of_range("resolve_frame: time step " + std::to_string(scene.time_step) + " of " +
                            std::to_string(volume.times.size()));
  }
  const VolumeGrid& g = volume.grid;
  FrameSpec f;
  f.camera = scene.camera ? *scene.camera : auto_camera(g, scene.width, scene.height);
  f.camera.width = scene.width, f.camera.height = scene.height;
  f.march_camera = f.camera;
  march_size(scene.width, scene.height, scene.render.resolution_scale, f.march_camera.width, f.march_camera.height);
  const ValidTime& vt = volume.times[static_cast<std::size_t>(scene.time_step)];
  // A valid time without a 'T' is a bare step index (the file had no usable time axis).
  f.valid_time_known = vt.iso_utc.find('T') != std::string::npos;
  f.sun = resolve_sun(scene.sun, f.valid_time_known ? std::optional<std::int64_t>(vt.unix_s) : std::nullopt, f.camera.lon_deg);
  f.march = scene.render.march;
  f.march.quality.view_step_m = resolve_view_step_m(scene.render, g);
  if (!(f.march.medium.droplet_diameter_um > 0.0)) f.march.medium.droplet_diameter_um = 2.0 * volume.liquid_r_eff_um;  // from the data
  f.accumulate = std::max(1, scene.render.accumulate);
  f.exposure = scene.render.exposure;
  f.auto_exposure = scene.render.auto_exposure;
  return f;
}

}  // namespace cv::core
