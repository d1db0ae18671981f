// A scene: everything that decides an image (data source and subset, time step, camera, sun,
// lighting and quality settings, overlays), as one plain struct that the renderer reads, the viewer
// edits and the scene file (JSON, versioned) stores, so every image can be reproduced.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "frame/camera.hpp"
#include "scene/camera_path.hpp"
#include "settings/march_settings.hpp"
#include "volume/time_interpolation.hpp"
#include "settings/overlay_settings.hpp"

namespace cv::core {

// Where the clouds come from, and the part of the file the scene uses (importers read only that).
struct DataSource {
  std::string path;  // NetCDF or .cvvol; a relative path is taken from the scene file's folder
  std::optional<std::array<double, 4>> region_deg;  // west, east, south, north
  std::optional<std::array<double, 2>> levels_hpa;  // min, max pressure of the levels read
  int horizontal_stride = 1;
  double dz_m = 0.0;  // vertical spacing of the resampled grid; 0: the importer's default
  // A file with temperature and humidity but no cloud field: a cloud diagnosed from relative
  // humidity (importers' ImportOptions::diagnose_cloud), with the scheme's critical humidity.
  bool diagnose_cloud = false;
  double rh_critical = 0.8;
};

// How the sun is placed: where it stood at the data's valid time (the scene's instant), at a given
// UTC date/time, by hand through its subsolar point, or for teaching at local noon over the camera's
// longitude (the declination of the instant kept), so an animation never goes dark.
enum class SunMode { ValidTime, DateTime, Manual, LocalNoon };
struct SunSpec {
  SunMode mode = SunMode::ValidTime;
  std::string datetime_utc;  // ISO 8601, for SunMode::DateTime
  double subsolar_lat_deg = 0.0, subsolar_lon_deg = 0.0;  // for SunMode::Manual
  double irradiance = 1.0;  // relative units at the top of the atmosphere
};

// A scene's march settings before any file or option changes them: the product's look, with the
// air, the globe and ambient sky light on (MarchSettings alone defaults to clouds on black, which
// tests of the cloud physics rely on). An empty ground_texture means the Natural Earth relief
// where it is installed; "none" means the constant ground_albedo. A droplet diameter of 0 is taken
// from the data (CloudVolume::liquid_r_eff_um) when the scene is rendered.
inline MarchSettings scene_march_defaults() {
  MarchSettings m;
  m.features.atmosphere = true;
  m.features.globe = true;
  m.medium.ambient = 1.0;
  m.medium.droplet_diameter_um = 0.0;  // from the data: twice the effective radius its extinction assumed
  // The two-stream source for multiple scattering: against the Monte Carlo far closer than the
  // octave sum on thick cloud (docs/physics.md), where the octaves leave sunlit cloud darker than
  // the sea. "multiple_scattering": "octaves" in a scene file restores the octave sum.
  m.medium.ms_two_stream = true;
  return m;
}

// Settings of the image as a whole (the march's own settings are in MarchSettings).
struct RenderSettings {
  MarchSettings march = scene_march_defaults();
  std::string quality = "default";  // the preset the march settings came from, or "custom"
  int accumulate = 1;               // jittered frames averaged per image
  double resolution_scale = 1.0;    // march at this fraction of the output size
  // Tonemapping: automatic (render::auto_exposure, from the marched image's luminance) unless a
  // number is given; `exposure` is then that number ("exposure": "auto" or a number in files).
  bool auto_exposure = true;
  double exposure = 4.0;
  // Frame-time budget in ms (`render --budget-ms`, the viewer's frame budget): the quality knobs
  // are chosen from the measured front to fit it (app/bench/quality_front.hpp). 0: off.
  double budget_ms = 0.0;
};

// The scene's instant: a UTC valid time anywhere within the file's times (between two steps the
// medium is interpolated), or, when valid_utc is empty, the time step `Scene::time_step`.
struct TimeSpec {
  std::string valid_utc;  // ISO 8601, YYYY-MM-DDThh:mm:ssZ; empty: Scene::time_step
  TimeInterpolation interpolation = TimeInterpolation::Auto;  // auto: advected where the file has winds, else linear
};

// One more view beside the scene's own in the viewer (issue 17): a file (empty: the scene's own) at a
// time (empty: the scene's instant; else a UTC time YYYY-MM-DDThh:mm:ssZ or a step index of that
// file), as `view --compare FILE[@T] | @T` gives it.
struct ViewSource {
  std::string path;  // a relative path is taken from the scene file's folder
  std::string time;
};

// The viewer's views when the scene is opened: the scene's own first, then `compare`.
struct ViewsSpec {
  static constexpr int kMaxCompare = 3;  // four views in all
  std::string layout = "grid";           // grid, or swipe (a divider between exactly two views)
  bool linked = true;                    // cameras and time move together
  double divider = 0.5;                  // the swipe divider, a fraction of the width
  std::vector<ViewSource> compare;
};

struct Scene {
  static constexpr int kVersion = 1;
  DataSource data;
  int time_step = 0;
  TimeSpec time;
  // No camera: frame the volume from the south and above (auto_camera in the renderer).
  std::optional<Camera> camera;
  // A flyover's camera path (`cloudviewer record`): keyframes tied to weather time. `render` and
  // the viewer use `camera`; record samples the path per video frame.
  std::optional<CameraPath> path;
  int width = 960, height = 540;
  SunSpec sun;
  RenderSettings render;
  // Overlays drawn with the clouds, composited by depth (settings/overlay_settings.def).
  std::vector<OverlaySpec> overlays;
  // Several views in the viewer (nothing: the scene's view alone). `render` draws the scene's own.
  std::optional<ViewsSpec> views;
};

}  // namespace cv::core
