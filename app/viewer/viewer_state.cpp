// The viewer's derived quantities: the sun from the scene's spec, the march size, change detection.
#include "viewer/viewer_state.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>

#include "scene/frame_spec.hpp"
#include "scene/framing.hpp"

namespace cv::viewer {

core::Sun resolve_sun(const core::Scene& scene, const core::CloudVolume& volume) {
  const std::size_t step = static_cast<std::size_t>(std::max(0, scene.time_step));
  // A valid time without a 'T' is a bare step index (the file had no usable time axis).
  std::optional<std::int64_t> valid;
  if (step < volume.times.size() && volume.times[step].iso_utc.find('T') != std::string::npos) valid = volume.times[step].unix_s;
  return core::resolve_sun(scene.sun, valid, scene.camera ? scene.camera->lon_deg : 0.0);
}

void march_size(const core::Scene& scene, int window_w, int window_h, int& w, int& h) {
  core::march_size(window_w, window_h, scene.render.resolution_scale, w, h);  // as resolve_frame sizes `render`'s march
}

namespace {
bool same_camera(const std::optional<core::Camera>& a, const std::optional<core::Camera>& b) {
  if (a.has_value() != b.has_value()) return false;
  if (!a) return true;
  return a->lat_deg == b->lat_deg && a->lon_deg == b->lon_deg && a->alt_m == b->alt_m && a->heading_deg == b->heading_deg &&
         a->pitch_deg == b->pitch_deg && a->fov_deg == b->fov_deg && a->width == b->width && a->height == b->height;
}
bool same_settings(const core::MarchSettings& a, const core::MarchSettings& b) {
  // Every setting that changes the marched image; `frame` is the accumulation's own counter.
  return a.view_step_m == b.view_step_m && a.sun_steps == b.sun_steps && a.max_sun_step_m == b.max_sun_step_m && a.octaves == b.octaves && a.octave_a == b.octave_a &&
         a.octave_b == b.octave_b && a.octave_c == b.octave_c && a.octave_gate == b.octave_gate && a.droplet_diameter_um == b.droplet_diameter_um &&
         a.liquid_phase_hg == b.liquid_phase_hg && a.ice_g == b.ice_g && a.blue_noise == b.blue_noise &&
         a.noise_amount == b.noise_amount && a.noise_scale_m == b.noise_scale_m && a.atmosphere == b.atmosphere &&
         a.globe == b.globe && a.ambient == b.ambient && a.sky_steps == b.sky_steps && a.atmo_sun_steps == b.atmo_sun_steps &&
         a.ground_albedo == b.ground_albedo && a.ground_texture == b.ground_texture && a.skip_empty == b.skip_empty &&
         a.adaptive_steps == b.adaptive_steps && a.max_step_optical_depth == b.max_step_optical_depth &&
         a.min_transmittance == b.min_transmittance;
}
}  // namespace

bool same_march(const core::Scene& a, const core::Scene& b) {
  return a.data.path == b.data.path && a.time_step == b.time_step && same_camera(a.camera, b.camera) && a.width == b.width &&
         a.height == b.height && a.sun.mode == b.sun.mode && a.sun.datetime_utc == b.sun.datetime_utc &&
         a.sun.subsolar_lat_deg == b.sun.subsolar_lat_deg && a.sun.subsolar_lon_deg == b.sun.subsolar_lon_deg &&
         a.sun.irradiance == b.sun.irradiance && same_settings(a.render.march, b.render.march) &&
         a.render.resolution_scale == b.render.resolution_scale;
}

}  // namespace cv::viewer
