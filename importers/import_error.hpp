// The one error type importers throw: a single line naming the file, the variable or attribute,
// what was found and what was expected.
#pragma once

#include <stdexcept>
#include <string>

#include "io/input_file.hpp"

namespace cv::importers {

class ImportError : public core::InputError {
 public:
  using core::InputError::InputError;
};

}  // namespace cv::importers
