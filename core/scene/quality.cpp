// The quality preset table and its application to render settings.
#include "scene/quality.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace cv::core {

const std::vector<QualityPreset>& quality_presets() {
  // "default" is what `render` used before presets existed (sun steps 16, octaves 4, step
  // max(50 m, dz)). low and high halve and double it as in docs/BENCHMARKS.md's renderer table
  // (there 1000/500/250 m on the sample, whose dz is 500 m); high also averages 4 jittered frames.
  static const std::vector<QualityPreset> table = {
      {"low", {.view_step_dz = 2.0, .view_step_min_m = 100.0, .sun_steps = 8, .octaves = 1, .accumulate = 1}},
      {"default", {.view_step_dz = 1.0, .view_step_min_m = 50.0, .sun_steps = 16, .octaves = 4, .accumulate = 1}},
      {"high", {.view_step_dz = 0.5, .view_step_min_m = 25.0, .sun_steps = 32, .octaves = 8, .accumulate = 4}},
  };
  return table;
}

const QualityPreset* find_quality(const std::string& name) {
  for (const auto& p : quality_presets()) {
    if (name == p.name) return &p;
  }
  return nullptr;
}

std::string quality_names() {
  std::string out;
  for (const auto& p : quality_presets()) out += std::string(p.name) + ", ";
  return out + "custom";
}

void apply_quality(const std::string& name, RenderSettings& render) {
  const QualityPreset* p = find_quality(name);
  if (!p) throw std::invalid_argument("unknown quality preset '" + name + "', expected one of " + quality_names());
  render.quality = p->name;
  apply_knobs(p->knobs, 0.0, render, /*presets_only=*/true);  // view step 0: from the grid
}

double resolve_view_step_m(const RenderSettings& render, const VolumeGrid& grid) {
  if (render.march.quality.view_step_m > 0.0) return render.march.quality.view_step_m;
  const QualityPreset* p = find_quality(render.quality);
  if (!p) p = find_quality("default");
  return p->knobs.view_step_m(grid.alt_m.step);
}

}  // namespace cv::core
