// What the viewer holds: the shared Scene (everything that decides the image), the loaded volume,
// and what is derived from them each frame (the camera at the march size, the sun).
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "frame/camera.hpp"
#include "frame/march_stats.hpp"
#include "frame/sun.hpp"
#include "settings/march_settings.hpp"
#include "scene/scene.hpp"
#include "volume/cloud_volume.hpp"
#include "viewer/keyframes.hpp"
#include "viewer/playback.hpp"
#include "viewer/plot_panels.hpp"
#include "viewer/probe_panel.hpp"
#include "viewer/views.hpp"

namespace cv::viewer {

// Bad viewer input (arguments, a date/time typed in): one line naming what and what was expected.
struct ViewerInputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The "Views" panel (several views side by side, issue 17): the layout and the link, what each view
// shows, and what the panel asks of the main loop (which owns the views).
struct ViewsPanel {
  ViewLayout layout = ViewLayout::Grid;
  double divider = 0.5;  // the swipe divider, a fraction of the width
  bool link_camera = true, link_time = true;
  std::vector<std::string> labels;  // per view (view 0 first): its source and valid time
  std::vector<core::ViewSource> sources;  // views 1..: file (empty: view 0's) and time, for a saved scene
  std::string add_source;           // FILE, FILE@TIME, or @TIME (this view's file at another time)
  bool add_requested = false;
  int remove_requested = -1;        // a view (1..) to close
  int step_view = -1, step_dir = 0;  // a view whose time goes to its file's previous / next step
  std::string message;              // the last request's problem, or empty
};

struct ViewerState {
  core::Scene scene;
  core::CloudVolume volume;
  std::string import_report;  // the importer's report as text, for the data panel
  bool fly_mode = false;      // the camera panel's mode; mouse and keys follow it
  Playhead play;              // the timeline: where in the file's times, playing or not
  bool timeline = false;      // the file has two or more ascending UTC valid times: play, scrub
  KeyframeEditor keys;        // the camera-path panel (keyframes.hpp)
  ViewsPanel views;           // several views (views.hpp); view 0 is this scene
  ProbePanel probe;           // the column under the last click (probe_panel.hpp)
  SectionPanel section;       // a vertical section of view 0's file (plot_panels.hpp)
  SeriesPanel series;         // a time series at a point of view 0's file
  double series_now_hours = 0.0;  // view 0's time on the series' axis, for its marker
  // The progressive path tracer (issue 11, item 4): every view traces one sample per pixel per frame
  // at its march size into a running mean, up to path_spp, instead of marching; any change that
  // restarts the march's accumulation restarts it.
  bool path_trace = false;
  int path_spp = 256;
  // Temporal reprojection (issue 18, item 4; render/reprojector.hpp): each view marches 1/16 of its
  // pixels per frame and reprojects the rest from its last image, until 16 frames of a still scene
  // have marched them all (single frames at step middles: no jittered accumulation). Views with
  // overlays and the path tracer march every pixel.
  bool reproject = false;
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

// The scene the "Scene file" panel saves: view 0's scene with the open views (each other view's
// file and instant, the layout, the link, the divider) as its "views", or none with one view open.
// Cameras and time count as linked only when both are.
core::Scene scene_to_save(const ViewerState& s);

}  // namespace cv::viewer
