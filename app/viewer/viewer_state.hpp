// What the viewer holds: the shared Scene (everything that decides the image), the loaded volume,
// and what is derived from them each frame (the camera at the march size, the sun).
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>

#include "frame/camera.hpp"
#include "frame/march_stats.hpp"
#include "frame/sun.hpp"
#include "settings/march_settings.hpp"
#include "scene/scene.hpp"
#include "volume/cloud_volume.hpp"
#include "viewer/keyframes.hpp"
#include "viewer/playback.hpp"

namespace cv::viewer {

// Bad viewer input (arguments, a date/time typed in): one line naming what and what was expected.
struct ViewerInputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct ViewerState {
  core::Scene scene;
  core::CloudVolume volume;
  std::string import_report;  // the importer's report as text, for the data panel
  bool fly_mode = false;      // the camera panel's mode; mouse and keys follow it
  Playhead play;              // the timeline: where in the file's times, playing or not
  bool timeline = false;      // the file has two or more ascending UTC valid times: play, scrub
  KeyframeEditor keys;        // the camera-path panel (keyframes.hpp)
};


// The sun for the scene's SunSpec: at the current step's valid time, at the given date/time, or
// at the manual subsolar point (core::resolve_sun). Without a usable valid time it stands at noon
// over the camera. Throws std::invalid_argument for a date/time that does not parse.
core::Sun resolve_sun(const core::Scene& scene, const core::CloudVolume& volume);

// The march size for a window: the window size times the resolution scale, at least 1 x 1.
void march_size(const core::Scene& scene, int window_w, int window_h, int& w, int& h);

// True when two scenes give the same marched image (so the accumulation can go on). Exposure is
// left out: it only changes the tonemap of the same accumulated mean.
bool same_march(const core::Scene& a, const core::Scene& b);

}  // namespace cv::viewer
