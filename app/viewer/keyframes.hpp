// The viewer's camera-path editing (issue 16, the keyframe panel): keyframes added at the current
// view and time, deleted, reordered and retimed on the scene's core::CameraPath, the path
// previewed at the viewer's quality and drawn on the globe, and the `record` command that renders
// it. The panel (panels.cpp) calls these; they hold no ImGui, so the tests call them too.
#pragma once

#include <optional>
#include <string>

#include "frame/camera.hpp"
#include "geometry/overlay_mesh.hpp"
#include "scene/camera_path.hpp"
#include "scene/scene.hpp"

namespace cv::viewer {

// The panel's own state: the keyframe selected, and the preview's path time while it plays.
struct KeyframeEditor {
  int selected = -1;
  bool previewing = false;
  double preview_t_s = 0.0;
  bool draw_path = true;
  std::string message;  // the last edit's problem, or empty
};

// Adds a keyframe at camera `cam` (its position, heading, pitch and fov) and the weather time
// `valid_utc` ("" for none), spacing_s after the path's last keyframe (at 0 for the first), and
// selects it. Makes the path when the scene has none.
void add_keyframe(core::Scene& scene, KeyframeEditor& ed, const core::Camera& cam, const std::string& valid_utc,
                  double spacing_s = 2.0);
// Deletes the selected keyframe (the path goes when its last keyframe does).
void delete_keyframe(core::Scene& scene, KeyframeEditor& ed);
// Moves the selected keyframe one place earlier (delta -1) or later (+1): the two keyframes trade
// their cameras and weather times and keep their path times, so the times still increase.
void move_keyframe(core::Scene& scene, KeyframeEditor& ed, int delta);
// Sets the selected keyframe's path time; refused (message set, nothing changed) unless it lies
// strictly between its neighbours' times.
bool set_keyframe_time(core::Scene& scene, KeyframeEditor& ed, double t_s);

// Why the path cannot be played or recorded yet (core::PathEvaluator's check, or "fewer than two
// keyframes"), or empty.
std::string path_problem(const core::Scene& scene);

// The preview: advances the path time by dt_s (wrapping at the end) and returns the scene at it
// (core::scene_at_path_time: the path's camera at the scene's size and its weather time); nothing
// when the path cannot be played.
std::optional<core::Scene> preview_step(const core::Scene& scene, KeyframeEditor& ed, double dt_s);

// The path on the globe: the camera's track sampled every sample_s of path time as a polyline at
// the camera's altitude, and a short tick from the ground up to each keyframe, on the sphere of
// radius r0_m (Earth-centred, as overlays are). Empty when the path cannot be played.
core::OverlayMesh path_mesh(const core::Scene& scene, double r0_m, double sample_s = 0.05);

// The command that records the path: `cloudviewer record SCENE -o VIDEO --fps 30 --size WxH`.
std::string record_command(const std::string& scene_path, const core::Scene& scene);

}  // namespace cv::viewer
