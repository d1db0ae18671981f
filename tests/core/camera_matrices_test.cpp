// The camera-relative view and projection matrices put a point on a pixel's march ray onto that
// pixel's centre, at the depth its distance gives, for cameras near the ground and far away.
#include <gtest/gtest.h>

#include <glm/glm.hpp>

#include "reference/raymarcher.hpp"

namespace {
using namespace cv;

void expect_rays_land_on_their_pixels(const core::Camera& cam) {
  const glm::dmat4 vp = core::camera_projection_matrix(cam, 10.0, 1e7) * core::camera_view_matrix(cam);
  for (int py : {0, cam.height / 3, cam.height - 1}) {
    for (int px : {0, cam.width / 2, cam.width - 1}) {
      for (double t : {50.0, 3e4, 5e6}) {
        const glm::dvec4 clip = vp * glm::dvec4(t * core::camera_ray(cam, px, py), 1.0);
        const glm::dvec3 ndc = glm::dvec3(clip) / clip.w;
        EXPECT_NEAR((ndc.x + 1.0) * 0.5 * cam.width, px + 0.5, 1e-6) << px << "," << py << " at " << t;
        EXPECT_NEAR((ndc.y + 1.0) * 0.5 * cam.height, py + 0.5, 1e-6) << px << "," << py << " at " << t;
        EXPECT_GT(ndc.z, -1.0);
        EXPECT_LT(ndc.z, 1.0);
        // Eye-space depth is the distance along the forward axis: t times the ray's cosine to it.
        const glm::dvec4 eye = core::camera_view_matrix(cam) * glm::dvec4(t * core::camera_ray(cam, px, py), 1.0);
        EXPECT_NEAR(-eye.z, t * glm::dot(core::camera_ray(cam, px, py), core::camera_frame(cam).forward), 1e-6 * t);
        EXPECT_NEAR(glm::length(glm::dvec3(eye)), t, 1e-9 * t);  // a rotation: distances kept
      }
    }
  }
}

TEST(CameraMatrices, RaysLandOnTheirPixelCentres) {
  core::Camera low;
  low.lat_deg = 47.0, low.lon_deg = 8.0, low.alt_m = 1200.0, low.heading_deg = 30.0, low.pitch_deg = -10.0;
  low.fov_deg = 70.0, low.width = 64, low.height = 36;
  expect_rays_land_on_their_pixels(low);
  core::Camera orbit;
  orbit.lat_deg = -20.0, orbit.lon_deg = 179.5, orbit.alt_m = 4e8, orbit.heading_deg = 0.0, orbit.pitch_deg = -90.0;
  orbit.fov_deg = 3.0, orbit.width = 48, orbit.height = 48;
  expect_rays_land_on_their_pixels(orbit);
}

TEST(CameraMatrices, DepthGrowsWithDistance) {
  core::Camera c;
  c.alt_m = 2000.0, c.width = 16, c.height = 9;
  const glm::dmat4 vp = core::camera_projection_matrix(c, 1.0, 1e6) * core::camera_view_matrix(c);
  double last = -2.0;
  for (double t : {1.0, 10.0, 1e3, 1e5, 1e6}) {
    const glm::dvec4 clip = vp * glm::dvec4(t * core::camera_ray(c, 8, 4), 1.0);
    const double z = clip.z / clip.w;
    EXPECT_GT(z, last);
    last = z;
  }
  const glm::dvec4 far = vp * glm::dvec4(1e6 * core::camera_frame(c).forward, 1.0);
  EXPECT_NEAR(far.z / far.w, 1.0, 1e-9);  // the far plane
}

}  // namespace
