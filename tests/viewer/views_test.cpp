// Several views in the viewer (issue 17): the layouts' rectangles, which view the mouse acts on,
// the swipe divider's drag, and "linked views share camera and time after any interaction": orbit,
// look, zoom and fly in any view, a time change in any view, and unlinked views that do not follow.
#include <gtest/gtest.h>

#include <random>

#include "scene/scene_json.hpp"
#include "viewer/camera_controller.hpp"
#include "viewer/viewer_state.hpp"
#include "viewer/views.hpp"

namespace {
using namespace cv;
using viewer::ViewLayout;
using viewer::ViewRect;

constexpr double kR0 = 6371000.0;

TEST(Views, ParsesLayouts) {
  EXPECT_TRUE(viewer::parse_view_layout("grid") == ViewLayout::Grid);
  EXPECT_TRUE(viewer::parse_view_layout("swipe") == ViewLayout::Swipe);
  EXPECT_FALSE(viewer::parse_view_layout("tiles"));
  EXPECT_STREQ(viewer::view_layout_name(ViewLayout::Swipe), "swipe");
}

TEST(Views, GridAndSwipeRectanglesCoverTheWindowOnce) {
  // Odd sizes: the halves differ by a pixel and nothing is lost or drawn twice.
  const int W = 641, H = 361;
  for (int n : {1, 2, 3, 4}) {
    const auto r = viewer::view_rects(ViewLayout::Grid, n, W, H);
    ASSERT_EQ(static_cast<int>(r.size()), n);
    long area = 0;
    for (const ViewRect& v : r) area += long(v.w) * v.h;
    EXPECT_EQ(area, n == 3 ? long(W) * H - long(W - W / 2) * (H - H / 2) : long(W) * H) << n << " views";
    for (int y = 0; y < H; y += 7) {
      for (int x = 0; x < W; x += 7) {
        int hits = 0;
        for (const ViewRect& v : r) hits += v.contains(x, y) ? 1 : 0;
        EXPECT_LE(hits, 1);
      }
    }
  }
  EXPECT_EQ(viewer::view_rects(ViewLayout::Grid, 2, W, H)[1], (ViewRect{320, 0, 321, 361}));
  EXPECT_EQ(viewer::view_rects(ViewLayout::Grid, 4, W, H)[3], (ViewRect{320, 180, 321, 181}));
  // Swipe: both views are the whole window; each shows its side of the divider.
  const auto s = viewer::view_rects(ViewLayout::Swipe, 2, W, H);
  EXPECT_EQ(s[0], (ViewRect{0, 0, W, H}));
  EXPECT_EQ(s[1], (ViewRect{0, 0, W, H}));
  EXPECT_EQ(viewer::visible_rect(ViewLayout::Swipe, 2, 0, W, H, 0.25), (ViewRect{0, 0, 160, H}));
  EXPECT_EQ(viewer::visible_rect(ViewLayout::Swipe, 2, 1, W, H, 0.25), (ViewRect{160, 0, W - 160, H}));
  EXPECT_EQ(viewer::visible_rect(ViewLayout::Swipe, 2, 1, W, H, 1.0).w, 0);
}

TEST(Views, MouseGoesToTheViewUnderItAndDragsStayWithTheirView) {
  const int W = 640, H = 360;
  double divider = 0.5;
  viewer::MouseRouter m;
  // Grid of four: the view under the cursor.
  EXPECT_EQ(m.route(ViewLayout::Grid, 4, W, H, divider, 10, 10, false, false), 0);
  EXPECT_EQ(m.route(ViewLayout::Grid, 4, W, H, divider, 630, 10, false, false), 1);
  EXPECT_EQ(m.route(ViewLayout::Grid, 4, W, H, divider, 10, 350, false, false), 2);
  EXPECT_EQ(m.route(ViewLayout::Grid, 4, W, H, divider, 630, 350, false, false), 3);
  EXPECT_EQ(m.route(ViewLayout::Grid, 4, W, H, divider, -1, 10, false, false), -1);
  // A drag that starts in view 1 and crosses into view 3 stays with view 1 until released.
  EXPECT_EQ(m.route(ViewLayout::Grid, 4, W, H, divider, 600, 100, true, true), 1);
  EXPECT_EQ(m.route(ViewLayout::Grid, 4, W, H, divider, 600, 300, false, true), 1);
  EXPECT_EQ(m.route(ViewLayout::Grid, 4, W, H, divider, 600, 300, false, false), 3);
  // Swipe: the side of the divider; a press on the divider drags it, and no view moves meanwhile.
  EXPECT_EQ(m.route(ViewLayout::Swipe, 2, W, H, divider, 100, 100, false, false), 0);
  EXPECT_EQ(m.route(ViewLayout::Swipe, 2, W, H, divider, 500, 100, false, false), 1);
  EXPECT_EQ(m.route(ViewLayout::Swipe, 2, W, H, divider, 322, 100, true, true), -1);
  EXPECT_TRUE(m.dragging_divider);
  EXPECT_EQ(m.route(ViewLayout::Swipe, 2, W, H, divider, 160, 120, false, true), -1);
  EXPECT_DOUBLE_EQ(divider, 0.25);
  EXPECT_EQ(m.route(ViewLayout::Swipe, 2, W, H, divider, 900, 120, false, true), -1);
  EXPECT_DOUBLE_EQ(divider, 1.0);  // held within the window
  EXPECT_EQ(m.route(ViewLayout::Swipe, 2, W, H, divider, 200, 120, false, true), -1);
  EXPECT_EQ(m.route(ViewLayout::Swipe, 2, W, H, divider, 200, 120, false, false), 1);  // released at 0.3125: right of it is view 1
  EXPECT_FALSE(m.dragging_divider);
  EXPECT_EQ(m.route(ViewLayout::Swipe, 2, W, H, divider, 100, 120, false, false), 0);
}

viewer::ViewCursor cursor(int w, int h, double t, double first, double last, bool utc = true) {
  viewer::ViewCursor c;
  c.camera.lat_deg = 45.0, c.camera.lon_deg = 185.0, c.camera.alt_m = 2.0e6, c.camera.heading_deg = 10.0, c.camera.pitch_deg = -40.0;
  c.camera.width = w, c.camera.height = h;
  c.t = t, c.t_first = first, c.t_last = last, c.utc = utc;
  return c;
}

void expect_same_camera(const viewer::LinkedViews& v) {
  for (std::size_t k = 1; k < v.views.size(); ++k) {
    const core::Camera &a = v.views[0].camera, &b = v.views[k].camera;
    EXPECT_EQ(a.lat_deg, b.lat_deg) << "view " << k;
    EXPECT_EQ(a.lon_deg, b.lon_deg) << "view " << k;
    EXPECT_EQ(a.alt_m, b.alt_m) << "view " << k;
    EXPECT_EQ(a.heading_deg, b.heading_deg) << "view " << k;
    EXPECT_EQ(a.pitch_deg, b.pitch_deg) << "view " << k;
    EXPECT_EQ(a.fov_deg, b.fov_deg) << "view " << k;
  }
}

TEST(Views, LinkedViewsShareCameraAndTimeAfterAnyInteraction) {
  // Four views of a grid: each with its own pixel size, all at one instant of a 0..48 h span.
  const double t0 = 1705276800.0;  // 2024-01-15T00:00:00Z
  viewer::LinkedViews v;
  for (int i = 0; i < 4; ++i) v.views.push_back(cursor(160 + i, 90 + i, t0 + 3 * 3600.0, t0, t0 + 48 * 3600.0));
  std::mt19937 rng(17);
  std::uniform_int_distribution<int> pick(0, 3), what(0, 4);
  std::uniform_real_distribution<double> px(-40.0, 40.0);
  for (int step = 0; step < 200; ++step) {
    v.begin();
    const int i = pick(rng);
    core::Camera& c = v.views[static_cast<std::size_t>(i)].camera;
    switch (what(rng)) {
      case 0: viewer::orbit(c, px(rng), px(rng), kR0); break;
      case 1: viewer::zoom(c, px(rng) / 20.0, kR0); break;
      case 2: viewer::look(c, px(rng), px(rng)); break;
      case 3: viewer::fly(c, {1.0, 0.5, -0.2}, 0.1, kR0); break;
      default: v.views[static_cast<std::size_t>(i)].t += 900.0 * (px(rng) > 0.0 ? 1 : -1); break;  // a scrub or a step
    }
    v.sync();
    expect_same_camera(v);
    for (int k = 0; k < 4; ++k) {
      EXPECT_EQ(v.views[static_cast<std::size_t>(k)].t, v.views[0].t) << "step " << step << ", view " << k;
      EXPECT_EQ(v.views[static_cast<std::size_t>(k)].camera.width, 160 + k);  // each keeps its pixel size
    }
    if (::testing::Test::HasFailure()) return;
  }
  EXPECT_NE(v.views[0].camera.lat_deg, 45.0);  // the interactions did move the cameras
}

TEST(Views, LinkedTimeKeepsTheDifferenceOfOneSourceAtTwoTimesWithinEachSpan) {
  const double t0 = 1705276800.0;
  viewer::LinkedViews v;
  v.views = {cursor(64, 36, t0, t0, t0 + 24 * 3600.0), cursor(64, 36, t0 + 6 * 3600.0, t0, t0 + 24 * 3600.0)};
  v.begin();
  v.views[1].t += 3600.0;  // view 1 scrubbed an hour on
  EXPECT_EQ(v.sync(), (std::vector<bool>{true, false}));
  EXPECT_EQ(v.views[0].t, t0 + 3600.0);
  v.begin();
  v.views[0].t = t0 + 20 * 3600.0;  // view 0 to 20 h: view 1 would pass its last step and stops there
  v.sync();
  EXPECT_EQ(v.views[1].t, t0 + 24 * 3600.0);
  // A view without UTC times (steps by index) does not follow UTC times, nor they it.
  v.views.push_back(cursor(64, 36, 2.0, 0.0, 5.0, false));
  v.begin();
  v.views[0].t -= 3600.0;
  v.sync();
  EXPECT_EQ(v.views[2].t, 2.0);
  v.begin();
  v.views[2].t = 3.0;
  v.sync();
  EXPECT_EQ(v.views[0].t, t0 + 19 * 3600.0);
}

TEST(Views, UnlinkedViewsDoNotFollow) {
  const double t0 = 1705276800.0;
  viewer::LinkedViews v;
  v.views = {cursor(64, 36, t0, t0, t0 + 86400.0), cursor(64, 36, t0, t0, t0 + 86400.0)};
  v.link_camera = false;
  v.begin();
  viewer::orbit(v.views[1].camera, 30.0, -12.0, kR0);
  viewer::zoom(v.views[1].camera, 2.0, kR0);
  v.views[1].t += 7200.0;
  EXPECT_EQ(v.sync(), (std::vector<bool>{true, false}));  // the time is still linked: view 0 follows it
  EXPECT_EQ(v.views[0].camera.lat_deg, 45.0);
  EXPECT_EQ(v.views[0].camera.alt_m, 2.0e6);
  EXPECT_NE(v.views[1].camera.alt_m, 2.0e6);
  EXPECT_EQ(v.views[0].t, t0 + 7200.0);
  v.link_time = false;
  const core::Camera cam1 = v.views[1].camera;
  v.begin();
  v.views[0].t += 3600.0;
  viewer::look(v.views[0].camera, 20.0, 5.0);
  EXPECT_EQ(v.sync(), (std::vector<bool>{false, false}));
  EXPECT_EQ(v.views[1].t, t0 + 7200.0);
  EXPECT_TRUE(viewer::same_view_camera(v.views[1].camera, cam1));
  EXPECT_FALSE(viewer::same_view_camera(v.views[0].camera, cam1));
  // Linked again: the next interaction brings the other view to the one moved.
  v.link_camera = v.link_time = true;
  v.begin();
  viewer::zoom(v.views[0].camera, 1.0, kR0);
  v.sync();
  expect_same_camera(v);
}

// The "Scene file" panel saves the open views; the scene file read back holds them, and with one
// view open it holds none.
TEST(Views, ASavedSceneKeepsTheOpenViews) {
  viewer::ViewerState s;
  s.scene.data.path = "/data/a.nc";
  EXPECT_FALSE(viewer::scene_to_save(s).views) << "one view: no views entry";
  s.views.sources = {{"", "2024-01-15T06:00:00Z"}, {"/data/b.nc", "3"}};
  s.views.layout = ViewLayout::Grid;
  s.views.link_camera = true, s.views.link_time = false;  // linked only when both are
  const core::Scene saved = core::scene_from_json(core::scene_to_json(viewer::scene_to_save(s)), "saved.json");
  ASSERT_TRUE(saved.views);
  EXPECT_EQ(saved.views->layout, "grid");
  EXPECT_FALSE(saved.views->linked);
  ASSERT_EQ(saved.views->compare.size(), 2u);
  EXPECT_EQ(saved.views->compare[0].path, "");
  EXPECT_EQ(saved.views->compare[0].time, "2024-01-15T06:00:00Z");
  EXPECT_EQ(saved.views->compare[1].path, "/data/b.nc");
  EXPECT_EQ(saved.views->compare[1].time, "3");
  s.views.sources.resize(1);
  s.views.layout = ViewLayout::Swipe;
  s.views.divider = 0.25;
  s.views.link_time = true;
  const core::Scene swipe = core::scene_from_json(core::scene_to_json(viewer::scene_to_save(s)), "swipe.json");
  EXPECT_EQ(swipe.views->layout, "swipe");
  EXPECT_TRUE(swipe.views->linked);
  EXPECT_EQ(swipe.views->divider, 0.25);
}

}  // namespace
