// Quality presets: one table from a preset name (low, default, high) to the march settings and the
// number of accumulated frames, so the CLI, the viewer and scene files mean the same by "high".
#pragma once

#include <string>
#include <vector>

#include "scene/scene.hpp"
#include "settings/quality_knobs.hpp"
#include "volume/cloud_volume.hpp"

namespace cv::core {

struct QualityPreset {
  const char* name;
  // The knobs a preset sets (quality_knobs.def, rows with .preset): the view step as a fraction
  // of the grid's vertical spacing, never below view_step_min_m (the data hold no structure finer
  // than dz, so a fixed step in metres would over- or under-sample), sun steps, octaves and the
  // jittered frames averaged per image (banding averages away).
  QualityKnobs knobs;
};

// The presets, from fastest to best. "custom" is not among them: it names settings set by hand.
const std::vector<QualityPreset>& quality_presets();

// The preset with this name, or nullptr ("custom" and unknown names).
const QualityPreset* find_quality(const std::string& name);

// "low, default, high, custom": for messages that list what is accepted.
std::string quality_names();

// Sets the march settings and accumulation of `render` from a preset and names it in
// render.quality; the view step becomes 0 (from the grid, see resolve_view_step_m).
// Throws std::invalid_argument for a name that is not a preset.
void apply_quality(const std::string& name, RenderSettings& render);

// The view step in metres: render.march.view_step_m when set (> 0), otherwise the preset's
// fraction of the grid's vertical spacing ("default" for custom settings).
double resolve_view_step_m(const RenderSettings& render, const VolumeGrid& grid);

}  // namespace cv::core
