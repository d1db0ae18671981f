// The viewer's temporal reprojection (issue 18, item 4; render/reprojector): 1/16 of the pixels
// marched per frame, the rest reprojected from the previous image.
// - A still camera: after 16 frames every pixel has been marched once, and the image is the full
//   march's.
// - A moving camera (the orbit sequence) and the ghosting scene (a fast pan over the cumulus field's
//   bright edges against the dark sea): each reprojected frame against the fully marched frame of
//   the same camera, mean and 99th percentile of |dL| / the first frame's brightest, printed; the history
//   must beat the new samples' blend alone, and the clamp must cut the ghosts.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <vector>

#include "bench/standard_scenes.hpp"
#include "render/context.hpp"
#include "render/frame_renderer.hpp"
#include "render/gl.hpp"
#include "render/reprojector.hpp"
#include "support/reprojection_sequence.hpp"
#include "volume/time_interpolation.hpp"

namespace {
using namespace cv;
using cv::test_support::Errors;
using cv::test_support::Mode;

core::FrameSpec base_of(const bench::StandardScene& sc) {
  core::FrameSpec f;
  f.camera = f.march_camera = sc.camera;
  f.sun = sc.sun;
  f.march = sc.march;
  return f;
}

class Reprojection : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { ctx_ = render::make_headless_context().release(); }
  static void TearDownTestSuite() {
    delete ctx_;
    ctx_ = nullptr;
  }
  static render::GlContext* ctx_;
  render::ShaderLoader loader_{{CV_SHADER_DIR}};
};
render::GlContext* Reprojection::ctx_ = nullptr;

TEST_F(Reprojection, AStillCameraConvergesToTheFullMarchIn16Frames) {
  const bench::StandardScene sc = bench::standard_scene("cumulus_field", 64, 36);
  render::FrameRenderer fr(loader_);
  fr.use_volume(std::make_shared<const core::PreparedVolume>(core::prepare_volume(sc.grid, sc.data)));
  render::Reprojector rp(loader_);
  // Frame k marched; after 16 every pixel was marched once with its own ray.
  const Errors e = test_support::run_sequence(fr, rp, base_of(sc), sc.grid.earth_radius_m, 16, 15, [](core::Camera&) {}, Mode::Reproject);
  double worst = 0.0;
  for (double x : e.all) worst = std::max(worst, x);
  std::printf("still camera, 16 frames: worst |dL| %.2e of the brightest\n", worst);
  ASSERT_EQ(e.all.size(), 64u * 36u);
  // The sparse ray and the full ray of a pixel differ only by float rounding of its position.
  EXPECT_LT(worst, 1e-3);
  EXPECT_TRUE(rp.complete());
}

