// The data a scene names, read as the scene subsets it: a .cvvol as it is, NetCDF through the
// importer with the scene's region, levels, stride and dz, so only that part of the file is read.
// For every command that renders a scene (render, view, and those built on them).
#pragma once

#include <cstddef>

#include "scene/scene.hpp"
#include "volume/cloud_volume.hpp"

namespace cv::importers {

// A subset asked of a .cvvol throws core::SceneError (a volume is subset when it is imported);
// import errors throw as import_file does. cache_steps: time steps kept decoded.
core::CloudVolume load_scene_volume(const core::Scene& scene, std::size_t cache_steps);

// The loud note a volume with a diagnosed cloud (data.diagnose_cloud, `--diagnose-cloud`) carries
// in its report: printed on stderr as "COMMAND: DIAGNOSED CLOUD ...", by every command that opens
// such a file, so no picture of an invented cloud goes out without it being said.
void print_diagnosed_cloud_note(const core::CloudVolume& volume, const char* command);

}  // namespace cv::importers
