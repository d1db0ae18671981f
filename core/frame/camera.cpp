// The camera's frame, rays and matrices.
#include "frame/camera.hpp"

#include <cmath>

#include <glm/glm.hpp>

#include "geo/geodesy.hpp"

namespace cv::core {
namespace {
constexpr double kDeg = 3.14159265358979323846 / 180.0;
}  // namespace

CameraFrame camera_frame(const Camera& cam) {
  const geo::EnuFrame f = geo::sphere_enu(cam.lat_deg, cam.lon_deg);
  const double h = cam.heading_deg * kDeg, pitch = cam.pitch_deg * kDeg;
  CameraFrame c;
  c.forward = std::cos(pitch) * (std::sin(h) * f.east + std::cos(h) * f.north) + std::sin(pitch) * f.up;
  // Right is the heading turned 90 degrees clockwise, level with the ground: defined also when
  // looking straight up or down, where the heading still sets which way the image turns.
  c.right = std::cos(h) * f.east - std::sin(h) * f.north;
  c.up = glm::cross(c.right, c.forward);
  c.tan_half = std::tan(0.5 * cam.fov_deg * kDeg);
  return c;
}

glm::dvec3 camera_ray(const Camera& cam, int px, int py) {
  const CameraFrame c = camera_frame(cam);
  const double x = (2.0 * (px + 0.5 + cam.pixel_shift_x) / cam.width - 1.0) * c.tan_half;
  const double y = (1.0 - 2.0 * (py + 0.5 + cam.pixel_shift_y) / cam.height) * c.tan_half * cam.height / cam.width;
  return glm::normalize(c.forward + x * c.right + y * c.up);
}

glm::dvec3 camera_ecef(const Camera& cam, double r0_m) {
  return geo::sphere_to_ecef({cam.lat_deg, cam.lon_deg, cam.alt_m}, r0_m);
}

glm::dmat4 camera_view_matrix(const Camera& cam) {
  const CameraFrame c = camera_frame(cam);
  // Rows: right, up, -forward (glm is column-major: m[column][row]).
  glm::dmat4 m(1.0);
  for (int i = 0; i < 3; ++i) {
    m[i][0] = c.right[i];
    m[i][1] = c.up[i];
    m[i][2] = -c.forward[i];
  }
  return m;
}

glm::dmat4 camera_projection_matrix(const Camera& cam, double near_m, double far_m) {
  const CameraFrame c = camera_frame(cam);
  const double aspect = static_cast<double>(cam.height) / cam.width;
  glm::dmat4 m(0.0);
  m[0][0] = 1.0 / c.tan_half;
  m[1][1] = -1.0 / (c.tan_half * aspect);  // row 0 at the top
  m[2][2] = -(far_m + near_m) / (far_m - near_m);
  m[2][3] = -1.0;
  m[3][2] = -2.0 * far_m * near_m / (far_m - near_m);
  return m;
}

}  // namespace cv::core
