// The viewer's Section and Series panels (issue 17, item 5): a vertical section between two points
// and a time series at a point, computed and drawn by app/plots (analysis_plots.hpp) exactly as
// `cloudviewer section` and `cloudviewer series` compute and draw them, down to the saved PNG and
// CSV. Plain C++ (no ImGui, no GL): panels.cpp shows the figures, viewer.cpp runs the requests, the
// tests call it.
#pragma once

#include <cstddef>
#include <string>

#include "plots/analysis_plots.hpp"
#include "viewer/probe_panel.hpp"
#include "volume/cloud_volume.hpp"

namespace cv::viewer {

struct SectionPanel {
  bool open = false;
  plots::SectionInputs inputs;  // the field and the two ends as typed (the figure at the command's default size)
  bool requested = false;       // "draw" was pressed: the main loop calls compute_section
  bool has_figure = false;
  plots::SectionFigure figure;  // the last section drawn
  std::string source, valid;    // its file and valid time
  std::size_t step = 0;
  int version = 0;              // counts the figures drawn (the panel re-uploads its image on a change)
  std::string png_path = "section.png", csv_path = "section.csv";
  std::string message;          // the last request's or save's problem or result, one line
  SectionPanel() { inputs.field = "extinction"; }
};

// Checks the panel's inputs against the volume (section_problem: the command's message, shown in
// the panel; the last figure stays) and draws the section of `step`.
void compute_section(SectionPanel& panel, core::CloudVolume& volume, const std::string& source, std::size_t step);

// Writes the figure's PNG and CSV to png_path and csv_path together (atomically, as the command's
// -o and --csv); the message says where or why not.
bool save_section(SectionPanel& panel);

// Sets the section's start (end = 0) or end (1) to the point of the last probe click; the message
// says so when there was none.
void take_probe_point(SectionPanel& panel, const ProbePanel& probe, int end);

struct SeriesPanel {
  bool open = false;
  double lat_deg = 0.0, lon_deg = 0.0;  // as typed
  int width = 800, height = 480;        // the command's default figure
  bool requested = false;               // "draw" was pressed: the main loop calls compute_series
  bool has_figure = false;
  plots::SeriesFigure figure;
  std::string source;
  double at_lat = 0.0, at_lon = 0.0;    // the figure's point
  int version = 0;
  std::string png_path = "series.png", csv_path = "series.csv";
  std::string message;
};

// The column at the panel's point at each of the file's steps (series_problem's message when the
// point is outside the data; the last figure stays).
void compute_series(SeriesPanel& panel, core::CloudVolume& volume, const std::string& source);

bool save_series(SeriesPanel& panel);

// The series' point from the last probe click.
void take_probe_point(SeriesPanel& panel, const ProbePanel& probe);

// `view --section LAT,LON,LAT,LON[,FIELD]` and `--series LAT,LON`: open the panel with those inputs
// and ask for the figure (the data's own problems then show in the panel). The message of a value
// that is not that list of numbers (latitudes within -90..90), naming the option; else empty.
std::string section_from_option(SectionPanel& panel, const std::string& value);
std::string series_from_option(SeriesPanel& panel, const std::string& value);

// The x of the viewer's time (hours after the file's first step, or the step index without UTC
// times, as the figure's axis) on the figure, in its pixels; NaN outside the axis or without a figure.
double series_marker_x(const SeriesPanel& panel, double hours);

}  // namespace cv::viewer
