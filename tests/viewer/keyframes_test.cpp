// The viewer's keyframe panel (issue 16): keyframes added at the view and time, deleted,
// reordered, retimed (refused out of order), previewed through the path, drawn on the globe, kept
// by the scene file, and the record command shown.
#include <gtest/gtest.h>
#include <string>
#include <unistd.h>

#include <cmath>
#include <filesystem>

#include <glm/glm.hpp>

#include "geo/geodesy.hpp"
#include "scene/scene_json.hpp"
#include "viewer/keyframes.hpp"

namespace {
using namespace cv;

core::Camera camera_at(double lat, double lon, double alt, double heading = 0.0, double pitch = -30.0) {
  core::Camera c;
  c.lat_deg = lat, c.lon_deg = lon, c.alt_m = alt, c.heading_deg = heading, c.pitch_deg = pitch, c.fov_deg = 50.0;
  return c;
}

TEST(KeyframePanel, AddsDeletesReordersAndRetimes) {
  core::Scene scene;
  viewer::KeyframeEditor ed;
  EXPECT_EQ(viewer::path_problem(scene), "the path has 0 keyframes, expected at least two");
  viewer::add_keyframe(scene, ed, camera_at(10.0, 20.0, 5.0e6), "2024-01-15T00:00:00Z");
  ASSERT_TRUE(scene.path);
  EXPECT_EQ(viewer::path_problem(scene), "the path has 1 keyframe, expected at least two");
  viewer::add_keyframe(scene, ed, camera_at(12.0, 22.0, 1.0e5, 45.0), "2024-01-15T03:00:00Z");
  viewer::add_keyframe(scene, ed, camera_at(13.0, 23.0, 8.0e3, 90.0), "2024-01-15T06:00:00Z", 3.0);
  ASSERT_EQ(scene.path->keyframes.size(), 3u);
  EXPECT_EQ(ed.selected, 2);
  EXPECT_EQ(scene.path->keyframes[1].t_s, 2.0);
  EXPECT_EQ(scene.path->keyframes[2].t_s, 5.0);
  EXPECT_EQ(scene.path->keyframes[2].heading_deg, 90.0);
  EXPECT_EQ(scene.path->keyframes[2].valid_utc, "2024-01-15T06:00:00Z");
  EXPECT_EQ(viewer::path_problem(scene), "");

  // Reorder: the keyframes trade places, the times stay in their slots.
  viewer::move_keyframe(scene, ed, -1);
  EXPECT_EQ(ed.selected, 1);
  EXPECT_EQ(scene.path->keyframes[1].alt_m, 8.0e3);
  EXPECT_EQ(scene.path->keyframes[1].t_s, 2.0);
  EXPECT_EQ(scene.path->keyframes[2].alt_m, 1.0e5);
  EXPECT_EQ(scene.path->keyframes[2].t_s, 5.0);
  viewer::move_keyframe(scene, ed, -5);  // out of range: nothing
  EXPECT_EQ(ed.selected, 1);

  // Retime: between the neighbours only.
  EXPECT_FALSE(viewer::set_keyframe_time(scene, ed, 6.0));
  EXPECT_EQ(ed.message, "keyframe 1: path time 6 s refused, expected a time between its neighbours' (0.000000..5.000000)");
  EXPECT_EQ(scene.path->keyframes[1].t_s, 2.0);
  EXPECT_FALSE(viewer::set_keyframe_time(scene, ed, 0.0));
  EXPECT_TRUE(viewer::set_keyframe_time(scene, ed, 4.5));
  EXPECT_EQ(scene.path->keyframes[1].t_s, 4.5);
  EXPECT_TRUE(ed.message.empty());

  viewer::delete_keyframe(scene, ed);
  ASSERT_EQ(scene.path->keyframes.size(), 2u);
  EXPECT_EQ(scene.path->keyframes[1].alt_m, 1.0e5);
  viewer::delete_keyframe(scene, ed);
  viewer::delete_keyframe(scene, ed);
  EXPECT_FALSE(scene.path);  // the last keyframe takes the path with it
  EXPECT_EQ(ed.selected, -1);
}

TEST(KeyframePanel, PreviewFollowsThePathAndWraps) {
  core::Scene scene;
  scene.width = 320, scene.height = 180;
  viewer::KeyframeEditor ed;
  viewer::add_keyframe(scene, ed, camera_at(10.0, 20.0, 5.0e6), "2024-01-15T00:00:00Z");
  viewer::add_keyframe(scene, ed, camera_at(12.0, 22.0, 1.0e5, 45.0), "2024-01-15T03:00:00Z");
  const core::PathEvaluator path(*scene.path);
  ed.preview_t_s = 0.0;
  // Each keyframe is where the preview shows it, with its weather time.
  auto at0 = viewer::preview_step(scene, ed, 0.0);
  ASSERT_TRUE(at0);
  EXPECT_NEAR(at0->camera->lat_deg, 10.0, 1e-9);
  EXPECT_NEAR(at0->camera->alt_m, 5.0e6, 1e-3);
  EXPECT_EQ(at0->camera->width, 320);
  EXPECT_EQ(at0->time.valid_utc, "2024-01-15T00:00:00Z");
  auto mid = viewer::preview_step(scene, ed, 1.0);
  ASSERT_TRUE(mid);
  EXPECT_EQ(ed.preview_t_s, 1.0);
  EXPECT_EQ(mid->camera->lat_deg, path.at(1.0).camera.lat_deg);
  EXPECT_EQ(mid->time.valid_utc, "2024-01-15T01:30:00Z");
  auto end = viewer::preview_step(scene, ed, 1.0);
  ASSERT_TRUE(end);
  EXPECT_NEAR(end->camera->lon_deg, 22.0, 1e-9);
  EXPECT_EQ(end->time.valid_utc, "2024-01-15T03:00:00Z");
  viewer::preview_step(scene, ed, 0.5);  // past the end: back to the start
  EXPECT_EQ(ed.preview_t_s, 0.0);
  core::Scene one;
  viewer::KeyframeEditor e1;
  viewer::add_keyframe(one, e1, camera_at(0.0, 0.0, 1.0e6), "");
  EXPECT_FALSE(viewer::preview_step(one, e1, 0.1));
}

TEST(KeyframePanel, ThePathIsDrawnWhereTheCameraGoesAndKeptByTheSceneFile) {
  core::Scene scene;
  scene.width = 640, scene.height = 360;
  scene.data.path = "cyclone.nc";
  viewer::KeyframeEditor ed;
  viewer::add_keyframe(scene, ed, camera_at(10.0, 170.0, 5.0e6), "2024-01-15T00:00:00Z");
  viewer::add_keyframe(scene, ed, camera_at(12.0, -170.0, 2.0e4, 45.0), "2024-01-15T03:00:00Z");
  const double r0 = 6371000.0;
  const core::OverlayMesh m = viewer::path_mesh(scene, r0, 0.05);
  const core::PathEvaluator path(*scene.path);
  // 41 track samples (2 s every 0.05 s) joined by 40 segments, and a tick per keyframe.
  ASSERT_EQ(m.positions.size(), 41u + 4u);
  EXPECT_EQ(m.lines.size(), 2u * (40u + 2u));
  for (int k = 0; k <= 40; ++k) {
    const glm::dvec3 expected = core::camera_ecef(path.at(0.05 * k).camera, r0);
    EXPECT_LT(glm::length(m.positions[static_cast<std::size_t>(k)] - expected), 1e-6) << k;
  }
  // The track crosses the date line the short way: no sample far from both keyframes' longitudes.
  for (int k = 0; k <= 40; ++k) {
    const geo::Geodetic g = geo::ecef_to_sphere(m.positions[static_cast<std::size_t>(k)], r0);
    EXPECT_TRUE(g.lon_deg >= 169.9 || g.lon_deg <= -169.9) << k << ": " << g.lon_deg;
  }
  // A keyframe's tick stands from the ground to the camera.
  const geo::Geodetic foot = geo::ecef_to_sphere(m.positions[41], r0), top = geo::ecef_to_sphere(m.positions[42], r0);
  EXPECT_NEAR(foot.alt_m, 0.0, 1e-3);
  EXPECT_NEAR(top.alt_m, 5.0e6, 1e-3);

  EXPECT_EQ(viewer::record_command("scenes/flyover.json", scene),
            "cloudviewer record scenes/flyover.json -o scenes/flyover.mp4 --fps 30 --size 640x360");

  // Saved with the scene file and loaded back, keyframe for keyframe.
  const std::filesystem::path file = std::filesystem::temp_directory_path() / ("keyframe_panel_scene_" + std::to_string(::getpid()) + ".json");
  core::save_scene(scene, file.string());
  const core::Scene back = core::load_scene(file.string());
  std::filesystem::remove(file);
  ASSERT_TRUE(back.path);
  ASSERT_EQ(back.path->keyframes.size(), 2u);
  EXPECT_EQ(back.path->keyframes[1].lon_deg, -170.0);
  EXPECT_EQ(back.path->keyframes[1].heading_deg, 45.0);
  EXPECT_EQ(back.path->keyframes[1].valid_utc, "2024-01-15T03:00:00Z");
  EXPECT_EQ(back.path->keyframes[1].t_s, 2.0);
}

}  // namespace
