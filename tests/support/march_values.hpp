// Test values from the settings table: for every row a value other than a given one, inside the
// row's range, so tests cover every row without naming them.
#pragma once

#include <string>
#include <type_traits>

#include <glm/vec3.hpp>

#include "settings/march_settings.hpp"

namespace cv::test {

// A value of `row` that is not `base`, inside the row's range, and for numbers not a short decimal
// (thirds and sevenths), so a lossy number format would show.
template <class T>
T other_value(const core::SettingRow& row, const T& base) {
  if constexpr (std::is_same_v<T, bool>) {
    return !base;
  } else if constexpr (std::is_same_v<T, int>) {
    return base + 1 <= row.hi ? base + 1 : base - 1;
  } else if constexpr (std::is_same_v<T, double>) {
    const double a = row.lo + (row.hi - row.lo) / 3.0;
    return a != base ? a : row.lo + 2.0 * (row.hi - row.lo) / 3.0;
  } else if constexpr (std::is_same_v<T, glm::dvec3>) {
    const glm::dvec3 v = row.lo + (row.hi - row.lo) * glm::dvec3(1.0 / 7.0, 2.0 / 7.0, 3.0 / 7.0);
    return v != base ? v : glm::dvec3(row.hi) - (v - row.lo);
  } else {
    return base + "elsewhere/ground.png";
  }
}

// Every row of `m` set to other_value of the same row of `base`.
inline void set_every_row_off(core::MarchSettings& m, const core::MarchSettings& base) {
  core::for_each_march_setting_pair(m, base, [](const core::SettingRow& row, auto& v, const auto& b) { v = other_value(row, b); });
}

}  // namespace cv::test
