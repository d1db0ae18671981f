// The interactive viewer, `cloudviewer view INPUT`: a GLFW window with Dear ImGui panels over the
// GPU raymarcher's accumulated image; with --frames N --screenshot PNG it runs N frames and exits.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "scene/scene.hpp"

namespace cv::viewer {

struct ViewerOptions {
  std::string input;        // NetCDF, .cvvol or a scene .json
  std::optional<core::Scene> scene;  // the scene file's, when INPUT is one (options given override it)
  bool time_given = false, scale_given = false;
  int width = 1280, height = 720;  // window size, screen pixels
  int time_step = 0;
  std::string time_utc;     // --time ISO: an instant (between steps: interpolated)
  double play_h_per_s = 0.0;  // --play H: start playing at H forecast hours per second (0: paused)
  bool realtime = false;      // --realtime: with --frames, playback follows wall time and does not wait (measures the prefetch)
  int frames = 0;           // 0: interactive until the window closes
  std::string screenshot;   // PNG of the window's framebuffer after the last frame
  bool hide_ui = false;     // start with the panels hidden (F1 toggles them)
  double scale = 1.0;       // resolution scale: march at this fraction of the window size
  double frame_budget_ms = -1.0;  // --frame-budget: the scene's render.budget_ms (0 off); < 0: not given
  std::vector<std::string> compare;  // --compare FILE[@TIME] | @TIME: more views (issue 17), up to 3
  std::string layout = "grid";       // --layout grid|swipe (swipe: two views)
  bool layout_given = false;         // --layout overrides the scene file's views.layout
  bool unlinked = false;             // --unlinked: cameras and time not linked between views
  std::string section, series;       // --section LAT,LON,LAT,LON[,FIELD], --series LAT,LON: open those panels, drawn
  bool path_trace = false;           // --quality reference: the progressive path tracer from the first frame
  int path_spp = 0;                  // --spp N: its samples per pixel (0: the state's default)
  bool reproject = false;            // --reproject: temporal reprojection (ViewerState::reproject)
  bool diagnose_cloud = false;       // --diagnose-cloud: a cloud from relative humidity where a file has none
  double rh_critical = 0.0;          // --rh-critical RH (0: the scene's)
  double orbit_px = 0.0;             // --orbit PX: the globe dragged PX pixels to the right every frame (a scripted orbit)
};

// Parses the `view` arguments and runs; returns the exit code (2 with one line for bad arguments).
// Errors in the input file propagate as the importers' exceptions, as for `render`.
int cmd_view(const std::vector<std::string>& args);

int run_viewer(const ViewerOptions& options);

}  // namespace cv::viewer
