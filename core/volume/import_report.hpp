// The import report: every variable used with units and conversions, value ranges before and after,
// missing values, clamps, and consistency warnings. Printed as text and saved as JSON.
#pragma once

#include <cstddef>
#include <limits>
#include <string>
#include <vector>

namespace cv::core {

// Running range and counts of one variable's values.
struct ValueStats {
  double min = std::numeric_limits<double>::infinity();
  double max = -std::numeric_limits<double>::infinity();
  std::size_t count = 0;    // finite values seen
  std::size_t missing = 0;  // fill, missing_value or NaN
  void add(double v);
  // The same over an array, in one pass (per-value calls cost a tenth of a global import).
  void add_all(const float* v, std::size_t n);
  void add_all(const double* v, std::size_t n);
  void merge(const ValueStats& o);
  bool empty() const { return count == 0; }
};

struct VariableUse {
  std::string role;        // what it became, e.g. "liquid extinction"
  std::string variable;    // name in the file
  std::string units;       // units in the file
  std::string conversion;  // what was done, in words and formula
  ValueStats before;       // as read (unpacked), per time step loaded
  ValueStats after;        // in the volume, SI
  std::string after_units; // units of `after` (what the volume stores), e.g. "1/m" for extinction
  std::size_t clamped = 0; // values clamped into their physical range
};

struct ImportReport {
  std::string file;
  std::string format;  // "CF pressure levels (ERA5 naming)", "WRF", ...
  std::vector<VariableUse> variables;
  std::vector<std::string> warnings;
  std::vector<std::string> notes;

  VariableUse& use(const std::string& role);  // finds or adds
  void warn(const std::string& message);      // adds once
  std::string to_text() const;
  std::string to_json() const;
};

// JSON string literal with escapes.
std::string json_quote(const std::string& s);

}  // namespace cv::core
