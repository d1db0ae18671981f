// The viewer's probe (issue 17, item 4): a click on a pixel (a press and release without a drag)
// reads the column under it with core/analysis's probe_column, as `cloudviewer probe` does, for the
// panel and its CSV. Plain C++ (no ImGui, no GL): panels.cpp draws it, viewer.cpp feeds it clicks,
// the tests call it.
#pragma once

#include <optional>
#include <string>

#include <glm/vec2.hpp>

#include "analysis/column_probe.hpp"
#include "frame/camera.hpp"
#include "volume/cloud_volume.hpp"

namespace cv::viewer {

// A click: the button went down and came up again within kSlop pixels of travel (a drag orbits).
struct ClickDetector {
  static constexpr double kSlop = 3.0;
  bool down = false;
  double x0 = 0.0, y0 = 0.0, travel = 0.0;
  // This frame's button state and cursor; true on the frame the button comes up after a click. The
  // click was at (x0, y0).
  bool update(bool held, double x, double y);
};

// Where pixel (px, py) of `cam` (pixel centres, rows down) meets the sphere of radius r0_m, as
// (lat, lon) in degrees; nothing when the ray passes the Earth.
std::optional<glm::dvec2> pixel_ground(const core::Camera& cam, double px, double py, double r0_m);

struct ProbePanel {
  bool open = false;
  std::string source, valid;  // the file and the valid time of the step read
  std::size_t step = 0;
  int view = 0;               // the view clicked
  double lat_deg = 0.0, lon_deg = 0.0;
  core::ColumnProbe column;
  // Where the light came from along the clicked view's ray to the column's ground (issue 17, item
  // 4): the march kernel's record for that one ray, as `probe --camera` gives it.
  std::optional<core::ViewRayProbe> ray;
  bool has_temperature = false, has_wind = false, has_pressure = false;
  std::string csv;            // as `probe --csv` writes it
  std::string csv_path = "probe.csv";
  std::string message;        // the last probe's or save's problem or result
};

// Reads the column at (lat, lon) of `step` of the volume (its data and its grid-mean extinction, as
// the probe command reads them) into the panel; outside the data, only the message (naming the
// data's extent) is set. With a camera, also the view ray from it to the column's ground, marched
// at view_step_m (the probe command's --camera and --view-step).
void probe_into(ProbePanel& panel, core::CloudVolume& volume, const std::string& source, std::size_t step, double lat_deg,
                double lon_deg, const core::Camera* camera = nullptr, double view_step_m = 100.0);

// Writes the panel's CSV to panel.csv_path (atomically); the message says where or why not.
bool save_probe_csv(ProbePanel& panel);

}  // namespace cv::viewer
