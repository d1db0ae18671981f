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
      {"low", 2.0, 100.0, 8, 1, 1},
      {"default", 1.0, 50.0, 16, 4, 1},
      {"high", 0.5, 25.0, 32, 8, 4},
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
  render.march.view_step_m = 0.0;
  render.march.sun_steps = p->sun_steps;
  render.march.octaves = p->octaves;
  render.accumulate = p->accumulate;
}

double resolve_view_step_m(const RenderSettings& render, const VolumeGrid& grid) {
  if (render.march.view_step_m > 0.0) return render.march.view_step_m;
  const QualityPreset* p = find_quality(render.quality);
  if (!p) p = find_quality("default");
  return std::max(p->view_step_min_m, p->view_step_dz_fraction * std::abs(grid.alt_m.step));
}

}  // namespace cv::core
