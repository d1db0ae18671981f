// Loading and saving the viewer's Scene as a scene file. The one place the viewer touches scene
// files: at merge time these call core/scene/scene_json (load_scene / save_scene).
#pragma once

#include <string>

#include "scene/scene.hpp"

namespace cv::viewer {

// Whether this build can read and write scene files.
bool scene_files_supported();
// Throws std::runtime_error naming the file and the problem.
core::Scene load_viewer_scene(const std::string& path);
void save_viewer_scene(const core::Scene& scene, const std::string& path);

}  // namespace cv::viewer
