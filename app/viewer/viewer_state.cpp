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

core::Scene scene_to_save(const ViewerState& s) {
  core::Scene out = s.scene;
  out.views.reset();
  if (!s.views.sources.empty()) {
    core::ViewsSpec v;
    v.layout = s.views.layout == ViewLayout::Swipe ? "swipe" : "grid";
    v.linked = s.views.link_camera && s.views.link_time;
    v.divider = s.views.divider;
    v.compare = s.views.sources;
    out.views = v;
  }
  return out;
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
// The camera path is drawn on the globe (the keyframe panel): a changed path is a changed image.
bool same_path(const std::optional<core::CameraPath>& a, const std::optional<core::CameraPath>& b) {
  if (a.has_value() != b.has_value()) return false;
  if (!a) return true;
  if (a->keyframes.size() != b->keyframes.size() || a->weather_hours_per_s != b->weather_hours_per_s || a->speed != b->speed ||
      a->ease != b->ease) {
    return false;
  }
  for (std::size_t i = 0; i < a->keyframes.size(); ++i) {
    const core::PathKeyframe &x = a->keyframes[i], &y = b->keyframes[i];
    if (x.t_s != y.t_s || x.lat_deg != y.lat_deg || x.lon_deg != y.lon_deg || x.alt_m != y.alt_m || x.heading_deg != y.heading_deg ||
        x.pitch_deg != y.pitch_deg || x.fov_deg != y.fov_deg || x.valid_utc != y.valid_utc) {
      return false;
    }
  }
  return true;
}
}  // namespace

bool same_march(const core::Scene& a, const core::Scene& b) {
  return a.data.path == b.data.path && a.time_step == b.time_step && a.time.valid_utc == b.time.valid_utc &&
         a.time.interpolation == b.time.interpolation && same_camera(a.camera, b.camera) && a.width == b.width &&
         a.height == b.height && a.sun.mode == b.sun.mode && a.sun.datetime_utc == b.sun.datetime_utc &&
         a.sun.subsolar_lat_deg == b.sun.subsolar_lat_deg && a.sun.subsolar_lon_deg == b.sun.subsolar_lon_deg &&
         a.sun.irradiance == b.sun.irradiance && core::same_image(a.render.march, b.render.march) &&
         a.render.resolution_scale == b.render.resolution_scale && a.overlays == b.overlays && same_path(a.path, b.path);
}

}  // namespace cv::viewer
