// The bench tools' command lines, parsed one way: options with a value, switches, and words
// (scene names). --help prints the usage; an unknown option, a missing value or a bad one is one
// line naming the option, what was found and what was expected, and exit code 2.
#pragma once

#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

namespace cv::bench_args {

struct Option {
  std::string name;      // "--spp"
  std::string expected;  // what the value must be, for the error line; empty: a switch with no value
  // Takes the value (a switch gets ""); false when it is not what `expected` says.
  std::function<bool(const std::string&)> set;
};

// Parses argv[1..]: -1 to go on, else the exit code (0 after --help, 2 after a bad argument).
// Words not starting with '-' go to `words`, or are refused where the tool takes none.
inline int parse(const char* tool, const std::string& usage, int argc, char** argv, const std::vector<Option>& options,
                 std::vector<std::string>* words = nullptr) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") {
      std::printf("%s", usage.c_str());
      return 0;
    }
    if (words && !a.empty() && a[0] != '-') {
      words->push_back(a);
      continue;
    }
    const Option* o = nullptr;
    for (const Option& c : options) {
      if (c.name == a) o = &c;
    }
    if (!o) {
      std::fprintf(stderr, "%s: unknown option %s (see --help)\n", tool, a.c_str());
      return 2;
    }
    if (o->expected.empty()) {
      o->set("");
      continue;
    }
    if (i + 1 >= argc) {
      std::fprintf(stderr, "%s: %s needs a value, %s (see --help)\n", tool, a.c_str(), o->expected.c_str());
      return 2;
    }
    const std::string v = argv[++i];
    if (!o->set(v)) {
      std::fprintf(stderr, "%s: %s: found '%s', expected %s\n", tool, a.c_str(), v.c_str(), o->expected.c_str());
      return 2;
    }
  }
  return -1;
}

// A whole number in lo..hi written with digits only (no sign, no "12abc").
inline bool whole_number(const std::string& v, long long lo, long long hi, long long& out) {
  if (v.empty() || v.size() > 18 || v.find_first_not_of("0123456789") != std::string::npos) return false;
  const long long n = std::stoll(v);
  if (n < lo || n > hi) return false;
  out = n;
  return true;
}

inline Option integer(const std::string& name, int& out, int lo = 1, int hi = 1 << 30) {
  return {name, "an integer from " + std::to_string(lo) + " to " + std::to_string(hi), [&out, lo, hi](const std::string& v) {
            long long n = 0;
            if (!whole_number(v, lo, hi, n)) return false;
            out = static_cast<int>(n);
            return true;
          }};
}

inline Option seed(const std::string& name, std::uint64_t& out) {
  return {name, "a whole number (the random seed)", [&out](const std::string& v) {
            long long n = 0;
            if (!whole_number(v, 0, 999999999999999999LL, n)) return false;
            out = static_cast<std::uint64_t>(n);
            return true;
          }};
}

// "1,2,5": finite numbers separated by commas, at least one.
inline Option numbers(const std::string& name, std::vector<double>& out) {
  return {name, "finite numbers separated by commas, e.g. 1,2,5", [&out](const std::string& v) {
            std::vector<double> got;
            std::stringstream in(v);
            std::string item;
            while (std::getline(in, item, ',')) {
              char* end = nullptr;
              errno = 0;
              const double x = std::strtod(item.c_str(), &end);
              if (item.empty() || end != item.c_str() + item.size() || errno == ERANGE || !std::isfinite(x)) return false;
              got.push_back(x);
            }
            if (got.empty() || v.back() == ',') return false;
            out = got;
            return true;
          }};
}

inline Option one_of(const std::string& name, std::string& out, const std::vector<std::string>& allowed) {
  std::string expected = "one of";
  for (std::size_t k = 0; k < allowed.size(); ++k) expected += (k ? ", " : " ") + allowed[k];
  return {name, expected, [&out, allowed](const std::string& v) {
            for (const std::string& a : allowed) {
              if (v == a) {
                out = v;
                return true;
              }
            }
            return false;
          }};
}

// "WxH", both whole numbers from 1 to 100000.
inline Option size(const std::string& name, int& w, int& h) {
  return {name, "WxH, two whole numbers from 1 to 100000", [&w, &h](const std::string& v) {
            const std::size_t x = v.find('x');
            long long a = 0, b = 0;
            if (x == std::string::npos || !whole_number(v.substr(0, x), 1, 100000, a) || !whole_number(v.substr(x + 1), 1, 100000, b)) {
              return false;
            }
            w = static_cast<int>(a), h = static_cast<int>(b);
            return true;
          }};
}

// A folder, made (with its parents) if it is not there yet.
inline Option folder(const std::string& name, std::string& out) {
  return {name, "a folder that exists or can be made", [&out](const std::string& v) {
            std::error_code ec;
            if (v.empty()) return false;
            std::filesystem::create_directories(v, ec);
            if (ec || !std::filesystem::is_directory(v)) return false;
            out = v;
            return true;
          }};
}

inline Option flag(const std::string& name, bool& out) {
  return {name, "", [&out](const std::string&) {
            out = true;
            return true;
          }};
}

}  // namespace cv::bench_args
