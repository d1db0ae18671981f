// Overlay data in core: the parameter table against docs/scene.md, the CPU cast of overlay
// primitives (the CPU reference's opaque layer), the projection of a point onto its pixel and the
// sphere's occlusion.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <string>

#include <glm/glm.hpp>

#include "frame/camera.hpp"
#include "geo/geodesy.hpp"
#include "geometry/overlay_mesh.hpp"
#include "settings/overlay_settings.hpp"

namespace {
using namespace cv::core;
constexpr double kR0 = 6371000.0;

TEST(OverlayTable, DocsSceneMdDocumentsEveryParameter) {
  std::ifstream in(std::string(CV_SOURCE_DIR) + "/docs/scene.md");
  ASSERT_TRUE(in);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (const OverlayParamRow& row : overlay_param_rows()) {
    const std::string key = std::string("| `overlays.") + row.overlay + "." + row.key + "` |";
    EXPECT_NE(text.find(key), std::string::npos) << "docs/scene.md has no entry " << key << " (" << row.doc << ")";
  }
}

// The camera at 2 km over (0, 0) looking straight up; a square plane 600 m above it, two triangles.
struct PlaneAbove {
  Camera cam;
  OverlayMesh mesh;
  glm::dvec3 up{1.0, 0.0, 0.0};
  double height_m = 600.0;
  PlaneAbove() {
    cam.alt_m = 2000.0, cam.pitch_deg = 90.0, cam.fov_deg = 30.0, cam.width = 9, cam.height = 9;
    const glm::dvec3 c = camera_ecef(cam, kR0) + height_m * up;
    const double s = 2000.0;  // half the side: wider than the view (30 degrees over 600 m: 161 m)
    mesh.positions = {c + glm::dvec3(0, -s, -s), c + glm::dvec3(0, s, -s), c + glm::dvec3(0, s, s), c + glm::dvec3(0, -s, s)};
    mesh.colors.assign(4, glm::vec4(0.5f, 0.25f, 0.125f, 1.0f));
    mesh.triangles = {0, 1, 2, 0, 2, 3};
  }
};

TEST(OverlayCast, TrianglesGiveTheExactDistanceAlongEachRay) {
  const PlaneAbove p;
  const OpaqueLayer layer = cast_overlay(p.mesh, p.cam, kR0);
  ASSERT_EQ(layer.distance_m.size(), 81u);
  for (int y = 0; y < 9; ++y) {
    for (int x = 0; x < 9; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * 9 + x;
      const double expected = p.height_m / glm::dot(camera_ray(p.cam, x, y), p.up);
      EXPECT_NEAR(layer.distance_m[i], expected, 1e-4) << "pixel " << x << ", " << y;
      EXPECT_EQ(layer.radiance_rgba[4 * i + 0], 0.5f);
      EXPECT_EQ(layer.radiance_rgba[4 * i + 2], 0.125f);
    }
  }
}

TEST(OverlayCast, NearestPrimitiveWinsAndEmptyPixelsStayZero) {
  PlaneAbove p;
  OverlayMesh nearer = p.mesh;
  for (auto& v : nearer.positions) v -= 300.0 * p.up;  // 300 m above the camera
  for (auto& c : nearer.colors) c = glm::vec4(1.0f, 0.0f, 0.0f, 1.0f);
  nearer.triangles = {0, 1, 2};  // half of the view only
  p.mesh.append(nearer);
  const OpaqueLayer layer = cast_overlay(p.mesh, p.cam, kR0);
  int near_count = 0;
  for (std::size_t i = 0; i < 81; ++i) {
    const double d = layer.distance_m[i];
    const double cos_up = glm::dot(camera_ray(p.cam, static_cast<int>(i % 9), static_cast<int>(i / 9)), p.up);
    const bool is_near = std::abs(d - 300.0 / cos_up) < 1e-4;
    EXPECT_TRUE(is_near || std::abs(d - 600.0 / cos_up) < 1e-4) << i;
    if (is_near) {
      ++near_count;
      EXPECT_EQ(layer.radiance_rgba[4 * i], 1.0f);
    }
  }
  EXPECT_GT(near_count, 20);
  EXPECT_LT(near_count, 61);
  // Nothing in view: every distance 0 (none), every radiance 0.
  Camera down = p.cam;
  down.pitch_deg = -90.0;
  const OpaqueLayer none = cast_overlay(p.mesh, down, kR0);
  for (float d : none.distance_m) EXPECT_EQ(d, 0.0f);
}

// Instances: each puts the glyph at origin + g.x axis_x + g.y axis_y + g.z axis_z with its own
// colour (alpha 1); the cast of an instanced mesh is the cast of the same triangles given plainly.
TEST(OverlayCast, InstancesAreCastAsTheirExpandedGlyphs) {
  PlaneAbove p;
  OverlayMesh inst;
  OverlayInstances& in = inst.instances;
  in.glyph_positions = {{0.0f, -1.0f, -1.0f}, {0.0f, 1.0f, -1.0f}, {0.0f, 1.0f, 1.0f}, {0.0f, -1.0f, 1.0f}};
  in.glyph_triangles = {0, 1, 2, 0, 2, 3};
  const glm::dvec3 c = camera_ecef(p.cam, kR0);
  // Two squares: 300 m above the camera and 100 m across, and 600 m above it and 4 km across.
  in.origins = {c + 300.0 * p.up, c + 600.0 * p.up};
  in.axis_x = {glm::vec3(1.0f, 0.0f, 0.0f), glm::vec3(1.0f, 0.0f, 0.0f)};
  in.axis_y = {glm::vec3(0.0f, 50.0f, 0.0f), glm::vec3(0.0f, 2000.0f, 0.0f)};
  in.axis_z = {glm::vec3(0.0f, 0.0f, 50.0f), glm::vec3(0.0f, 0.0f, 2000.0f)};
  in.colors = {glm::vec4(1.0f, 0.0f, 0.0f, 0.25f), glm::vec4(0.5f, 0.25f, 0.125f, 1.0f)};
  ASSERT_FALSE(inst.empty());
  const OverlayMesh plain = expand_instances(inst);
  EXPECT_TRUE(plain.instances.empty());
  ASSERT_EQ(plain.positions.size(), 8u);
  ASSERT_EQ(plain.triangles.size(), 12u);
  EXPECT_EQ(plain.positions[2], c + 300.0 * p.up + glm::dvec3(0.0, 50.0, 50.0));
  EXPECT_EQ(plain.positions[4], c + 600.0 * p.up + glm::dvec3(0.0, -2000.0, -2000.0));
  EXPECT_EQ(plain.colors[0], glm::vec4(1.0f, 0.0f, 0.0f, 1.0f));  // opaque whatever the alpha given
  EXPECT_EQ(plain.triangles[6], 4u);
  const OpaqueLayer a = cast_overlay(inst, p.cam, kR0), b = cast_overlay(plain, p.cam, kR0);
  EXPECT_EQ(a.distance_m, b.distance_m);
  EXPECT_EQ(a.radiance_rgba, b.radiance_rgba);
  int near = 0;
  for (std::size_t i = 0; i < 81; ++i) {
    const double cos_up = glm::dot(camera_ray(p.cam, static_cast<int>(i % 9), static_cast<int>(i / 9)), p.up);
    near += std::abs(a.distance_m[i] - 300.0 / cos_up) < 1e-4 ? 1 : 0;
  }
  EXPECT_GT(near, 0);   // the small square covers the middle of the view...
  EXPECT_LT(near, 81);  // ...and the large one the rest
  // Appending joins instances of the same glyph, and expands those of another.
  OverlayMesh joined = inst;
  joined.append(inst);
  EXPECT_EQ(joined.instances.count(), 4u);
  EXPECT_TRUE(joined.positions.empty());
  OverlayMesh other = inst;
  other.instances.glyph_triangles = {0, 1, 2};
  joined.append(other);
  EXPECT_EQ(joined.instances.count(), 4u);
  EXPECT_EQ(joined.positions.size(), 8u);
  EXPECT_EQ(joined.triangles.size(), 6u);
}

TEST(OverlayCast, APointProjectsOntoThePixelWhoseRayPassesThroughIt) {
  Camera cam;
  cam.lat_deg = 64.0, cam.lon_deg = -20.0, cam.alt_m = 100.0, cam.heading_deg = 37.0, cam.pitch_deg = -4.0;
  cam.width = 32, cam.height = 18;
  for (int py : {0, 7, 17}) {
    for (int px : {0, 13, 31}) {
      const Projected q = project_point(cam, 1234.5 * camera_ray(cam, px, py));
      ASSERT_TRUE(q.in_front);
      EXPECT_NEAR(q.x, px + 0.5, 1e-9);
      EXPECT_NEAR(q.y, py + 0.5, 1e-9);
      EXPECT_NEAR(q.distance_m, 1234.5, 1e-6);
    }
  }
}

TEST(OverlayCast, TheSphereHidesItsFarSideOnly) {
  Camera cam;
  cam.alt_m = 400000.0;
  const glm::dvec3 c = camera_ecef(cam, kR0);
  const glm::dvec3 near_side = cv::geo::sphere_to_ecef({10.0, 5.0, 0.0}, kR0);
  const glm::dvec3 far_side = cv::geo::sphere_to_ecef({0.0, 150.0, 0.0}, kR0);
  EXPECT_FALSE(hidden_by_sphere(c, near_side - c, kR0));
  EXPECT_TRUE(hidden_by_sphere(c, far_side - c, kR0));
  // A point 1 km above the far side's horizon... still behind the Earth from 400 km.
  EXPECT_TRUE(hidden_by_sphere(c, cv::geo::sphere_to_ecef({0.0, 90.0, 1000.0}, kR0) - c, kR0));
}

}  // namespace
