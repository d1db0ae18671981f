// The overlay parameter table and the typed overlay entries.
#include "settings/overlay_settings.hpp"

#include <cmath>
#include <cstdlib>
#include <sstream>
#include <stdexcept>

namespace cv::core {
namespace {

std::string number_text(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

// "r,g,b" (or r/g/b) into three numbers; false when it is not three finite numbers.
bool parse_rgb(const std::string& text, glm::dvec3& out) {
  std::string t = text;
  for (char& c : t) c = (c == ',' || c == '/') ? ' ' : c;
  std::istringstream in(t);
  double v[3];
  for (double& x : v) {
    if (!(in >> x) || !std::isfinite(x)) return false;
  }
  std::string rest;
  if (in >> rest) return false;
  out = {v[0], v[1], v[2]};
  return true;
}

bool parse_number(const std::string& text, double& out) {
  if (text.empty()) return false;
  char* end = nullptr;
  out = std::strtod(text.c_str(), &end);
  return end && *end == '\0' && std::isfinite(out);
}

}  // namespace

const std::vector<OverlayParamRow>& overlay_param_rows() {
  static const std::vector<OverlayParamRow> rows = {
#define CV_OVERLAY_PARAM(OVERLAY, KEY, KIND, NUMBER, TEXT, LO, HI, UNIT, DOC) \
  {#OVERLAY, #KEY, OverlayParamKind::KIND, NUMBER, TEXT, LO, HI, UNIT, DOC},
#include "settings/overlay_settings.def"
#undef CV_OVERLAY_PARAM
  };
  return rows;
}

const std::vector<std::string>& overlay_types() {
  static const std::vector<std::string> types = [] {
    std::vector<std::string> t;
    for (const OverlayParamRow& r : overlay_param_rows()) {
      if (t.empty() || t.back() != r.overlay) t.push_back(r.overlay);
    }
    return t;
  }();
  return types;
}

bool is_overlay_type(const std::string& type) {
  for (const std::string& t : overlay_types()) {
    if (t == type) return true;
  }
  return false;
}

const OverlayParamRow* overlay_param(const std::string& type, const std::string& key) {
  for (const OverlayParamRow& r : overlay_param_rows()) {
    if (type == r.overlay && key == r.key) return &r;
  }
  return nullptr;
}

double OverlaySpec::number(const std::string& key) const {
  const auto it = numbers.find(key);
  if (it == numbers.end()) throw std::logic_error("overlay " + type + " has no number " + key);
  return it->second;
}
const std::string& OverlaySpec::text(const std::string& key) const {
  const auto it = texts.find(key);
  if (it == texts.end()) throw std::logic_error("overlay " + type + " has no text " + key);
  return it->second;
}
glm::dvec3 OverlaySpec::color(const std::string& key) const {
  const auto it = colors.find(key);
  if (it == colors.end()) throw std::logic_error("overlay " + type + " has no colour " + key);
  return it->second;
}

OverlaySpec default_overlay(const std::string& type) {
  if (!is_overlay_type(type)) throw std::invalid_argument("found \"" + type + "\", expected " + overlay_types_expected());
  OverlaySpec s;
  s.type = type;
  for (const OverlayParamRow& r : overlay_param_rows()) {
    if (type != r.overlay) continue;
    if (r.kind == OverlayParamKind::Number) s.numbers[r.key] = r.number;
    if (r.kind == OverlayParamKind::Text) s.texts[r.key] = r.text;
    if (r.kind == OverlayParamKind::Rgb) parse_rgb(r.text, s.colors[r.key]);
  }
  return s;
}

std::string overlay_types_expected() {
  std::string list;
  for (const std::string& t : overlay_types()) list += (list.empty() ? "" : ", ") + t;
  return "one of " + list;
}

std::string overlay_param_expected(const OverlayParamRow& r) {
  const std::string unit = *r.unit ? std::string(" (") + r.unit + ")" : "";
  switch (r.kind) {
    case OverlayParamKind::Number: return "a number " + number_text(r.lo) + ".." + number_text(r.hi) + unit;
    case OverlayParamKind::Rgb: return "[r, g, b], each " + number_text(r.lo) + ".." + number_text(r.hi);
    case OverlayParamKind::Text: break;
  }
  return "a name (" + std::string(r.doc) + ")";
}

void set_overlay_param(OverlaySpec& spec, const std::string& key, const std::string& value) {
  const OverlayParamRow* row = overlay_param(spec.type, key);
  if (!row) {
    std::string keys;
    for (const OverlayParamRow& r : overlay_param_rows()) {
      if (spec.type == r.overlay) keys += std::string(keys.empty() ? "" : ", ") + r.key;
    }
    throw std::invalid_argument("found the key \"" + key + "\", expected one of " + keys + " for " + spec.type);
  }
  const std::string found = "found \"" + value + "\" for " + key + ", expected ";
  if (row->kind == OverlayParamKind::Number) {
    double v = 0.0;
    if (!parse_number(value, v) || v < row->lo || v > row->hi) throw std::invalid_argument(found + overlay_param_expected(*row));
    spec.numbers[key] = v;
  } else if (row->kind == OverlayParamKind::Rgb) {
    glm::dvec3 c;
    if (!parse_rgb(value, c)) throw std::invalid_argument(found + overlay_param_expected(*row));
    for (int i = 0; i < 3; ++i) {
      if (c[i] < row->lo || c[i] > row->hi) throw std::invalid_argument(found + overlay_param_expected(*row));
    }
    spec.colors[key] = c;
  } else {
    if (value.empty()) throw std::invalid_argument(found + overlay_param_expected(*row));
    spec.texts[key] = value;
  }
}

OverlaySpec parse_overlay_flag(const std::string& arg) {
  const std::string where = "--overlay " + arg + ": ";
  const std::size_t colon = arg.find(':');
  const std::string name = arg.substr(0, colon);
  OverlaySpec spec;
  try {
    spec = default_overlay(name);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(where + e.what());
  }
  if (colon == std::string::npos) return spec;
  // key=value pairs split at commas; a colour's own commas stay with it (r,g,b: a part without '='
  // continues the previous value), so color=1,0,0 reads as one value.
  std::vector<std::pair<std::string, std::string>> pairs;
  std::string rest = arg.substr(colon + 1);
  std::size_t start = 0;
  while (start <= rest.size()) {
    const std::size_t comma = rest.find(',', start);
    const std::string part = rest.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    const std::size_t eq = part.find('=');
    if (eq != std::string::npos) {
      pairs.emplace_back(part.substr(0, eq), part.substr(eq + 1));
    } else if (!pairs.empty()) {
      pairs.back().second += "," + part;
    } else {
      throw std::invalid_argument(where + "found \"" + part + "\", expected key=value");
    }
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  for (const auto& [key, value] : pairs) {
    try {
      set_overlay_param(spec, key, value);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(where + e.what());
    }
  }
  return spec;
}

}  // namespace cv::core
