// The viewer's Dear ImGui panels: data, camera, sun and date/time, lighting, quality, scene file,
// and the statistics overlay. They edit the ViewerState's Scene; the main loop sees what changed.
#pragma once

#include <string>
#include <vector>

#include "frame/camera.hpp"
#include "frame/march_stats.hpp"
#include "frame/sun.hpp"
#include "settings/march_settings.hpp"
#include "viewer/viewer_state.hpp"

namespace cv::viewer {

// One overlay's cost, as the overlay panel shows it.
struct OverlayTiming {
  double build_ms = 0.0;  // the last (re)build of its geometry (VTK)
  double draw_ms = 0.0;   // its draw in the last overlay pass
};

struct FrameStats {
  double march_ms = 0.0;    // GPU time of the last raymarch dispatch (timer query)
  double present_ms = 0.0;  // GPU time of accumulation + tonemap draw
  double fps = 0.0;         // window frames per second, averaged over ~0.5 s
  int accumulated = 0;      // frames in the current mean (the path tracer: samples per pixel)
  bool path_trace = false;  // the mean is the path tracer's
  bool reprojecting = false;  // the view is reprojected (accumulated: frames since the last change)
  double path_error = 0.0;  // its mean relative standard error (MonteCarloImage), once 2 samples are in
  int march_w = 0, march_h = 0;
  core::MarchStats march;   // what the last marched frame sampled and left out
  std::string renderer;     // GL_RENDERER
  std::string prefetch;     // the prefetcher's resident instants, memory and hit rate (playback)
  std::vector<OverlayTiming> overlays;  // per scene overlay
};

// What the panels need besides the state, and what they ask of the main loop.
struct PanelContext {
  core::Camera home;            // the automatic framing, for "reset view"
  core::Sun sun;                // as resolved this frame
  std::string sun_error;        // why the typed date/time was not used, or empty
  std::string sun_note;         // the sun low over the whole domain (dawn, dusk or night), or empty
  double goto_lat_deg = 0.0, goto_lon_deg = 0.0, goto_alt_m = 10000.0;
  std::string scene_path = "scene.json";
  std::string scene_message;    // result of the last load/save
  double auto_exposure = 4.0;   // what the automatic exposure chose, shown while it is on
  bool exposure_held = false;   // ...held over the frames played (the forecast is playing)
  std::string budget_text;      // the frame budget's candidate and its source, when the budget is on
  std::string instant_text;     // the scene's instant, and how the medium there was made
  std::string time_warning;     // why `advected` fell back to `linear` (no winds), shown on screen
  // The Section and Series panels' figures as GL textures, re-uploaded when a figure changes.
  unsigned section_texture = 0, series_texture = 0;
  int section_version = 0, series_version = 0;
};

void draw_panels(ViewerState& state, PanelContext& ctx, const FrameStats& stats);
// Deletes the panels' textures (before the GL context goes).
void release_panel_textures(PanelContext& ctx);
void draw_stats_overlay(const FrameStats& stats, int target);

}  // namespace cv::viewer
