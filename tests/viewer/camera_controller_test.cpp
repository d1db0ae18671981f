// The viewer's camera navigation and derived state, as plain math (no window): orbiting keeps the
// altitude, fly speed follows altitude, placement round-trips with the renderer's camera frame.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include <glm/glm.hpp>

#include "geo/geodesy.hpp"
#include "viewer/camera_controller.hpp"
#include "scene/framing.hpp"
#include "viewer/viewer_state.hpp"

namespace {
using namespace cv;
constexpr double kR = 6371000.0;

core::Camera camera(double lat, double lon, double alt, double heading, double pitch) {
  core::Camera c;
  c.lat_deg = lat, c.lon_deg = lon, c.alt_m = alt, c.heading_deg = heading, c.pitch_deg = pitch;
  c.width = 320, c.height = 180;
  return c;
}

TEST(CameraController, PlaceCameraRoundTripsWithTheCameraFrame) {
  const core::Camera c = camera(35.0, 150.0, 12000.0, 123.0, -20.0);
  core::Camera d = camera(0, 0, 0, 0, 0);
  viewer::place_camera(d, geo::sphere_to_ecef({c.lat_deg, c.lon_deg, c.alt_m}, kR), core::camera_frame(c).forward, kR);
  EXPECT_NEAR(d.lat_deg, 35.0, 1e-9);
  EXPECT_NEAR(d.lon_deg, 150.0, 1e-9);
  EXPECT_NEAR(d.alt_m, 12000.0, 1e-6);
  EXPECT_NEAR(d.heading_deg, 123.0, 1e-9);
  EXPECT_NEAR(d.pitch_deg, -20.0, 1e-9);
}

TEST(CameraController, OrbitKeepsAltitudeAndTheViewRelativeToTheGround) {
  core::Camera c = camera(20.0, 100.0, 500000.0, 0.0, -60.0);
  viewer::orbit(c, 100.0, 0.0, kR);
  EXPECT_NEAR(c.alt_m, 500000.0, 1e-3);
  EXPECT_NEAR(c.lat_deg, 20.0, 1e-9);  // a horizontal drag turns the globe about its axis
  // 100 px at 320 px wide and 60 degrees fov from 500 km: 100 x 500 km x 2 tan 30 / 320 of arc.
  const double expect_deg = 100.0 * 500000.0 * 2.0 * std::tan(30.0 * std::numbers::pi / 180.0) / 320.0 / kR * 180.0 / std::numbers::pi;
  EXPECT_NEAR(c.lon_deg, 100.0 - expect_deg, 1e-9);
  EXPECT_NEAR(c.heading_deg, 0.0, 1e-9);
  EXPECT_NEAR(c.pitch_deg, -60.0, 1e-9);
  viewer::orbit(c, 0.0, -50.0, kR);  // dragging the ground up (away) moves the camera back, south
  EXPECT_NEAR(c.lat_deg, 20.0 - expect_deg / 2.0, 1e-9);
  EXPECT_NEAR(c.alt_m, 500000.0, 1e-3);
  EXPECT_NEAR(c.pitch_deg, -60.0, 1e-9);
  core::Camera down = camera(0.0, 0.0, 1e6, 0.0, -90.0);  // straight down: the vertical drag still works
  viewer::orbit(down, 0.0, 40.0, kR);
  EXPECT_GT(down.lat_deg, 0.0);
  EXPECT_NEAR(down.pitch_deg, -90.0, 1e-6);
}

TEST(CameraController, FlySpeedScalesWithAltitudeAndMovesAlongTheView) {
  EXPECT_DOUBLE_EQ(viewer::fly_speed_m_per_s(2000.0), 500.0);
  EXPECT_DOUBLE_EQ(viewer::fly_speed_m_per_s(1e7), 2.5e6);
  EXPECT_DOUBLE_EQ(viewer::fly_speed_m_per_s(0.0), 20.0);  // never stuck at the ground
  core::Camera c = camera(0.0, 0.0, 2000.0, 90.0, 0.0);  // level, looking east
  viewer::fly(c, {1.0, 0.0, 0.0}, 0.1, kR);               // 50 m east, 2 km above the sphere
  EXPECT_NEAR(c.lon_deg, 50.0 / (kR + 2000.0) * 180.0 / std::numbers::pi, 1e-9);
  EXPECT_NEAR(c.lat_deg, 0.0, 1e-12);
  EXPECT_NEAR(c.alt_m, 2000.0, 0.01);  // 50 m along the tangent rises 0.2 mm
  EXPECT_DOUBLE_EQ(c.heading_deg, 90.0);
  viewer::fly(c, {0.0, 0.0, -1.0}, 10.0, kR);  // down 5 km: stops at the floor
  EXPECT_DOUBLE_EQ(c.alt_m, 2.0);
}

TEST(CameraController, ZoomStepsAFractionOfTheAltitude) {
  core::Camera c = camera(10.0, 10.0, 100000.0, 0.0, -90.0);
  viewer::zoom(c, 1.0, kR);
  EXPECT_NEAR(c.alt_m, 85000.0, 1e-3);
  for (int i = 0; i < 200; ++i) viewer::zoom(c, 1.0, kR);
  EXPECT_GE(c.alt_m, 10.0);
}

TEST(ViewerState, IsoTimesAndWhatResetsTheAccumulation) {
  EXPECT_EQ(core::parse_iso_utc("2024-01-15T03:00:00Z"), 1705287600);
  EXPECT_EQ(core::parse_iso_utc("2024-01-15T03:00"), 1705287600);
  EXPECT_FALSE(core::parse_iso_utc("2024-13-15T03:00:00Z"));
  EXPECT_FALSE(core::parse_iso_utc("noon"));
  core::Scene a;
  a.camera = camera(1, 2, 3, 4, 5);
  core::Scene b = a;
  b.render.exposure *= 2.0;  // tonemap only
  b.render.march.per_frame.frame = 7;  // the accumulation's own counter
  EXPECT_TRUE(viewer::same_march(a, b));
  b.render.march.quality.view_step_m += 1.0;
  EXPECT_FALSE(viewer::same_march(a, b));
  b = a;
  b.camera->heading_deg += 0.001;
  EXPECT_FALSE(viewer::same_march(a, b));
  b = a;
  b.render.resolution_scale = 0.5;
  EXPECT_FALSE(viewer::same_march(a, b));
}

TEST(ViewerState, MarchSizeFollowsTheResolutionScale) {
  core::Scene s;
  int w = 0, h = 0;
  s.render.resolution_scale = 0.5;
  viewer::march_size(s, 321, 180, w, h);
  EXPECT_EQ(w, 161);
  EXPECT_EQ(h, 90);
  s.render.resolution_scale = 0.0;  // clamped, never an empty image
  viewer::march_size(s, 10, 10, w, h);
  EXPECT_EQ(w, 1);
  EXPECT_EQ(h, 1);
}

}  // namespace
