// Scene files and the data they name, for the viewer and the `render` command alike: loading and
// saving a Scene (core/scene/scene_json) and reading just the part of the data a scene uses.
#pragma once

#include <string>

#include "scene/scene.hpp"
#include "volume/cloud_volume.hpp"

namespace cv::viewer {

// Throw core::SceneError naming the file and the key.
core::Scene load_viewer_scene(const std::string& path);
void save_viewer_scene(const core::Scene& scene, const std::string& path);

// The scene's data: a .cvvol as it is, NetCDF through the importer with the scene's subset (region,
// levels, stride, dz), so only that part of the file is read. A subset asked of a .cvvol throws
// core::SceneError (a volume is subset when it is imported).
core::CloudVolume load_scene_volume(const core::Scene& scene, std::size_t cache_steps);

}  // namespace cv::viewer
