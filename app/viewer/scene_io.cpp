// Scene files for the viewer. core/scene/scene_json is written on another branch; until it is merged
// this build has no scene-file format, and says so instead of inventing one.
#include "viewer/scene_io.hpp"

#include <stdexcept>

namespace cv::viewer {

bool scene_files_supported() { return false; }

core::Scene load_viewer_scene(const std::string& path) {
  throw std::runtime_error(path + ": scene files need core/scene/scene_json, which this build does not have yet");
}

void save_viewer_scene(const core::Scene&, const std::string& path) {
  throw std::runtime_error(path + ": scene files need core/scene/scene_json, which this build does not have yet");
}

}  // namespace cv::viewer
