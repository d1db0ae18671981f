// MarchSettings and its table of rows (march_settings.def): one row per setting, from which the
// struct, scene files' render.march, `render`'s flags, the viewer's widgets, "does this change the
// image" and the check of docs/scene.md are all produced, so a new setting is written once.
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <type_traits>

#include <glm/vec3.hpp>

namespace cv::core {

enum class SettingGroup {
  Medium,    // the medium and lighting model
  Quality,   // march quality: steps, cut-offs, jitter
  Features,  // program features: what the march compiles in or leaves out
  PerFrame,  // per-frame state, not part of "the image"
};

enum class SettingKind {
  Bool,    // true/false
  Int,     // an integer lo..hi
  Real,    // a number lo..hi (or 0 where zero_ok)
  Choice,  // a bool written as one of two names (choices[false], choices[true])
  Rgb01,   // three numbers, each lo..hi
  Text,    // a string
};

// One setting's description. The macro fills member, group and kind; each row in the .def gives
// the rest by designated initializers, in this order (the compiler checks the order).
struct SettingRow {
  const char* member = nullptr;  // the C++ member of MarchSettings
  SettingGroup group = SettingGroup::Quality;
  SettingKind kind = SettingKind::Bool;
  const char* key = nullptr;  // the scene file's key under render.march
  // Accepted values (numbers; each component of Rgb01). zero_ok: 0 is accepted too, below lo,
  // with the meaning `note` gives.
  double lo = 0.0, hi = 0.0;
  bool zero_ok = false;
  const char* unit = "";           // of the number, for the usage text and the reader
  const char* what = nullptr;      // noun phrase of messages: "a view step in metres"
  const char* note = nullptr;      // appended to the range in messages: "0: from the grid"
  bool image = true;               // a change changes the image (the viewer restarts accumulating)
  const char* flag = nullptr;      // `render`'s option; for a Bool, a flag without a value that sets !default;
                                   // for a Choice, one that takes one of the choices' names
  const char* metavar = nullptr;   // its value in the usage text
  const char* label = nullptr;     // the viewer's widget; nullptr: no widget
  double wlo = 0.0, whi = 0.0;     // the widget's range, where all of lo..hi is unusable as a slider
  bool wlog = false;               // a logarithmic slider
  const char* needs = nullptr;     // the widget shows only while this row's setting is on / non-zero
  std::array<const char*, 2> choices{};        // Choice: names in files for false, true
  std::array<const char*, 2> choice_labels{};  // Choice: what the widget shows for false, true
  const char* doc = "";                        // one line of documentation
};

template <class T>
constexpr SettingKind setting_kind_of() {
  if constexpr (std::is_same_v<T, bool>) return SettingKind::Bool;
  else if constexpr (std::is_same_v<T, int>) return SettingKind::Int;
  else if constexpr (std::is_same_v<T, double>) return SettingKind::Real;
  else if constexpr (std::is_same_v<T, glm::dvec3>) return SettingKind::Rgb01;
  else if constexpr (std::is_same_v<T, std::string>) return SettingKind::Text;
  else static_assert(!sizeof(T), "a march setting is bool, int, double, glm::dvec3 or std::string");
}

#define CV_SETTING_FIELDS(...) __VA_ARGS__

// The settings of a march, CPU and GPU alike, split by concern: one struct per group of the table
// (members, types and defaults: march_settings.def), gathered in MarchSettings. A setting is
// reached through its group: `m.quality.sun_steps`, `m.medium.ice_g`, `m.features.globe`.
#define CV_SETTING_GROUP_Medium medium
#define CV_SETTING_GROUP_Quality quality
#define CV_SETTING_GROUP_Features features
#define CV_SETTING_GROUP_PerFrame per_frame
#define CV_SETTING_GROUP(GROUP) CV_SETTING_GROUP_##GROUP
#define CV_SETTING_KEEP_Medium_Medium(X) X
#define CV_SETTING_KEEP_Medium_Quality(X)
#define CV_SETTING_KEEP_Medium_Features(X)
#define CV_SETTING_KEEP_Medium_PerFrame(X)
#define CV_SETTING_KEEP_Quality_Medium(X)
#define CV_SETTING_KEEP_Quality_Quality(X) X
#define CV_SETTING_KEEP_Quality_Features(X)
#define CV_SETTING_KEEP_Quality_PerFrame(X)
#define CV_SETTING_KEEP_Features_Medium(X)
#define CV_SETTING_KEEP_Features_Quality(X)
#define CV_SETTING_KEEP_Features_Features(X) X
#define CV_SETTING_KEEP_Features_PerFrame(X)
#define CV_SETTING_KEEP_PerFrame_Medium(X)
#define CV_SETTING_KEEP_PerFrame_Quality(X)
#define CV_SETTING_KEEP_PerFrame_Features(X)
#define CV_SETTING_KEEP_PerFrame_PerFrame(X) X
// X when the row's GROUP is WANT, nothing otherwise.
#define CV_SETTING_KEEP(WANT, GROUP, X) CV_SETTING_KEEP_##WANT##_##GROUP(X)

// The medium and the lighting model: what is in the air and how light crosses it.
struct MediumSettings {
#define CV_MARCH_SETTING(TYPE, NAME, DEF, GROUP, FIELDS) CV_SETTING_KEEP(Medium, GROUP, TYPE NAME{DEF};)
#include "settings/march_settings.def"
#undef CV_MARCH_SETTING
};

// March quality: steps, cut-offs, jitter (cost against error).
struct QualitySettings {
#define CV_MARCH_SETTING(TYPE, NAME, DEF, GROUP, FIELDS) CV_SETTING_KEEP(Quality, GROUP, TYPE NAME{DEF};)
#include "settings/march_settings.def"
#undef CV_MARCH_SETTING
};

// Program features: what the march compiles in or leaves out.
struct FeatureSettings {
#define CV_MARCH_SETTING(TYPE, NAME, DEF, GROUP, FIELDS) CV_SETTING_KEEP(Features, GROUP, TYPE NAME{DEF};)
#include "settings/march_settings.def"
#undef CV_MARCH_SETTING
};

// Per-frame state, not part of "the image".
struct FrameState {
#define CV_MARCH_SETTING(TYPE, NAME, DEF, GROUP, FIELDS) CV_SETTING_KEEP(PerFrame, GROUP, TYPE NAME{DEF};)
#include "settings/march_settings.def"
#undef CV_MARCH_SETTING
};

struct MarchSettings {
  MediumSettings medium;
  QualitySettings quality;
  FeatureSettings features;
  FrameState per_frame;
};

inline constexpr std::size_t kMarchSettingCount = 0
#define CV_MARCH_SETTING(TYPE, NAME, DEF, GROUP, FIELDS) +1
#include "settings/march_settings.def"
#undef CV_MARCH_SETTING
    ;

namespace detail {
// A bool row with choices is a Choice; otherwise the kind follows the member's type.
constexpr SettingRow finish_row(SettingRow r) {
  if (r.kind == SettingKind::Bool && r.choices[0]) r.kind = SettingKind::Choice;
  return r;
}
}  // namespace detail

// The rows, in the .def's order (the order of render.march keys in scene files).
inline constexpr std::array<SettingRow, kMarchSettingCount> kMarchSettingRows = {{
#define CV_MARCH_SETTING(TYPE, NAME, DEF, GROUP, FIELDS) \
  detail::finish_row(SettingRow{.member = #NAME, .group = SettingGroup::GROUP, .kind = setting_kind_of<TYPE>(), \
                                 CV_SETTING_FIELDS FIELDS}),
#include "settings/march_settings.def"
#undef CV_MARCH_SETTING
}};

namespace detail {
constexpr bool same_text(const char* a, const char* b) {
  while (*a && *a == *b) ++a, ++b;
  return *a == *b;
}
// The table's own consistency, checked when it compiles: keys unique, ranges ordered, every
// `needs` naming a row, and a flag and widget only where their consumers can use them.
constexpr bool march_setting_rows_consistent() {
  for (std::size_t i = 0; i < kMarchSettingCount; ++i) {
    const SettingRow& r = kMarchSettingRows[i];
    if (!r.key || !r.doc[0]) return false;
    for (std::size_t j = 0; j < i; ++j) {
      if (same_text(r.key, kMarchSettingRows[j].key)) return false;
    }
    const bool numeric = r.kind == SettingKind::Int || r.kind == SettingKind::Real || r.kind == SettingKind::Rgb01;
    if (numeric && !(r.lo <= r.hi)) return false;
    if ((r.kind == SettingKind::Real || r.kind == SettingKind::Rgb01) && !r.what) return false;
    if (r.label && numeric && r.kind != SettingKind::Rgb01 && !(r.wlo < r.whi)) return false;
    if (r.flag && (r.kind == SettingKind::Text || r.kind == SettingKind::Rgb01)) return false;
    if (r.flag && r.kind != SettingKind::Bool && !r.metavar) return false;
    if (r.needs) {
      bool found = false;
      for (const SettingRow& n : kMarchSettingRows) found = found || same_text(n.key, r.needs);
      if (!found) return false;
    }
  }
  return true;
}
}  // namespace detail
static_assert(detail::march_setting_rows_consistent(), "march_settings.def: a row is inconsistent (see the checks above)");

// Calls f(row, member) for every row in order, member a (const) reference of its own type.
template <class Settings, class F>
void for_each_march_setting(Settings& m, F&& f) {
  std::size_t i = 0;
#define CV_MARCH_SETTING(TYPE, NAME, DEF, GROUP, FIELDS) f(kMarchSettingRows[i++], m.CV_SETTING_GROUP(GROUP).NAME);
#include "settings/march_settings.def"
#undef CV_MARCH_SETTING
}

// Calls f(row, a.member, b.member) for every row in order.
template <class A, class B, class F>
void for_each_march_setting_pair(A& a, B& b, F&& f) {
  std::size_t i = 0;
#define CV_MARCH_SETTING(TYPE, NAME, DEF, GROUP, FIELDS) \
  f(kMarchSettingRows[i++], a.CV_SETTING_GROUP(GROUP).NAME, b.CV_SETTING_GROUP(GROUP).NAME);
#include "settings/march_settings.def"
#undef CV_MARCH_SETTING
}

// The row whose scene-file key is `key`, or nullptr.
const SettingRow* find_march_setting(const std::string& key);

// Whether a height band masks the medium: layer_bottom_m or layer_top_m moved from their defaults
// (the whole column). The march's band test is compiled in only then (kernel::MarchVariant).
inline bool layer_band_set(const MarchSettings& s) { return s.medium.layer_bottom_m > -100000.0 || s.medium.layer_top_m < 1e7; }

// Whether a false colour is set: tint_liquid or tint_ice is not white. The march's tint is compiled
// in only then (kernel::MarchVariant).
inline bool tint_set(const MarchSettings& s) {
  return s.medium.tint_liquid != glm::dvec3(1.0) || s.medium.tint_ice != glm::dvec3(1.0);
}

// Whether the two march the same image: every row but those marked image = false (`frame`).
bool same_image(const MarchSettings& a, const MarchSettings& b);

// Whether a number is in a row's range (lo..hi, or 0 where zero_ok); integers must be whole.
bool in_range(const SettingRow& row, double v);

// The range as messages and docs/scene.md write it: "1..1024", "0 or 0.01..50", "0..1e7".
std::string range_text(const SettingRow& row);

// What a value of this row must be, for messages: "an integer 1..1024", "a sun step length in
// metres 0..1e7 (0: the grid's horizontal cell)", "true or false", "\"mie\" or \"hg\"".
std::string expected_text(const SettingRow& row);

// A number as the messages write it: 1e7, not 1e+07; 0.001; 1024.
std::string short_number(double v);

}  // namespace cv::core
