// The analysts' section and time-series figures (issue 17, item 5), drawn once for the headless
// `cloudviewer section` and `series` commands and the viewer's Section and Series panels: the
// inputs checked (the commands' one-line messages), the data computed with core/analysis, the
// figure drawn on a Canvas, and the CSV text. Plain C++: no GL, no ImGui, no file writing.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "analysis/column_probe.hpp"
#include "analysis/section.hpp"
#include "plots/plot_canvas.hpp"
#include "volume/cloud_volume.hpp"

namespace cv::plots {

// A number for the CSVs and messages: printf's `fmt`, empty when not finite.
std::string num(double v, const char* fmt = "%.6g");

// "OPTION: found LAT,LON, outside the data of FILE, expected a point within EXTENT" when the grid
// does not hold the point, as the analysis commands word it after their name; else empty.
std::string point_problem(const core::VolumeGrid& grid, const std::string& option, double lat_deg, double lon_deg, const std::string& file);

struct SectionInputs {
  std::string field;  // a name section_field accepts
  double lat1 = 0.0, lon1 = 0.0, lat2 = 0.0, lon2 = 0.0;
  int width = 800, height = 400;  // the figure
  int columns = 64;               // the CSV's columns
  bool have_range = false;        // the colour bar's ends; else the section's own
  double lo = 0.0, hi = 0.0;
};

// What is wrong with a section's field and ends for this volume, worded as `cloudviewer section`
// words it after "cloudviewer section: " (the option, what was found, the data's extent, `file`);
// empty when they are fine.
std::string section_problem(const core::CloudVolume& volume, const std::string& file, const SectionInputs& in);

struct SectionFigure {
  core::SectionField field;
  core::Section pixels;     // one column per pixel of the plot area, one row per pixel
  core::Section grid_rows;  // the CSV's: `columns` columns at the grid's levels
  double lo = 0.0, hi = 0.0;  // the colour bar's ends
  Canvas canvas{1, 1, kPaper};
  std::string csv;          // as `section --csv` writes it
};

// The figure of step `step`; the inputs must pass section_problem (else std::invalid_argument).
SectionFigure section_figure(core::CloudVolume& volume, const std::string& file, std::size_t step, const SectionInputs& in);

// What is wrong with a series' point, worded as `cloudviewer series` words it after
// "cloudviewer series: "; empty when it is within the data.
std::string series_problem(const core::CloudVolume& volume, const std::string& file, double lat_deg, double lon_deg);

struct SeriesFigure {
  std::vector<core::ColumnProbe> columns;  // per step of the file
  std::vector<std::string> valid;          // per step: its valid time as the file gives it
  std::vector<double> hours;               // per step: hours after the first (or the step index without UTC times)
  bool timed = false;
  Canvas canvas{1, 1, kPaper};
  std::string csv;                         // as `series --csv` writes it (the command also prints it)
  int left = 0, right = 0, top = 0, bottom = 0;  // the panels' span on the canvas (pixels)
  double t_end = 1.0;                      // the time axis runs 0..t_end hours from left to right
};

// The canvas x of `hours` on a series figure's time axis (the points are drawn there).
double series_x(const SeriesFigure& figure, double hours);

// The column at (lat, lon) at each of the file's steps, as probe reads it, drawn in three panels
// (cover, optical depth, base and top); the point must pass series_problem.
SeriesFigure series_figure(core::CloudVolume& volume, double lat_deg, double lon_deg, int width, int height);

}  // namespace cv::plots
