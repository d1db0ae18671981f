// The table's shared wording and checks: ranges, messages and image equality, the same for scene
// files, `render`'s flags and the viewer.
#include "settings/march_settings.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace cv::core {

const SettingRow* find_march_setting(const std::string& key) {
  for (const SettingRow& r : kMarchSettingRows) {
    if (key == r.key) return &r;
  }
  return nullptr;
}

bool same_image(const MarchSettings& a, const MarchSettings& b) {
  bool same = true;
  for_each_march_setting_pair(a, b, [&](const SettingRow& row, const auto& x, const auto& y) {
    if (row.image && !(x == y)) same = false;
  });
  return same;
}

bool in_range(const SettingRow& row, double v) {
  if (!std::isfinite(v)) return false;
  if (row.kind == SettingKind::Int && v != std::floor(v)) return false;
  return (v >= row.lo && v <= row.hi) || (row.zero_ok && v == 0.0);
}

std::string short_number(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%g", v);
  if (std::strtod(buf, nullptr) != v) {  // %g rounded it: whole numbers in full, others exactly
    if (v == std::floor(v) && std::abs(v) < 9e15) std::snprintf(buf, sizeof buf, "%lld", static_cast<long long>(v));
    else std::snprintf(buf, sizeof buf, "%.17g", v);
  }
  // "1e+07" -> "1e7", "1e-06" -> "1e-6": as people write them (and docs/scene.md does).
  std::string s = buf;
  const auto e = s.find('e');
  if (e == std::string::npos) return s;
  std::string exp = s.substr(e + 1);
  const bool neg = exp[0] == '-';
  if (exp[0] == '+' || exp[0] == '-') exp.erase(0, 1);
  while (exp.size() > 1 && exp[0] == '0') exp.erase(0, 1);
  return s.substr(0, e) + "e" + (neg ? "-" : "") + exp;
}

std::string range_text(const SettingRow& row) {
  const std::string span = short_number(row.lo) + ".." + short_number(row.hi);
  return row.zero_ok && row.lo > 0.0 ? "0 or " + span : span;
}

std::string expected_text(const SettingRow& row) {
  const std::string note = row.note ? std::string(" (") + row.note + ")" : "";
  switch (row.kind) {
    case SettingKind::Bool: return "true or false";
    case SettingKind::Choice: return std::string("\"") + row.choices[0] + "\" or \"" + row.choices[1] + "\"";
    case SettingKind::Text: return "a string";
    case SettingKind::Int: return "an integer " + range_text(row) + note;
    case SettingKind::Rgb01: return std::string(row.what) + " " + range_text(row) + " [r, g, b]";
    case SettingKind::Real: break;
  }
  return std::string(row.what ? row.what : "a number") + " " + range_text(row) + note;
}

}  // namespace cv::core
