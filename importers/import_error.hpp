// The one error type importers throw: a single line naming the file, the variable or attribute,
// what was found and what was expected.
#pragma once

#include <stdexcept>
#include <string>

namespace cv::importers {

class ImportError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace cv::importers