// A still view after its first pass: pass c marches each pixel once more as accumulation frame c
// (jittered steps, rays spread over the pixel by anti-aliasing) and averages it in, so after C passes
// the image is `render --accumulate C`'s. Passes start again at 0 when the camera moves.
TEST_F(Reprojection, AStillViewRefinesToTheAntiAliasedAccumulation) {
  const bench::StandardScene sc = bench::standard_scene("cumulus_field", 64, 36);
  render::FrameRenderer fr(loader_);
  fr.use_volume(std::make_shared<const core::PreparedVolume>(core::prepare_volume(sc.grid, sc.data)));
  render::Reprojector rp(loader_);
  core::FrameSpec full = base_of(sc);
  full.accumulate = 1;
  const int w = full.camera.width, h = full.camera.height, passes = 4;
  GLuint out = 0;
  glCreateTextures(GL_TEXTURE_2D, 1, &out);
  glTextureStorage2D(out, 1, GL_RGBA32F, w, h);
  for (int k = 0; k < 16 * passes; ++k) {
    const int cycle = rp.next_cycle(full.march_camera, false);
    ASSERT_EQ(cycle, k / 16) << k;
    core::FrameSpec sparse = full;
    sparse.march.per_frame.frame = cycle;
    sparse.march_camera = render::Reprojector::sparse_camera(full.march_camera, k);
    fr.march_into(rp.sparse_target(full.march_camera), sparse, 0);
    rp.resolve(fr.raymarcher().cloud_depth_texture(), full.march_camera, k, false, sc.grid.earth_radius_m, out, fr.volume());
  }
  const std::vector<glm::vec4> got = test_support::read_rgba(out, w, h);
  glDeleteTextures(1, &out);
  core::FrameSpec acc = full;
  acc.accumulate = passes;
  const std::vector<glm::vec4> want = fr.render(acc);
  const std::vector<glm::vec4> first = fr.render(full);
  double peak = 0.0, worst = 0.0, moved = 0.0;
  for (const glm::vec4& c : want) peak = std::max(peak, test_support::luminance(c));
  ASSERT_GT(peak, 0.0);
  for (std::size_t i = 0; i < want.size(); ++i) {
    worst = std::max(worst, std::abs(test_support::luminance(got[i]) - test_support::luminance(want[i])) / peak);
    moved = std::max(moved, std::abs(test_support::luminance(first[i]) - test_support::luminance(want[i])) / peak);
  }
  std::printf("a still view after %d passes against render --accumulate %d: worst |dL| %.2e of the brightest (one frame "
              "differs by up to %.2e)\n", passes, passes, worst, moved);
  EXPECT_LT(worst, 1e-3);
  EXPECT_GT(moved, 1e-2) << "the passes after the first add what a single frame lacks";
  core::Camera turned = full.march_camera;
  turned.heading_deg += 1.0;
  EXPECT_EQ(rp.next_cycle(turned, false), 0) << "a moved camera starts again";
  EXPECT_EQ(rp.next_cycle(full.march_camera, true), 0) << "so does a changed medium";
  EXPECT_EQ(rp.next_cycle(full.march_camera, false), passes);
}

TEST_F(Reprojection, MovingCameraErrorsAgainstFullFrames) {
  const bench::StandardScene sc = bench::standard_scene("cumulus_field", 96, 56);
  render::FrameRenderer fr(loader_);
  fr.use_volume(std::make_shared<const core::PreparedVolume>(core::prepare_volume(sc.grid, sc.data)));
  render::Reprojector rp(loader_);
  // The orbit sequence: the camera moves along the ground and turns, as an orbit drag does.
  auto orbit = [](core::Camera& c) {
    c.lon_deg += 0.01;
    c.heading_deg += 0.3;
  };
  // A pan (2 degrees a frame, 3 pixels at this size): a turn reprojects exactly, unclamped.
  auto pan = [](core::Camera& c) { c.heading_deg += 2.0; };
  const int frames = 24, skip = 16;  // measured once the history has filled
  struct Row {
    const char* name;
    std::function<void(core::Camera&)> step;
  };
  for (const Row& row : {Row{"orbit", orbit}, Row{"pan", pan}}) {
    const Errors rep = test_support::run_sequence(fr, rp, base_of(sc), sc.grid.earth_radius_m, frames, skip, row.step, Mode::Reproject);
    const Errors raw = test_support::run_sequence(fr, rp, base_of(sc), sc.grid.earth_radius_m, frames, skip, row.step, Mode::NoClamp);
    const Errors spatial = test_support::run_sequence(fr, rp, base_of(sc), sc.grid.earth_radius_m, frames, skip, row.step, Mode::SpatialOnly);
    std::printf("%s, cumulus_field 96x56, frames %d-%d against full marches (|dL| / brightest): reprojected mean %.4f p99 %.4f; "
                "without the clamp mean %.4f p99 %.4f; the new samples' blend alone mean %.4f p99 %.4f\n",
                row.name, skip, frames - 1, rep.mean(), rep.p99(), raw.mean(), raw.p99(), spatial.mean(), spatial.p99());
    EXPECT_LT(rep.mean(), spatial.mean()) << row.name << ": the history must add what 1/16 of the pixels cannot";
    EXPECT_LE(rep.mean(), raw.mean() * 1.0001) << row.name << ": the clamp must not make the frames worse";
  }
}

