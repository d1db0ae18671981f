// Camera navigation: framing, orbit, zoom and fly on the spherical Earth.
#include "viewer/camera_controller.hpp"

#include <algorithm>
#include <cmath>

#include <glm/glm.hpp>

#include "geo/geodesy.hpp"

namespace cv::viewer {
namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

glm::dvec3 eye_of(const core::Camera& c, double r0) { return geo::sphere_to_ecef({c.lat_deg, c.lon_deg, c.alt_m}, r0); }

// Rotates v about the unit axis by angle (radians), Rodrigues' formula.
glm::dvec3 rotate(const glm::dvec3& v, const glm::dvec3& axis, double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  return v * c + glm::cross(axis, v) * s + axis * glm::dot(axis, v) * (1.0 - c);
}
}  // namespace

void place_camera(core::Camera& cam, const glm::dvec3& eye, const glm::dvec3& forward, double r0) {
  const geo::Geodetic p = geo::ecef_to_sphere(eye, r0);
  cam.lat_deg = p.lat_deg;
  cam.lon_deg = p.lon_deg;
  cam.alt_m = p.alt_m;
  const geo::EnuFrame f = geo::sphere_enu(p.lat_deg, p.lon_deg);
  cam.pitch_deg = std::asin(std::clamp(glm::dot(forward, f.up), -1.0, 1.0)) / kDeg;
  const double e = glm::dot(forward, f.east), n = glm::dot(forward, f.north);
  // Straight up or down the heading is undefined: keep the one the camera had.
  if (std::hypot(e, n) > 1e-9) cam.heading_deg = std::atan2(e, n) / kDeg;
}

void orbit(core::Camera& cam, double dx_px, double dy_px, double r0) {
  const core::CameraFrame f = core::camera_frame(cam);
  glm::dvec3 eye = eye_of(cam, r0);
  glm::dvec3 fwd = f.forward;
  // One pixel moves the view by about the ground distance one pixel covers at nadir: alt x (2 tan
  // half-fov / width) metres, i.e. that over r0 radians of Earth rotation.
  const double rad_per_px = cam.alt_m * 2.0 * f.tan_half / std::max(1, cam.width) / r0;
  // Horizontal drag: about the Earth's axis (the globe spins under the camera; drag right turns
  // the camera westward so the ground follows the cursor).
  const glm::dvec3 pole(0.0, 0.0, 1.0);
  const double a = -dx_px * rad_per_px;
  eye = rotate(eye, pole, a);
  fwd = rotate(fwd, pole, a);
  // Vertical drag: about the axis through the centre along the camera's level right vector (defined
  // at every pitch, also straight down); dragging up pushes the ground away, so the camera goes back.
  const glm::dvec3 right = rotate(f.right, pole, a);
  const double b = -dy_px * rad_per_px;
  eye = rotate(eye, right, b);
  fwd = rotate(fwd, right, b);
  place_camera(cam, eye, glm::normalize(fwd), r0);
}

void zoom(core::Camera& cam, double notches, double r0, double min_alt_m) {
  const glm::dvec3 fwd = core::camera_frame(cam).forward;
  const double step = 0.15 * notches * std::max(cam.alt_m, min_alt_m);
  place_camera(cam, eye_of(cam, r0) + step * fwd, fwd, r0);
  cam.alt_m = std::max(cam.alt_m, min_alt_m);
}

void look(core::Camera& cam, double dx_px, double dy_px, double degrees_per_px) {
  cam.heading_deg = std::remainder(cam.heading_deg + dx_px * degrees_per_px, 360.0);
  cam.pitch_deg = std::clamp(cam.pitch_deg - dy_px * degrees_per_px, -89.9, 89.9);
}

double fly_speed_m_per_s(double alt_m) { return std::max(20.0, 0.25 * alt_m); }

void fly(core::Camera& cam, const glm::dvec3& fru, double seconds, double r0, double min_alt_m) {
  const core::CameraFrame f = core::camera_frame(cam);
  const glm::dvec3 eye = eye_of(cam, r0);
  const glm::dvec3 up = glm::normalize(eye);
  const double d = fly_speed_m_per_s(cam.alt_m) * seconds;
  const double heading = cam.heading_deg, pitch = cam.pitch_deg;
  const glm::dvec3 moved = eye + d * (fru.x * f.forward + fru.y * f.right + fru.z * up);
  // Flying keeps the geodetic heading and pitch (the view stays level as the ground curves away).
  place_camera(cam, moved, f.forward, r0);
  cam.heading_deg = heading;
  cam.pitch_deg = pitch;
  cam.alt_m = std::max(cam.alt_m, min_alt_m);
}

}  // namespace cv::viewer
