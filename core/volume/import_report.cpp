// The import report: collection, text and JSON.
#include "volume/import_report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace cv::core {

void ValueStats::add(double v) {
  if (!std::isfinite(v)) {
    ++missing;
    return;
  }
  min = std::min(min, v);
  max = std::max(max, v);
  ++count;
}

namespace {
template <typename T>
void add_range(ValueStats& s, const T* v, std::size_t n) {
  // Branch-free so the compiler vectorises it (a global step is 10^8 values): a value that is not
  // finite (|x| <= max is false for NaN and infinity) leaves lo and hi alone and is not counted.
  const T inf = std::numeric_limits<T>::infinity(), big = std::numeric_limits<T>::max();
  T lo = inf, hi = -inf;
  std::size_t finite = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const T x = v[i];
    const bool ok = std::abs(x) <= big;
    lo = std::min(lo, ok ? x : inf);
    hi = std::max(hi, ok ? x : -inf);
    finite += ok ? 1 : 0;
  }
  if (finite) {
    s.min = std::min(s.min, static_cast<double>(lo));
    s.max = std::max(s.max, static_cast<double>(hi));
  }
  s.count += finite;
  s.missing += n - finite;
}
}  // namespace

void ValueStats::add_all(const float* v, std::size_t n) { add_range(*this, v, n); }
void ValueStats::add_all(const double* v, std::size_t n) { add_range(*this, v, n); }

void ValueStats::merge(const ValueStats& o) {
  min = std::min(min, o.min);
  max = std::max(max, o.max);
  count += o.count;
  missing += o.missing;
}

VariableUse& ImportReport::use(const std::string& role) {
  for (auto& v : variables) {
    if (v.role == role) return v;
  }
  variables.push_back({});
  variables.back().role = role;
  return variables.back();
}

void ImportReport::warn(const std::string& message) {
  if (std::find(warnings.begin(), warnings.end(), message) == warnings.end()) warnings.push_back(message);
}

std::string json_quote(const std::string& s) {
  std::string out = "\"";
  for (unsigned char c : s) {
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\t': out += "\\t"; break;
      default:
        if (c < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04x", c);
          out += buf;
        } else {
          out += static_cast<char>(c);
        }
    }
  }
  return out + "\"";
}

namespace {
std::string num(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

std::string stats_json(const ValueStats& s) {
  return "{\"min\": " + num(s.empty() ? NAN : s.min) + ", \"max\": " + num(s.empty() ? NAN : s.max) +
         ", \"count\": " + std::to_string(s.count) + ", \"missing\": " + std::to_string(s.missing) + "}";
}

std::string range_text(const ValueStats& s) {
  if (s.empty()) return "no values";
  char buf[96];
  std::snprintf(buf, sizeof buf, "%.4g .. %.4g", s.min, s.max);
  return buf;
}
}  // namespace

std::string ImportReport::to_json() const {
  std::string j = "{\n  \"file\": " + json_quote(file) + ",\n  \"format\": " + json_quote(format) + ",\n";
  j += "  \"variables\": [\n";
  for (size_t i = 0; i < variables.size(); ++i) {
    const auto& v = variables[i];
    j += "    {\"role\": " + json_quote(v.role) + ", \"variable\": " + json_quote(v.variable) +
         ", \"units\": " + json_quote(v.units) + ", \"conversion\": " + json_quote(v.conversion) +
         ", \"before\": " + stats_json(v.before) + ", \"after\": " + stats_json(v.after) + ", \"after_units\": " + json_quote(v.after_units) +
         ", \"clamped\": " + std::to_string(v.clamped) + "}" + (i + 1 < variables.size() ? ",\n" : "\n");
  }
  j += "  ],\n  \"warnings\": [";
  for (size_t i = 0; i < warnings.size(); ++i) j += (i ? ", " : "") + json_quote(warnings[i]);
  j += "],\n  \"notes\": [";
  for (size_t i = 0; i < notes.size(); ++i) j += (i ? ", " : "") + json_quote(notes[i]);
  j += "]\n}\n";
  return j;
}

std::string ImportReport::to_text() const {
  std::string t = "import report for " + file + " (" + format + ")\n";
  for (const auto& v : variables) {
    t += "  " + v.role + " <- " + v.variable + " [" + (v.units.empty() ? "no units" : v.units) + "]: " +
         v.conversion + "\n      read " + range_text(v.before) + (v.units.empty() || v.before.empty() ? std::string() : " " + v.units) + " (" +
         std::to_string(v.before.missing) + " missing)" + (v.after.empty() && v.after.missing == 0 ? std::string() : ", stored " + range_text(v.after) + (v.after_units.empty() ? std::string() : " " + v.after_units)) + (v.clamped ? ", " + std::to_string(v.clamped) + " clamped" : "") +
         "\n";
  }
  for (const auto& n : notes) t += "  note: " + n + "\n";
  for (const auto& w : warnings) t += "  WARNING: " + w + "\n";
  return t;
}

}  // namespace cv::core