// The ghosting scene: the cumulus field for 16 frames of a still camera, then the clouds gone (a
// clear sky: a forecast step without them). Unclamped, each pixel keeps the old cloud until its
// turn comes in the next 16 frames; the clamp to the new samples' range removes the ghost at once.
TEST_F(Reprojection, TheClampRemovesTheGhostOfAVanishedCloud) {
  const bench::StandardScene sc = bench::standard_scene("cumulus_field", 96, 56);
  render::FrameRenderer fr(loader_);
  const auto cloudy = std::make_shared<const core::PreparedVolume>(core::prepare_volume(sc.grid, sc.data));
  core::GridMeanExtinction none = core::grid_mean_extinction(sc.grid, sc.data);
  std::fill(none.liquid_per_m.begin(), none.liquid_per_m.end(), 0.0f);
  std::fill(none.ice_per_m.begin(), none.ice_per_m.end(), 0.0f);
  const auto clear = std::make_shared<const core::PreparedVolume>(core::prepare_volume(sc.grid, std::move(none)));
  render::Reprojector rp(loader_);
  auto before = [&](int k) {
    fr.use_volume(k < 16 ? cloudy : clear);
    return k == 16;
  };
  const int frames = 20, skip = 16;
  const Errors rep = test_support::run_sequence(fr, rp, base_of(sc), sc.grid.earth_radius_m, frames, skip, [](core::Camera&) {}, Mode::Reproject, before);
  const Errors raw = test_support::run_sequence(fr, rp, base_of(sc), sc.grid.earth_radius_m, frames, skip, [](core::Camera&) {}, Mode::NoClamp, before);
  std::printf("ghosting (the cloud vanishes under a still camera), cumulus_field 96x56, the 4 frames after: clamped mean %.4f "
              "p99 %.4f; unclamped mean %.4f p99 %.4f\n", rep.mean(), rep.p99(), raw.mean(), raw.p99());
  EXPECT_LT(rep.mean(), 0.25 * raw.mean()) << "the clamp removes most of the ghost";
  EXPECT_LT(rep.p99(), raw.p99());
}

