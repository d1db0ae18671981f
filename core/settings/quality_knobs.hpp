// QualityKnobs and its table of rows (quality_knobs.def): the knobs a quality preset, a measured
// configuration of the quality front and the frame-time budget set, written once. The presets,
// quality_front.json, `render --budget-ms`, the viewer's frame budget and the bench's rows all hold
// a QualityKnobs and apply it with apply_knobs.
#pragma once

#include <array>
#include <cstddef>
#include <string>

#include "settings/march_settings.hpp"

namespace cv::core {

struct RenderSettings;

// One knob: a SettingRow (key, range, messages, doc) plus where it comes from.
struct KnobRow {
  SettingRow row;
  bool preset = false;  // set by a quality preset
  bool step = false;    // a part of the view step (view_step_dz, view_step_min_m)
};

namespace detail {
// The fields a knob row may give: SettingRow's, plus .march (the march setting it is, whose range
// and documentation it takes) and .preset.
struct KnobFields {
  const char* key = nullptr;
  double lo = 0.0, hi = 0.0;
  const char* unit = "";
  const char* what = nullptr;
  const char* march = nullptr;
  bool preset = false;
  const char* doc = "";
};

// The index of the march setting row with this key, or -1 (an index, not a pointer: GCC cannot
// constant-evaluate pointer tests under -fsanitize=address).
constexpr int march_row_index(const char* key) {
  for (std::size_t i = 0; i < kMarchSettingCount; ++i) {
    if (same_text(kMarchSettingRows[i].key, key)) return static_cast<int>(i);
  }
  return -1;
}

constexpr KnobRow knob_row(const char* member, SettingKind kind, bool step, KnobFields f) {
  KnobRow k;
  if (f.march) {
    const int m = march_row_index(f.march);
    if (m >= 0) k.row = kMarchSettingRows[static_cast<std::size_t>(m)];  // -1: caught by knob_rows_consistent
  }
  k.row.member = member;
  k.row.group = SettingGroup::Quality;
  k.row.kind = kind;
  k.row.key = f.key;
  k.row.flag = nullptr, k.row.label = nullptr, k.row.needs = nullptr;
  if (!f.march) {
    k.row.lo = f.lo, k.row.hi = f.hi, k.row.unit = f.unit, k.row.what = f.what, k.row.doc = f.doc;
    k.row.zero_ok = false, k.row.note = nullptr;
  }
  k.preset = f.preset;
  k.step = step;
  return k;
}
}  // namespace detail

#define CV_KNOB_FIELDS(...) __VA_ARGS__

struct QualityKnobs {
#define CV_QUALITY_KNOB(TYPE, NAME, DEF, TARGET, FIELDS) TYPE NAME{DEF};
#define CV_QUALITY_STEP_KNOB(TYPE, NAME, DEF, FIELDS) TYPE NAME{DEF};
#include "settings/quality_knobs.def"
#undef CV_QUALITY_KNOB
#undef CV_QUALITY_STEP_KNOB

  // The view step in metres on a grid of vertical spacing dz_m.
  double view_step_m(double dz_m) const;
  bool operator==(const QualityKnobs&) const = default;
};

inline constexpr std::size_t kQualityKnobCount = 0
#define CV_QUALITY_KNOB(TYPE, NAME, DEF, TARGET, FIELDS) +1
#define CV_QUALITY_STEP_KNOB(TYPE, NAME, DEF, FIELDS) +1
#include "settings/quality_knobs.def"
#undef CV_QUALITY_KNOB
#undef CV_QUALITY_STEP_KNOB
    ;

inline constexpr std::array<KnobRow, kQualityKnobCount> kQualityKnobRows = {{
#define CV_QUALITY_KNOB(TYPE, NAME, DEF, TARGET, FIELDS) \
  detail::knob_row(#NAME, setting_kind_of<TYPE>(), false, detail::KnobFields{CV_KNOB_FIELDS FIELDS}),
#define CV_QUALITY_STEP_KNOB(TYPE, NAME, DEF, FIELDS) \
  detail::knob_row(#NAME, setting_kind_of<TYPE>(), true, detail::KnobFields{CV_KNOB_FIELDS FIELDS}),
#include "settings/quality_knobs.def"
#undef CV_QUALITY_KNOB
#undef CV_QUALITY_STEP_KNOB
}};

namespace detail {
constexpr bool knob_rows_consistent() {
  for (std::size_t i = 0; i < kQualityKnobCount; ++i) {
    const SettingRow& r = kQualityKnobRows[i].row;
    if (!r.key || !r.doc || !r.doc[0]) return false;  // an unknown .march leaves no doc
    for (std::size_t j = 0; j < i; ++j) {
      if (same_text(r.key, kQualityKnobRows[j].row.key)) return false;
    }
    if ((r.kind == SettingKind::Int || r.kind == SettingKind::Real) && !(r.lo <= r.hi)) return false;
    if (r.kind == SettingKind::Real && !r.what) return false;
  }
  return true;
}
}  // namespace detail
static_assert(detail::knob_rows_consistent(), "quality_knobs.def: a row is inconsistent (an unknown .march?)");

// Calls f(knob row, member) for every knob in order.
template <class Knobs, class F>
void for_each_quality_knob(Knobs& k, F&& f) {
  std::size_t i = 0;
#define CV_QUALITY_KNOB(TYPE, NAME, DEF, TARGET, FIELDS) f(kQualityKnobRows[i++], k.NAME);
#define CV_QUALITY_STEP_KNOB(TYPE, NAME, DEF, FIELDS) f(kQualityKnobRows[i++], k.NAME);
#include "settings/quality_knobs.def"
#undef CV_QUALITY_KNOB
#undef CV_QUALITY_STEP_KNOB
}

// The knob row whose key is `key`, or nullptr.
const KnobRow* find_quality_knob(const std::string& key);

// Writes every knob into `render` (march.view_step_m from the step knobs on a grid of vertical
// spacing dz_m; dz_m <= 0: view_step_m 0, "from the grid" by the preset). presets_only: only the
// rows a preset sets. Does not touch render.quality.
void apply_knobs(const QualityKnobs& k, double dz_m, RenderSettings& render, bool presets_only = false);

// The knobs `render` marches with, given the view step in metres it resolved to on a grid of
// vertical spacing dz_m (view_step_dz = step / dz, no floor).
QualityKnobs knobs_of(const RenderSettings& render, double view_step_m, double dz_m);

// One line: "view step 1 dz (>= 50 m), 16 sun steps, 4 octave(s), 1 frame(s), resolution scale 1,
// adaptive off".
std::string describe_knobs(const QualityKnobs& k);

}  // namespace cv::core
