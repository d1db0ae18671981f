// The viewer's probe: clicks, the ground under a pixel, the column read and saved (probe_panel.hpp).
#include "viewer/probe_panel.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <stdexcept>

#include <glm/glm.hpp>

#include "geo/geodesy.hpp"
#include "io/output_file.hpp"
#include "volume/grid_mean.hpp"

namespace cv::viewer {

bool ClickDetector::update(bool held, double x, double y) {
  if (held && !down) {
    down = true;
    x0 = x, y0 = y, travel = 0.0;
    return false;
  }
  if (held) {
    travel = std::max(travel, std::hypot(x - x0, y - y0));
    return false;
  }
  const bool click = down && std::max(travel, std::hypot(x - x0, y - y0)) <= kSlop;
  down = false;
  return click;
}

std::optional<glm::dvec2> pixel_ground(const core::Camera& cam, double px, double py, double r0_m) {
  const int ix = std::clamp(static_cast<int>(std::floor(px)), 0, cam.width - 1);
  const int iy = std::clamp(static_cast<int>(std::floor(py)), 0, cam.height - 1);
  const glm::dvec3 o = geo::sphere_to_ecef({cam.lat_deg, cam.lon_deg, cam.alt_m}, r0_m);
  const glm::dvec3 d = glm::normalize(core::camera_ray(cam, ix, iy));
  const double b = glm::dot(o, d), c = glm::dot(o, o) - r0_m * r0_m;
  const double disc = b * b - c;
  if (disc < 0.0) return std::nullopt;
  const double t = -b - std::sqrt(disc);
  if (t < 0.0) return std::nullopt;
  const geo::Geodetic g = geo::ecef_to_sphere(o + t * d, r0_m);
  return glm::dvec2(g.lat_deg, g.lon_deg);
}

void probe_into(ProbePanel& panel, core::CloudVolume& volume, const std::string& source, std::size_t step, double lat_deg,
                double lon_deg, const core::Camera* camera, double view_step_m) {
  panel.open = true;
  char at[64];
  std::snprintf(at, sizeof at, "%.4f, %.4f", lat_deg, lon_deg);
  if (!core::grid_holds(volume.grid, lat_deg, lon_deg)) {
    panel.message = std::string("the click at ") + at + " is outside the data of " + source + " (" + core::grid_extent_text(volume.grid) + ")";
    return;
  }
  const core::TimeStepData& data = volume.step(step);
  panel.column = core::probe_column(volume, data, core::grid_mean_extinction(volume.grid, data), lat_deg, lon_deg);
  panel.ray.reset();
  if (camera) {
    const double ground = std::isfinite(panel.column.ground_m) ? panel.column.ground_m : 0.0;
    try {
      panel.ray = core::probe_view_ray(core::prepare_volume(volume.grid, data), camera->lat_deg, camera->lon_deg, camera->alt_m,
                                       lat_deg, lon_deg, ground, view_step_m);
    } catch (const std::invalid_argument&) {  // the camera stands at the point: no ray to record
    }
  }
  panel.source = source;
  panel.step = step;
  panel.valid = volume.times[step].iso_utc;
  panel.lat_deg = lat_deg, panel.lon_deg = lon_deg;
  panel.has_temperature = volume.has_field[static_cast<int>(core::Field::Temperature)];
  panel.has_pressure = volume.has_field[static_cast<int>(core::Field::Pressure)];
  panel.has_wind = volume.has_field[static_cast<int>(core::Field::WindU)] && volume.has_field[static_cast<int>(core::Field::WindV)];
  char where[96];
  std::snprintf(where, sizeof where, " at lat %.6g lon %.6g, valid ", lat_deg, lon_deg);
  panel.csv = "# probe of " + source + where + panel.valid + "\n" + core::probe_summary_csv(panel.column) +
              (panel.ray ? core::view_ray_csv(*panel.ray) : std::string()) + "\n" + core::probe_levels_csv(panel.column, volume);
  panel.message.clear();
}

bool save_probe_csv(ProbePanel& panel) {
  try {
    core::check_output_extension(panel.csv_path, "probe CSV", {".csv"});
    core::check_output_path(panel.csv_path, "probe CSV");
    core::write_file_atomically(panel.csv_path, [&](std::FILE* f) {
      if (std::fputs(panel.csv.c_str(), f) < 0) throw core::WriteError("could not write the probe");
    });
    panel.message = "wrote " + panel.csv_path;
    return true;
  } catch (const std::exception& e) {
    panel.message = e.what();
    return false;
  }
}

}  // namespace cv::viewer