// The wind's motion (the modelled cloud in an animation): the deck's sub-grid detail carried
// east-north-east by the wind, 0.01 and 0.005 of a cell a frame (28 and 14 m, about 1.8 and 0.9
// pixels), under a still camera looking straight down from 4 km (2.6 km above the deck's top), one
// tile per cell. Each frame's medium is a new instant, so the clamp holds
// throughout; the history looked up where the wind held each point must beat the history looked up
// where the point is now (the camera's motion alone), and the motion must be found from the media.
TEST_F(Reprojection, TheWindCarriesTheHistoryWithTheDetail) {
  bench::StandardScene sc = bench::standard_scene("stratocumulus", 192, 112);
  sc.camera.lat_deg = 0.0, sc.camera.lon_deg = 0.0, sc.camera.alt_m = 4000.0;
  sc.camera.heading_deg = 0.0, sc.camera.pitch_deg = -90.0, sc.camera.fov_deg = 60.0;
  sc.march.medium.modelled = true;
  sc.march.medium.detail_scale_m = 2800.0;
  const core::PreparedVolume still = core::prepare_volume(sc.grid, core::grid_mean_extinction(sc.grid, sc.data));
  const double east = 0.01, north = 0.005;  // grid cells a frame
  std::vector<std::shared_ptr<const core::PreparedVolume>> instants;
  for (int k = 0; k < 24; ++k) {
    core::PreparedVolume v = still;
    for (int z = 0; z < sc.grid.alt_m.count; ++z) {
      v.extinction.detail_drift_cells.push_back(east * k);
      v.extinction.detail_drift_cells.push_back(north * k);
    }
    instants.push_back(std::make_shared<const core::PreparedVolume>(std::move(v)));
  }
  // The motion the reprojector finds between two instants: the drift's difference times the steps.
  const std::vector<float> m = render::Reprojector::wind_motion_deg(instants[3]->grid, instants[3]->extinction.detail_drift_cells,
                                                                     instants[4]->grid, instants[4]->extinction.detail_drift_cells);
  ASSERT_EQ(m.size(), 2u * std::size_t(sc.grid.alt_m.count));
  EXPECT_NEAR(m[0], east * sc.grid.lon_deg.step, 1e-7);
  EXPECT_NEAR(m[1], north * sc.grid.lat_deg.step, 1e-7);
  EXPECT_TRUE(render::Reprojector::wind_motion_deg(still.grid, still.extinction.detail_drift_cells, still.grid,
                                                   still.extinction.detail_drift_cells).empty()) << "no drift: no motion";

  render::FrameRenderer fr(loader_);
  render::Reprojector rp(loader_);
  auto before = [&](int k) {
    fr.use_volume(instants[static_cast<std::size_t>(k)]);
    return k > 0;
  };
  const int frames = 24, skip = 16;
  const Errors wind = test_support::run_sequence(fr, rp, base_of(sc), sc.grid.earth_radius_m, frames, skip, [](core::Camera&) {}, Mode::Reproject, before);
  EXPECT_TRUE(rp.wind_moved()) << "the last frame's history moved with the wind";
  const Errors still_history =
      test_support::run_sequence(fr, rp, base_of(sc), sc.grid.earth_radius_m, frames, skip, [](core::Camera&) {}, Mode::NoWind, before);
  const Errors spatial =
      test_support::run_sequence(fr, rp, base_of(sc), sc.grid.earth_radius_m, frames, skip, [](core::Camera&) {}, Mode::SpatialOnly, before);
  std::printf("wind (the modelled deck's detail, 0.01 and 0.005 cells a frame east and north, still camera 4 km up), stratocumulus "
              "192x112, frames %d-%d against full marches (|dL| / brightest): history moved with the wind mean %.4f p99 %.4f; history "
              "where the point is now mean %.4f p99 %.4f; the new samples' blend alone mean %.4f p99 %.4f\n",
              skip, frames - 1, wind.mean(), wind.p99(), still_history.mean(), still_history.p99(), spatial.mean(), spatial.p99());
  EXPECT_LT(wind.mean(), 0.85 * still_history.mean()) << "the wind's motion must bring the history to where the detail went";
  EXPECT_LT(wind.mean(), spatial.mean()) << "and the moved history must add to the new samples";
}

