// Video frames of a camera path (issue 16) through the one frame renderer: each frame's jitter comes
// from its number, the same frame gives the same image, and on a still camera and still weather
// consecutive frames differ by no more than their own noise estimate (no flicker).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "kernel/volume_cache.hpp"
#include "render/context.hpp"
#include "render/frame_renderer.hpp"
#include "render/shader_loader.hpp"
#include "scene/camera_path.hpp"
#include "scene/quality.hpp"
#include "scene_source.hpp"

namespace {
using namespace cv;

constexpr int kAccumulate = 4;

core::Scene still_scene() {
  core::Scene s;
  core::apply_quality("low", s.render);
  s.data.path = CV_SAMPLE_FILE;
  s.time_step = 1;
  s.width = 48, s.height = 28;
  s.render.accumulate = kAccumulate;
  s.render.auto_exposure = false;
  core::CameraPath p;  // still: the same view at both keyframes, no weather times (the scene's step)
  core::PathKeyframe k;
  k.lat_deg = 38, k.lon_deg = 186, k.alt_m = 120000, k.heading_deg = 10, k.pitch_deg = -25, k.fov_deg = 50;
  p.keyframes = {k, k};
  p.keyframes[1].t_s = 1.0;
  s.path = p;
  return s;
}

double luminance(const glm::vec4& c) { return 0.2126 * c.r + 0.7152 * c.g + 0.0722 * c.b; }

struct Frames {
  core::Scene scene = still_scene();
  core::CloudVolume vol = importers::load_scene_volume(scene, 2);
  core::PathEvaluator path{*scene.path};
  core::PreparedVolumeCache volumes;
};

TEST(RecordFrames, StillCameraFramesDifferByNoMoreThanTheirNoise) {
  Frames f;
  auto ctx = render::make_headless_context();
  const render::ShaderLoader loader{{render::ShaderLoader::default_shader_dir()}};
  render::FrameRenderer renderer(loader);
  const double fps = 10.0;

  std::vector<std::vector<glm::vec4>> video;
  std::vector<double> noise_var;  // per frame: the variance of its mean, from its own jittered frames
  for (int k = 5; k <= 6; ++k) {
    const core::FrameSpec spec = render::resolve_path_frame(f.scene, f.path, f.vol, k, fps);
    ASSERT_EQ(spec.jitter_base, k * kAccumulate);
    renderer.use_volume(f.volumes.get(f.scene.data.path, f.vol, spec.instant, f.scene.time.interpolation));
    const std::vector<glm::vec4> frame = renderer.render(spec);
    EXPECT_EQ(frame, renderer.render(spec)) << "frame " << k << " is not the same image twice";
    // Its jittered frames one by one: jitter indices k * accumulate .. k * accumulate + 3.
    core::FrameSpec one = spec;
    one.accumulate = 1;
    std::vector<std::vector<glm::vec4>> subs;
    for (int j = 0; j < kAccumulate; ++j) {
      one.march.per_frame.frame = k * kAccumulate + j;
      subs.push_back(renderer.render(one));
    }
    double var_sum = 0.0, worst = 0.0, brightest = 0.0;
    for (std::size_t p = 0; p < frame.size(); ++p) {
      double mean = 0.0, sq = 0.0;
      for (const auto& s : subs) mean += luminance(s[p]) / kAccumulate;
      for (const auto& s : subs) sq += (luminance(s[p]) - mean) * (luminance(s[p]) - mean);
      var_sum += sq / (kAccumulate - 1) / kAccumulate;  // the variance of the mean of the jittered frames
      worst = std::max(worst, std::abs(luminance(frame[p]) - mean));
      brightest = std::max(brightest, luminance(frame[p]));
    }
    ASSERT_GT(brightest, 0.0);
    EXPECT_LT(worst, 1e-5 * brightest) << "frame " << k << " is not the mean of its jittered frames " << k * kAccumulate << "..";
    noise_var.push_back(var_sum / frame.size());
    video.push_back(frame);
  }
  double diff2 = 0.0;
  for (std::size_t p = 0; p < video[0].size(); ++p) {
    const double d = luminance(video[0][p]) - luminance(video[1][p]);
    diff2 += d * d;
  }
  const double rms = std::sqrt(diff2 / video[0].size());
  const double noise = std::sqrt(noise_var[0] + noise_var[1]);  // the noise estimate of a difference of two frames
  std::printf("still camera, frames 5 and 6: RMS luminance difference %.4g, their noise estimate %.4g (ratio %.3f)\n", rms, noise,
              rms / noise);
  EXPECT_GT(rms, 0.0) << "consecutive frames have the same jitter: their seeds do not come from the frame number";
  EXPECT_LE(rms, noise) << "consecutive frames of a still camera differ by more than their noise: the video flickers";
}

}  // namespace
