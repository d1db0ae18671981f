// What the analysts' commands share (app/cli/analysis_commands.cpp, compare_command.cpp): loading a
// source, choosing its step, parsing points, checking outputs, formatting numbers for CSV.
#pragma once

#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <utility>

#include "analysis/column_probe.hpp"
#include "cli_common.hpp"
#include "importer.hpp"
#include "io/output_file.hpp"
#include "plots/analysis_plots.hpp"
#include "plots/plot_canvas.hpp"
#include "scene/framing.hpp"
#include "scene/instant.hpp"
#include "volume/volume_io.hpp"

namespace cv::cli::analysis {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The options every analysis command shares, parsed in turn; each command takes the rest.
struct Common {
  std::string command;  // "probe", for messages
  std::string file;
  std::string time;     // ISO or a step index; empty: the first step
};

inline core::CloudVolume load(const std::string& path) {
  if (path.size() > 6 && path.substr(path.size() - 6) == ".cvvol") return core::read_cvvol(path, 2);
  importers::ImportOptions o;
  o.cache_steps = 2;
  return importers::import_file(path, o);
}

// The step --time names: a step index, or an instant that is one of the file's valid times (the
// probes read the file's own steps; between them nothing is interpolated, and the message says so).
inline std::size_t resolve_step(const core::CloudVolume& vol, const Common& c) {
  if (c.time.empty()) return 0;
  if (core::parse_iso_utc(c.time)) {
    const core::Instant at = core::instant_at_time(vol.times, c.time, c.file);
    if (at.between()) {
      throw UsageError{"cloudviewer " + c.command + ": --time: found " + c.time + ", between steps " + std::to_string(at.step0) + " (" +
                       vol.times[at.step0].iso_utc + ") and " + std::to_string(at.step1) + " (" + vol.times[at.step1].iso_utc +
                       "), expected one of the file's valid times " + core::time_range_text(vol.times)};
    }
    return at.step0;
  }
  const double n = parse_number("--time", c.time);
  if (!(n >= 0 && n == std::floor(n) && n < static_cast<double>(vol.times.size()))) {
    throw UsageError{"cloudviewer " + c.command + ": --time: found '" + c.time + "', expected a UTC date-time or a step index 0.." +
                     std::to_string(vol.times.size() - 1) + " of " + c.file};
  }
  return static_cast<std::size_t>(n);
}

// LAT,LON with latitude in -90..90.
inline std::pair<double, double> parse_lat_lon(const std::string& cmd, const std::string& option, const std::string& v) {
  const auto p = parse_list(option, v, ',', 2, 2, "LAT,LON in degrees");
  if (!(p[0] >= -90.0 && p[0] <= 90.0)) {
    throw UsageError{"cloudviewer " + cmd + ": " + option + ": found '" + v + "', expected a latitude within -90..90"};
  }
  return {p[0], p[1]};
}

inline void check_point(const core::VolumeGrid& g, const std::string& cmd, const std::string& option, double lat, double lon,
                 const std::string& file) {
  const std::string problem = plots::point_problem(g, option, lat, lon, file);
  if (!problem.empty()) throw UsageError{"cloudviewer " + cmd + ": " + problem};
}

inline void check_outputs(const std::string& cmd, const std::string& png, const std::string& csv, const std::string& input) {
  (void)cmd;
  if (!png.empty()) {
    core::check_output_extension(png, "-o", {".png"});
    core::check_output_path(png, "-o");
    core::check_output_not_input(png, "-o", input, "the input");
  }
  if (!csv.empty()) {
    core::check_output_extension(csv, "--csv", {".csv"});
    core::check_output_path(csv, "--csv");
    core::check_output_not_input(csv, "--csv", input, "the input");
  }
}

inline void put(std::FILE* f, const std::string& s) {
  if (std::fwrite(s.data(), 1, s.size(), f) != s.size()) throw core::WriteError("write failed");
}

// The plots' raster, area and colours, and num (app/plots/).
using namespace cv::plots;

}  // namespace cv::cli::analysis
