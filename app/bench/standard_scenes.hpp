// The standard scenes: synthetic cloud fields with a camera and a sun, each built to exercise one
// regime of the renderer (thin ice, a thick deck, broken cumulus, a towering cell with optical depth
// above 100, a low sun, a camera inside a cloud, the whole globe from 400 000 km, the date line, a
// pole, and a sky with no cloud at all). Tests hold the GPU against the CPU reference on each; the
// benchmark renders them against converged references.
#pragma once

#include <string>
#include <vector>

#include "frame/camera.hpp"
#include "frame/sun.hpp"
#include "settings/march_settings.hpp"
#include "volume/cloud_volume.hpp"

namespace cv::core {}

namespace cv::bench {
// The bench works on core's types throughout (it was core::bench before it moved up to app/).
using namespace cv::core;

struct StandardScene {
  std::string name;
  std::string description;
  VolumeGrid grid;
  TimeStepData data;  // ExtinctionLiquid, ExtinctionIce (in-cloud, 1/m) and CloudFraction
  Camera camera;
  Sun sun;
  MarchSettings march;  // a view step that resolves the scene's structure
};

// The names, in a fixed order.
std::vector<std::string> standard_scene_names();

// Builds a scene by name for an image of width x height; an unknown name throws
// std::invalid_argument naming the known ones.
StandardScene standard_scene(const std::string& name, int width, int height);

}  // namespace cv::bench
