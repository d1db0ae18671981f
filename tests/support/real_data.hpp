// The real model files in ../shared/data/real: a test skips with a message when they are absent
// (a user's clone) and fails under CI (CI=true), where they must be there.
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <string>

namespace cv::test {

inline std::string real_file(const std::string& name) {
  const std::string p = std::string(CV_REAL_DATA_DIR) + "/" + name;
  if (!std::filesystem::exists(p)) {
    const char* ci = std::getenv("CI");
    if (ci && std::string(ci) == "true") ADD_FAILURE() << p << " is missing under CI";
    return "";
  }
  return p;
}

}  // namespace cv::test

#define REAL_FILE(var, name)                            \
  const std::string var = cv::test::real_file(name);    \
  if (var.empty()) GTEST_SKIP() << name << " not found beside the checkout"
