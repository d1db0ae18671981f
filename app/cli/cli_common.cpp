// Argument parsers shared by the subcommands.
#include "cli_common.hpp"

#include <cmath>
#include <exception>

namespace cv::cli {

double parse_number(const std::string& option, const std::string& text) {
  try {
    size_t used = 0;
    const double v = std::stod(text, &used);
    if (used == text.size() && std::isfinite(v)) return v;
  } catch (const std::exception&) {
  }
  throw UsageError{"cloudviewer: " + option + ": found '" + text + "', expected a finite number"};
}

std::vector<double> parse_list(const std::string& option, const std::string& text, char sep, std::size_t min_n,
                               std::size_t max_n, const char* expected) {
  std::vector<double> out;
  std::size_t pos = 0;
  while (pos <= text.size()) {
    const std::size_t end = text.find(sep, pos);
    const std::string item = text.substr(pos, end == std::string::npos ? std::string::npos : end - pos);
    try {
      out.push_back(parse_number(option, item));
    } catch (const UsageError&) {
      throw UsageError{"cloudviewer: " + option + ": found '" + text + "', expected " + expected};
    }
    if (end == std::string::npos) break;
    pos = end + 1;
  }
  if (out.size() < min_n || out.size() > max_n) {
    throw UsageError{"cloudviewer: " + option + ": found '" + text + "', expected " + expected};
  }
  return out;
}

std::optional<std::pair<int, int>> parse_size(const std::string& text, int lo, int hi) {
  const std::size_t x = text.find('x');
  if (x == std::string::npos) return std::nullopt;
  auto whole = [&](const std::string& part) -> std::optional<int> {
    if (part.empty() || part.size() > 9) return std::nullopt;  // 9 digits cannot overflow an int
    for (char c : part) {
      if (c < '0' || c > '9') return std::nullopt;
    }
    const int v = std::stoi(part);
    if (v < lo || v > hi) return std::nullopt;
    return v;
  };
  const auto w = whole(text.substr(0, x)), h = whole(text.substr(x + 1));
  if (!w || !h) return std::nullopt;
  return std::pair{*w, *h};
}

}  // namespace cv::cli
