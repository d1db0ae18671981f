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

Instant scene_instant(const Scene& scene, const CloudVolume& volume, const std::string& source) {
  if (!scene.time.valid_utc.empty()) return instant_at_time(volume.times, scene.time.valid_utc, source);
  return instant_at_step(volume.times, static_cast<std::size_t>(std::max(0, scene.time_step)), source);
}

FrameSpec resolve_frame(const Scene& scene, const CloudVolume& volume) {
  const VolumeGrid& g = volume.grid;
  FrameSpec f;
  f.instant = scene_instant(scene, volume, scene.data.path);
  f.camera = scene.camera ? *scene.camera : auto_camera(g, scene.width, scene.height);
  f.camera.width = scene.width, f.camera.height = scene.height;
  f.march_camera = f.camera;
  march_size(scene.width, scene.height, scene.render.resolution_scale, f.march_camera.width, f.march_camera.height);
  // A valid time without a 'T' is a bare step index (the file had no usable time axis).
  f.valid_time_known = f.instant.time_known;
  f.sun = resolve_sun(scene.sun, f.valid_time_known ? std::optional<std::int64_t>(f.instant.unix_s) : std::nullopt, f.camera.lon_deg);
  f.march = scene.render.march;
  f.march.quality.view_step_m = resolve_view_step_m(scene.render, g);
  if (!(f.march.medium.droplet_diameter_um > 0.0)) f.march.medium.droplet_diameter_um = 2.0 * volume.liquid_r_eff_um;  // from the data
  f.accumulate = std::max(1, scene.render.accumulate);
  f.exposure = scene.render.exposure;
  f.auto_exposure = scene.render.auto_exposure;
  return f;
}

}  // namespace cv::core
