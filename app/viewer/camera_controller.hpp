// Camera navigation for the viewer, as pure math on core::Camera (no GL, no window): the automatic
// framing of a volume, orbiting the globe, zoom, and a fly mode whose speed scales with altitude.
#pragma once

#include <glm/vec3.hpp>

#include "frame/camera.hpp"

namespace cv::viewer {


// Sets the camera's position and geodetic heading/pitch (degrees) from an Earth-centred eye point
// and view direction (metres, unit vector) on a sphere of radius r0_m.
void place_camera(core::Camera& cam, const glm::dvec3& eye_ecef_m, const glm::dvec3& forward, double r0_m);

// Orbit: drags the globe under the camera. dx, dy are the drag in pixels (right, down); the globe
// turns about its centre (horizontal drags about its axis, vertical ones about the camera's right
// vector) by about the ground one pixel covers at nadir, so the ground follows the cursor roughly;
// the altitude and the view relative to the ground below stay the same.
void orbit(core::Camera& cam, double dx_px, double dy_px, double r0_m);

// Zoom: moves along the view direction by `notches` x 15 % of the altitude (positive: closer),
// never below min_alt_m.
void zoom(core::Camera& cam, double notches, double r0_m, double min_alt_m = 10.0);

// Fly: turn by mouse pixels (heading right, pitch up), pitch held within +-89.9 degrees.
void look(core::Camera& cam, double dx_px, double dy_px, double degrees_per_px = 0.15);

// Fly speed in m/s: a quarter of the altitude per second, at least 20 m/s, so a camera inside a
// cloud at 2 km moves at 500 m/s and one at 20 000 km crosses the globe in seconds.
double fly_speed_m_per_s(double alt_m);

// Fly: moves by (forward, right, up) in units of fly_speed x seconds; forward/right follow the view,
// up is the local vertical. Altitude stays at least min_alt_m.
void fly(core::Camera& cam, const glm::dvec3& forward_right_up, double seconds, double r0_m, double min_alt_m = 2.0);

}  // namespace cv::viewer
