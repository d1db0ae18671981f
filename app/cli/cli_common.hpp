// What the `cloudviewer` subcommands share: the bad-input exception, exit codes and the parsers of
// numbers and lists in arguments.
#pragma once

#include <chrono>
#include <cstddef>
#include <optional>
#include <utility>
#include <string>
#include <vector>

namespace cv::cli {

constexpr int kExitBadInput = 2;

// Wall-clock seconds since t0 (steady clock), for the commands' timing lines.
inline double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Bad command-line input: one line naming the argument, what was found and what was expected.
struct UsageError {
  std::string message;
};

// A finite number, or UsageError naming the option.
double parse_number(const std::string& option, const std::string& text);

// min_n..max_n finite numbers separated by `sep`, or UsageError naming the option and `expected`.
std::vector<double> parse_list(const std::string& option, const std::string& text, char sep, std::size_t min_n,
                               std::size_t max_n, const char* expected);

// "WxH" with both whole numbers in lo..hi (digits only: "4294967328x18" is refused, not wrapped).
std::optional<std::pair<int, int>> parse_size(const std::string& text, int lo, int hi);

}  // namespace cv::cli