// The data mode while an advected forecast plays: the deck carried by a uniform wind (4.8 m/s east,
// 2.4 m/s north; 720 and 360 m a frame, about 1.2 and 0.6 pixels) between two steps an hour apart,
// each frame a new instant of the semi-Lagrangian interpolation (core::interpolate_extinction, as the
// viewer's cache makes them), under a still camera 100 km straight up (a cell is about 4.6 pixels).
// The history moved by the medium's flow (core::angular_flow times the time between the frames'
// media) must beat the history looked up where the point is now, and the new samples alone.
TEST_F(Reprojection, TheFlowCarriesTheDataModesHistoryWhileAnAdvectedForecastPlays) {
  bench::StandardScene sc = bench::standard_scene("stratocumulus", 192, 112);
  sc.camera.lat_deg = 0.0, sc.camera.lon_deg = 0.0, sc.camera.alt_m = 100000.0;
  sc.camera.heading_deg = 0.0, sc.camera.pitch_deg = -90.0, sc.camera.fov_deg = 60.0;
  const core::GridMeanExtinction e0 = core::grid_mean_extinction(sc.grid, sc.data);
  core::StepWinds w;
  w.u.assign(sc.grid.points(), 4.8f);
  w.v.assign(sc.grid.points(), 2.4f);
  const double gap_s = 3600.0;
  core::GridMeanExtinction e1 = e0;  // the earlier step carried over the whole gap
  e1.liquid_per_m = core::advect_field(sc.grid, e0.liquid_per_m, w, w, gap_s, 1.0, 0);
  e1.ice_per_m = core::advect_field(sc.grid, e0.ice_per_m, w, w, gap_s, 1.0, 0);
  const int frames = 24, skip = 16;
  std::vector<std::shared_ptr<const core::PreparedVolume>> instants;
  for (int k = 0; k < frames; ++k) {
    const double f = (k + 0.5) / frames;
    core::TimeInterpolationReport report;
    core::PreparedVolume v = core::prepare_volume(
        sc.grid, core::interpolate_extinction(sc.grid, e0, e1, w, w, gap_s, f, core::TimeInterpolation::Advected, &report), false);
    ASSERT_EQ(report.used, core::TimeInterpolation::Advected);
    v.time_s = f * gap_s;
    v.flow = core::angular_flow(sc.grid, w, w, f);
    instants.push_back(std::make_shared<const core::PreparedVolume>(std::move(v)));
  }
  render::FrameRenderer fr(loader_);
  render::Reprojector rp(loader_);
  auto before = [&](int k) {
    fr.use_volume(instants[static_cast<std::size_t>(k)]);
    return k > 0;
  };
  const Errors flow = test_support::run_sequence(fr, rp, base_of(sc), sc.grid.earth_radius_m, frames, skip, [](core::Camera&) {}, Mode::Reproject, before);
  EXPECT_TRUE(rp.wind_moved()) << "the last frame's history moved with the flow";
  const Errors still_history =
      test_support::run_sequence(fr, rp, base_of(sc), sc.grid.earth_radius_m, frames, skip, [](core::Camera&) {}, Mode::NoWind, before);
  const Errors spatial =
      test_support::run_sequence(fr, rp, base_of(sc), sc.grid.earth_radius_m, frames, skip, [](core::Camera&) {}, Mode::SpatialOnly, before);
  std::printf("flow (the data mode's deck advected at 4.8 and 2.4 m/s east and north, 720 and 360 m a frame, still camera "
              "100 km up), stratocumulus 192x112, frames %d-%d against full marches (|dL| / brightest): history moved with the flow "
              "mean %.4f p99 %.4f; history where the point is now mean %.4f p99 %.4f; the new samples' blend alone mean %.4f p99 %.4f\n",
              skip, frames - 1, flow.mean(), flow.p99(), still_history.mean(), still_history.p99(), spatial.mean(), spatial.p99());
  EXPECT_LT(flow.mean(), 0.85 * still_history.mean()) << "the flow must bring the history to where the cloud went";
  EXPECT_LT(flow.mean(), spatial.mean()) << "and the moved history must add to the new samples";
}

TEST_F(Reprojection, SparseCamerasCoverEveryPixelOnce) {
  core::Camera full;
  full.width = 16, full.height = 8;
  std::vector<int> hits(16 * 8, 0);
  for (int k = 0; k < 16; ++k) {
    const core::Camera c = render::Reprojector::sparse_camera(full, k);
    ASSERT_EQ(c.width, 4);
    ASSERT_EQ(c.height, 2);
    for (int j = 0; j < c.height; ++j)
      for (int i = 0; i < c.width; ++i) {
        // The sparse pixel's ray is the full pixel's ray.
        const glm::ivec2 o = render::Reprojector::offset_of(k);
        const int x = 4 * i + o.x, y = 4 * j + o.y;
        ++hits[static_cast<std::size_t>(y * 16 + x)];
        const glm::dvec3 a = core::camera_ray(c, i, j), b = core::camera_ray(full, x, y);
        EXPECT_LT(glm::length(a - b), 1e-12) << k << ": " << i << "," << j;
      }
  }
  for (int h : hits) EXPECT_EQ(h, 1);
}

}  // namespace
