// A folder of this test process's own for the files a test writes (ending in '/', as
// ::testing::TempDir() does): the system's temporary folder / cv_test_<pid>, made on first use and
// removed with everything in it when the process ends, so runs never meet each other's files and
// leave nothing behind.
#pragma once

#include <filesystem>
#include <string>
#include <system_error>

#include <unistd.h>

namespace cv::test_support {

inline const std::string& scratch_dir() {
  struct Dir {
    std::filesystem::path path;
    Dir() : path(std::filesystem::temp_directory_path() / ("cv_test_" + std::to_string(::getpid()))) {
      std::filesystem::create_directories(path);
    }
    ~Dir() {
      std::error_code ec;
      std::filesystem::remove_all(path, ec);
    }
  };
  static const Dir dir;
  static const std::string text = dir.path.string() + "/";
  return text;
}

}  // namespace cv::test_support
