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
