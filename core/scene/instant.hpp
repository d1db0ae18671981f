// A scene's instant against its file's time axis: which two steps it falls between and where, with
// the errors a user can make (a time outside the file, a time axis that does not ascend) named.
#pragma once

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "volume/cloud_volume.hpp"

namespace cv::core {

// Bad time input: the message is one line that names the file, what was found and what was expected.
struct TimeError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct Instant {
  std::size_t step0 = 0, step1 = 0;  // the steps before and after (equal at a step, or in a one-step file)
  double fraction = 0.0;             // 0 at step0, 1 at step1
  std::int64_t unix_s = 0;           // the instant (when the file's times are known)
  std::string iso_utc;               // the instant as YYYY-MM-DDThh:mm:ssZ, or the step's own label
  bool time_known = false;           // the file has UTC valid times
  double gap_s = 0.0;                // seconds from step0 to step1 (0 at a step)
  bool between() const { return step1 != step0 && fraction > 0.0; }
};

// Whether the file's valid times are UTC date-times (not bare step labels).
bool times_known(const std::vector<ValidTime>& times);
// Throws TimeError naming `source` and the two values unless the valid times strictly ascend.
void check_time_axis(const std::vector<ValidTime>& times, const std::string& source);
// "2024-01-15T00:00:00Z .. 2024-01-15T15:00:00Z (6 steps)".
std::string time_range_text(const std::vector<ValidTime>& times);
std::string format_iso_utc(std::int64_t unix_s);

// The instant of time step `step` (TimeError when the file has no such step).
Instant instant_at_step(const std::vector<ValidTime>& times, std::size_t step, const std::string& source);
// The instant `iso` (YYYY-MM-DDThh:mm:ssZ) in the file: TimeError when it is no such date-time, the
// file has no valid times, its axis does not ascend, or the instant lies outside the file's range.
Instant instant_at_time(const std::vector<ValidTime>& times, const std::string& iso, const std::string& source);

}  // namespace cv::core
