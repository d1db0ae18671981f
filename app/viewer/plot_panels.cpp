// The viewer's Section and Series panels: requests checked, figures drawn and saved as the
// commands draw and save them (plot_panels.hpp).
#include "viewer/plot_panels.hpp"

#include <cmath>
#include <cstdio>
#include <exception>
#include <limits>
#include <vector>

#include "io/output_file.hpp"
#include "render/image_output.hpp"

namespace cv::viewer {

namespace {
// The PNG and the CSV of a figure, written together as the commands' -o and --csv are.
void save_figure(const plots::Canvas& canvas, const std::string& csv, const std::string& png_path, const std::string& csv_path,
                 const std::string& what) {
  core::check_output_extension(png_path, what + " PNG", {".png"});
  core::check_output_path(png_path, what + " PNG");
  core::check_output_extension(csv_path, what + " CSV", {".csv"});
  core::check_output_path(csv_path, what + " CSV");
  core::OutputGroup group;
  group.write(png_path, [&](std::FILE* f) { render::encode_png(f, canvas.width(), canvas.height(), canvas.rgb()); });
  group.write(csv_path, [&](std::FILE* f) {
    if (std::fwrite(csv.data(), 1, csv.size(), f) != csv.size()) throw core::WriteError("could not write " + csv_path);
  });
  group.commit();
}
}  // namespace

void compute_section(SectionPanel& panel, core::CloudVolume& volume, const std::string& source, std::size_t step) {
  panel.requested = false;
  const std::string problem = plots::section_problem(volume, source, panel.inputs);
  if (!problem.empty()) {
    panel.message = problem;
    return;
  }
  try {
    panel.figure = plots::section_figure(volume, source, step, panel.inputs);
  } catch (const std::exception& e) {  // the step could not be read
    panel.message = e.what();
    return;
  }
  panel.has_figure = true;
  panel.source = source;
  panel.step = step;
  panel.valid = volume.times[step].iso_utc;
  ++panel.version;
  panel.message.clear();
}

bool save_section(SectionPanel& panel) {
  if (!panel.has_figure) {
    panel.message = "nothing to save: draw a section first";
    return false;
  }
  try {
    save_figure(panel.figure.canvas, panel.figure.csv, panel.png_path, panel.csv_path, "section");
    panel.message = "wrote " + panel.png_path + " and " + panel.csv_path;
    return true;
  } catch (const std::exception& e) {
    panel.message = e.what();
    return false;
  }
}

void take_probe_point(SectionPanel& panel, const ProbePanel& probe, int end) {
  if (probe.source.empty()) {
    panel.message = "no probe yet: click (no drag) on the globe, then take its point";
    return;
  }
  (end == 0 ? panel.inputs.lat1 : panel.inputs.lat2) = probe.lat_deg;
  (end == 0 ? panel.inputs.lon1 : panel.inputs.lon2) = probe.lon_deg;
  panel.message.clear();
}

void compute_series(SeriesPanel& panel, core::CloudVolume& volume, const std::string& source) {
  panel.requested = false;
  const std::string problem = plots::series_problem(volume, source, panel.lat_deg, panel.lon_deg);
  if (!problem.empty()) {
    panel.message = problem;
    return;
  }
  try {
    panel.figure = plots::series_figure(volume, panel.lat_deg, panel.lon_deg, panel.width, panel.height);
  } catch (const std::exception& e) {
    panel.message = e.what();
    return;
  }
  panel.has_figure = true;
  panel.source = source;
  panel.at_lat = panel.lat_deg, panel.at_lon = panel.lon_deg;
  ++panel.version;
  panel.message.clear();
}

bool save_series(SeriesPanel& panel) {
  if (!panel.has_figure) {
    panel.message = "nothing to save: draw a series first";
    return false;
  }
  try {
    save_figure(panel.figure.canvas, panel.figure.csv, panel.png_path, panel.csv_path, "series");
    panel.message = "wrote " + panel.png_path + " and " + panel.csv_path;
    return true;
  } catch (const std::exception& e) {
    panel.message = e.what();
    return false;
  }
}

void take_probe_point(SeriesPanel& panel, const ProbePanel& probe) {
  if (probe.source.empty()) {
    panel.message = "no probe yet: click (no drag) on the globe, then take its point";
    return;
  }
  panel.lat_deg = probe.lat_deg, panel.lon_deg = probe.lon_deg;
  panel.message.clear();
}

namespace {
// Splits "a,b,c" into its numbers (all of them finite) and the rest after `n` of them (or empty).
bool leading_numbers(const std::string& v, std::size_t n, std::vector<double>& out, std::string& rest) {
  out.clear(), rest.clear();
  std::size_t at = 0;
  while (out.size() < n) {
    const std::size_t comma = v.find(',', at);
    const std::string part = v.substr(at, comma == std::string::npos ? std::string::npos : comma - at);
    try {
      std::size_t used = 0;
      const double x = std::stod(part, &used);
      if (used != part.size() || !std::isfinite(x)) return false;
      out.push_back(x);
    } catch (const std::exception&) {
      return false;
    }
    if (comma == std::string::npos) return out.size() == n;
    at = comma + 1;
    if (out.size() == n) rest = v.substr(at);
  }
  return true;
}
}  // namespace

std::string section_from_option(SectionPanel& panel, const std::string& value) {
  std::vector<double> x;
  std::string field;
  if (!leading_numbers(value, 4, x, field) || !(std::abs(x[0]) <= 90.0 && std::abs(x[2]) <= 90.0) ||
      field.find(',') != std::string::npos) {
    return "cloudviewer view: --section: found '" + value + "', expected FROM_LAT,FROM_LON,TO_LAT,TO_LON[,FIELD] with latitudes within -90..90";
  }
  panel.inputs.lat1 = x[0], panel.inputs.lon1 = x[1], panel.inputs.lat2 = x[2], panel.inputs.lon2 = x[3];
  if (!field.empty()) panel.inputs.field = field;
  panel.open = panel.requested = true;
  return "";
}

std::string series_from_option(SeriesPanel& panel, const std::string& value) {
  std::vector<double> x;
  std::string rest;
  if (!leading_numbers(value, 2, x, rest) || !rest.empty() || !(std::abs(x[0]) <= 90.0)) {
    return "cloudviewer view: --series: found '" + value + "', expected LAT,LON with the latitude within -90..90";
  }
  panel.lat_deg = x[0], panel.lon_deg = x[1];
  panel.open = panel.requested = true;
  return "";
}

double series_marker_x(const SeriesPanel& panel, double hours) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (!panel.has_figure || !std::isfinite(hours) || hours < -1e-9 || hours > panel.figure.t_end + 1e-9) return nan;
  return plots::series_x(panel.figure, hours);
}

}  // namespace cv::viewer
