// The quality knobs applied to render settings and described, from quality_knobs.def.
#include "settings/quality_knobs.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "scene/scene.hpp"

namespace cv::core {

double QualityKnobs::view_step_m(double dz_m) const {
  return std::max(view_step_min_m, view_step_dz * std::abs(dz_m));
}

const KnobRow* find_quality_knob(const std::string& key) {
  for (const KnobRow& r : kQualityKnobRows) {
    if (key == r.row.key) return &r;
  }
  return nullptr;
}

void apply_knobs(const QualityKnobs& k, double dz_m, RenderSettings& render, bool presets_only) {
  std::size_t i = 0;
  auto set = [&](auto& target, const auto& value) {
    const KnobRow& row = kQualityKnobRows[i++];
    if (!presets_only || row.preset) target = value;
  };
  auto step = [&] { ++i; };
#define CV_QUALITY_KNOB(TYPE, NAME, DEF, TARGET, FIELDS) set(render.TARGET, k.NAME);
#define CV_QUALITY_STEP_KNOB(TYPE, NAME, DEF, FIELDS) step();
#include "settings/quality_knobs.def"
#undef CV_QUALITY_KNOB
#undef CV_QUALITY_STEP_KNOB
  render.march.quality.view_step_m = dz_m > 0.0 ? k.view_step_m(dz_m) : 0.0;
}

QualityKnobs knobs_of(const RenderSettings& render, double view_step_m, double dz_m) {
  QualityKnobs k;
#define CV_QUALITY_KNOB(TYPE, NAME, DEF, TARGET, FIELDS) k.NAME = render.TARGET;
#define CV_QUALITY_STEP_KNOB(TYPE, NAME, DEF, FIELDS)
#include "settings/quality_knobs.def"
#undef CV_QUALITY_KNOB
#undef CV_QUALITY_STEP_KNOB
  k.view_step_min_m = 0.0;
  k.view_step_dz = dz_m > 0.0 ? view_step_m / std::abs(dz_m) : 1.0;
  return k;
}

std::string describe_knobs(const QualityKnobs& k) {
  char b[256];
  char floor_text[48] = "";
  if (k.view_step_min_m > 0.0) std::snprintf(floor_text, sizeof floor_text, " (>= %g m)", k.view_step_min_m);
  std::snprintf(
      b, sizeof b,
      "view step %.3g dz%s, %d sun steps, %d octave(s), %d frame(s), resolution scale %g, adaptive %s",
      k.view_step_dz, floor_text, k.sun_steps, k.octaves, k.accumulate, k.resolution_scale,
      k.adaptive ? "on" : "off");
  return b;
}

}  // namespace cv::core
