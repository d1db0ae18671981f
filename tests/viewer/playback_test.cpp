// The viewer's playhead: the grid of instants, play with loop or stop at the end, step to the
// file's steps, the instants prefetching asks for; and the local solar time.
#include <gtest/gtest.h>

#include <algorithm>

#include "geo/solar.hpp"
#include "scene_source.hpp"
#include "kernel/ms_source.hpp"
#include "kernel/volume_cache.hpp"
#include "render/albedo_map.hpp"
#include "render/frame_renderer.hpp"
#include "scene/instant.hpp"
#include "viewer/playback.hpp"

namespace cv::viewer {
namespace {

std::vector<core::ValidTime> three_hourly(int n) {
  std::vector<core::ValidTime> t;
  for (int i = 0; i < n; ++i) t.push_back({1705276800 + i * 10800, core::format_iso_utc(1705276800 + i * 10800)});
  return t;
}

TEST(Playhead, PlaysOnAGridOfInstantsAndLoopsOrStops) {
  Playhead p;
  p.frames_per_step = 4;
  p.reset(three_hourly(3));  // 00, 03, 06 UTC
  EXPECT_DOUBLE_EQ(p.quantum_s, 2700.0);
  EXPECT_EQ(p.shown(), 1705276800);
  p.playing = true;
  p.speed_h_per_s = 1.0;
  p.advance(0.5);  // half an hour: on the grid, 45 min
  EXPECT_EQ(p.shown(), 1705276800 + 2700);
  EXPECT_EQ(p.upcoming(3), (std::vector<std::int64_t>{1705276800 + 5400, 1705276800 + 8100, 1705276800 + 10800}));
  p.t_s = p.last_s;
  p.advance_one();  // past the end: back to the start on loop
  EXPECT_EQ(p.shown(), 1705276800);
  p.loop = false;
  p.t_s = p.last_s;
  p.advance_one();
  EXPECT_FALSE(p.playing);
  EXPECT_EQ(p.shown(), 1705276800 + 21600);
  EXPECT_TRUE(p.upcoming(2).empty());
}

// Played through an afternoon into dusk, the exposure stays at the brightest frame's instead of
// lifting each darker frame back up; frames with nothing lit do not move it; a new hold starts over.
TEST(ExposureHold, HoldsTheBrightestFramesExposureAndLeavesUnlitFramesOut) {
  ExposureHold h;
  EXPECT_DOUBLE_EQ(h.update(std::nullopt, 4.0), 4.0);  // nothing lit yet: the fallback
  EXPECT_DOUBLE_EQ(h.update(2.0, 4.0), 2.0);
  EXPECT_DOUBLE_EQ(h.update(3.0, 4.0), 2.0);           // a darker frame (a larger exposure of its own)
  EXPECT_DOUBLE_EQ(h.update(1.5, 4.0), 1.5);           // a brighter one
  EXPECT_DOUBLE_EQ(h.update(std::nullopt, 4.0), 1.5);  // night: nothing lit
  EXPECT_DOUBLE_EQ(h.update(80.0, 4.0), 1.5);
  h.reset();
  EXPECT_DOUBLE_EQ(h.update(80.0, 4.0), 80.0);
}

TEST(Playhead, StepsToTheFilesStepsAndAOneStepFileIsAStill) {
  const auto times = three_hourly(3);
  Playhead p;
  p.reset(times);
  p.t_s = 1705276800 + 4000;
  p.step(times, +1);
  EXPECT_EQ(p.shown(), 1705276800 + 10800);
  p.step(times, -1);
  EXPECT_EQ(p.shown(), 1705276800);
  Playhead one;
  one.playing = true;
  one.reset(three_hourly(1));
  EXPECT_TRUE(one.still());
  EXPECT_FALSE(one.playing);
  one.advance(10.0);
  EXPECT_EQ(one.shown(), 1705276800);
}

TEST(LocalSolarTime, IsNoonUnderTheSun) {
  const std::int64_t t = 1705276800;  // 2024-01-15T00:00:00Z: the sun is near 177 E (the equation of time)
  const double lon = geo::subsolar_point(t).lon_deg;
  EXPECT_NEAR(local_solar_time_h(lon, t), 12.0, 1e-9);
  EXPECT_NEAR(local_solar_time_h(lon + 90.0, t), 18.0, 1e-9);
  EXPECT_NEAR(local_solar_time_h(lon - 180.0, t), 0.0, 1e-9);
}

// Playback takes each instant's two-stream source as the prefetcher built it on its own thread: for
// the sun at that instant and with the key the render thread's march asks for (the scene resolved
// at the instant as the viewer resolves it), the same numbers a build on the render thread gives.
TEST(Prefetcher, BuildsEachInstantsSourceForItsOwnSun) {
  core::Scene scene;
  scene.data.path = CV_SAMPLE_FILE;
  scene.width = 64, scene.height = 36;
  ASSERT_TRUE(scene.render.march.medium.ms_two_stream);  // the default model
  const core::CloudVolume vol = importers::load_scene_volume(scene, 2);
  ASSERT_GE(vol.times.size(), 2u);
  const std::int64_t t0 = vol.times[0].unix_s, t1 = (vol.times[0].unix_s + vol.times[1].unix_s) / 2;  // a step, and between two
  Prefetcher prefetch(scene, 4);
  prefetch.want({t0, t1}, core::TimeInterpolation::Auto, false, &scene);
  glm::dvec3 suns[2];
  for (int n = 0; n < 2; ++n) {
    const std::int64_t t = n ? t1 : t0;
    const std::shared_ptr<const core::PreparedVolume> v = prefetch.get(t, true);
    ASSERT_TRUE(v);
    ASSERT_TRUE(v->ms_prebuilt) << "instant " << t;
    core::Scene at = scene;
    at.time.valid_utc = core::format_iso_utc(t);
    const core::FrameSpec spec = render::resolve_frame(at, vol);
    // The ground map the renderer draws and gives the columns (GpuRaymarcher::prepare_ground).
    std::shared_ptr<const core::AlbedoMap> ground;
    if (spec.march.features.globe && !spec.march.medium.ground_texture.empty()) {
      ground = render::shared_albedo_map(spec.march.medium.ground_texture, spec.march.medium.ground_map_colours);
    }
    const core::MsSourceKey key =
        core::ms_source_key(spec.march, core::march_params(*v, spec.march_camera, spec.sun, spec.march).u_to_sun, ground.get());
    EXPECT_EQ(key.ground != nullptr, ground != nullptr);
    EXPECT_TRUE(v->ms_prebuilt->key == key) << "instant " << t;
    suns[n] = key.to_sun;
    bool built = true;
    const std::shared_ptr<const core::MsSource> taken = core::ms_source_for(*v, key, &built);
    EXPECT_FALSE(built);
    EXPECT_EQ(taken.get(), &v->ms_prebuilt->source);
    const core::MsSource fresh = core::build_ms_source(*v, key);
    EXPECT_EQ(fresh.i0, taken->i0);
    EXPECT_EQ(fresh.i1, taken->i1);
    EXPECT_GT(*std::max_element(taken->i0.begin(), taken->i0.end()), 0.0f);  // the sample's cloud is lit
    // Another medium (a droplet size that changes the phase's mean cosine) is built, not taken.
    core::MsSourceKey other = key;
    other.liquid_g += 0.01;
    EXPECT_NE(core::ms_source_for(*v, other, &built).get(), &v->ms_prebuilt->source);
    EXPECT_TRUE(built);
  }
  EXPECT_GT(glm::length(suns[0] - suns[1]), 1e-3);  // 90 minutes apart: the sun has moved
  EXPECT_EQ(prefetch.stats().sources, 2u);
  // No scene, or a scene on the octave model: no source built ahead.
  Prefetcher none(scene, 1);
  none.want({t0}, core::TimeInterpolation::Auto, false, nullptr);
  EXPECT_FALSE(none.get(t0, true)->ms_prebuilt);
  core::Scene octaves = scene;
  octaves.render.march.medium.ms_two_stream = false;
  Prefetcher octave(octaves, 1);
  octave.want({t0}, core::TimeInterpolation::Auto, false, &octaves);
  EXPECT_FALSE(octave.get(t0, true)->ms_prebuilt);
  EXPECT_EQ(octave.stats().sources, 0u);
}

// The prefetcher and the render path (PreparedVolumeCache) keep the last two steps' media and winds
// for the instants between them (core::StepMediaCache); each instant either prepares is the medium
// derived from the steps themselves, bit for bit, through instants that share steps, a step
// itself, and a return to an earlier pair.
TEST(Prefetcher, PreparesEachInstantAsTheRenderPathDoes) {
  core::Scene scene;
  scene.data.path = CV_SAMPLE_FILE;
  scene.width = 64, scene.height = 36;
  core::CloudVolume vol = importers::load_scene_volume(scene, 2);
  ASSERT_GE(vol.times.size(), 3u);
  const std::int64_t a = vol.times[0].unix_s, b = vol.times[1].unix_s, c = vol.times[2].unix_s;
  const std::vector<std::int64_t> order = {a + (b - a) / 4, (a + b) / 2, b, (b + c) / 2, a + (b - a) / 3};
  Prefetcher prefetch(scene, 1);
  core::PreparedVolumeCache cache;
  for (std::int64_t t : order) {
    prefetch.want({t}, core::TimeInterpolation::Auto);
    const std::shared_ptr<const core::PreparedVolume> got = prefetch.get(t, true);
    ASSERT_TRUE(got) << prefetch.error();
    const core::Instant at = core::instant_at_time(vol.times, core::format_iso_utc(t), scene.data.path);
    // The medium derived here from the steps themselves, without either cache.
    core::GridMeanExtinction direct = core::grid_mean_extinction(vol.grid, vol.step(at.step0));
    if (at.between()) {
      const core::StepWinds w0 = core::step_winds(vol.step(at.step0));
      const core::GridMeanExtinction e1 = core::grid_mean_extinction(vol.grid, vol.step(at.step1));
      const core::StepWinds w1 = core::step_winds(vol.step(at.step1));
      direct = core::interpolate_extinction(vol.grid, direct, e1, w0, w1, at.gap_s, at.fraction, core::TimeInterpolation::Auto);
    }
    const std::shared_ptr<const core::PreparedVolume> cached = cache.get(scene.data.path, vol, at, core::TimeInterpolation::Auto);
    for (const core::GridMeanExtinction* e : {&got->extinction, &cached->extinction}) {
      EXPECT_EQ(e->liquid_per_m, direct.liquid_per_m) << core::format_iso_utc(t);
      EXPECT_EQ(e->ice_per_m, direct.ice_per_m) << core::format_iso_utc(t);
      EXPECT_EQ(e->fraction, direct.fraction) << core::format_iso_utc(t);
    }
    EXPECT_FALSE(direct.liquid_per_m.empty());
  }
}

// A bound in bytes lowers the bound in instants to what fits, measured on the first instant, but
// never under two; a generous one leaves it.
TEST(Prefetcher, KeepsToItsBoundInBytes) {
  core::Scene scene;
  scene.data.path = CV_SAMPLE_FILE;
  scene.width = 64, scene.height = 36;
  const core::CloudVolume vol = importers::load_scene_volume(scene, 2);
  ASSERT_GE(vol.times.size(), 4u);
  std::vector<std::int64_t> four;
  for (std::size_t k = 0; k < 4; ++k) four.push_back(vol.times[k].unix_s);
  Prefetcher tight(scene, 6, 1);
  tight.want(four, core::TimeInterpolation::Auto, false, &scene);
  ASSERT_TRUE(tight.get(four[0], true));
  EXPECT_EQ(tight.stats().max_resident, 2u);
  ASSERT_TRUE(tight.get(four[1], true));
  EXPECT_FALSE(tight.get(four[2], false));  // beyond the bound: not prepared
  EXPECT_LE(tight.stats().resident, 2u);
  // Room for three instants with their sources, besides what the worker holds for the first: its
  // decoded step and that step's medium.
  std::size_t each = 0, held = 0;
  {
    Prefetcher one(scene, 1);
    one.want({four[0]}, core::TimeInterpolation::Auto, false, &scene);
    each = prepared_bytes(*one.get(four[0], true));
    held = one.stats().held_bytes;
  }
  ASSERT_GT(each, 0u);
  core::CloudVolume copy = importers::load_scene_volume(scene, 2);
  const std::size_t step_bytes = copy.step(0).bytes();
  EXPECT_GE(held, step_bytes) << "the decoded step is counted";
  EXPECT_GE(held, step_bytes + 2 * copy.grid.points() * sizeof(float)) << "and its medium";
  const std::size_t bound = held + 3 * each + each / 2;
  Prefetcher three(scene, 6, bound);
  three.want({four[0]}, core::TimeInterpolation::Auto, false, &scene);
  ASSERT_TRUE(three.get(four[0], true));
  EXPECT_EQ(three.stats().held_bytes, held);
  EXPECT_EQ(three.stats().max_resident, 3u);
  // A second step decoded, and its medium: the bound falls by what they hold.
  three.want({four[0], four[1]}, core::TimeInterpolation::Auto, false, &scene);
  ASSERT_TRUE(three.get(four[1], true));
  const PrefetchStats s2 = three.stats();
  EXPECT_GT(s2.held_bytes, held + step_bytes) << "two steps and two media";
  EXPECT_EQ(s2.max_resident, std::min<std::size_t>(3, std::max<std::size_t>(2, (bound - std::min(bound, s2.held_bytes)) / each)));
  EXPECT_EQ(s2.max_resident, 2u) << "a second step and medium take more than half an instant's room";
  Prefetcher roomy(scene, 6, std::size_t(1) << 40);
  roomy.want(four, core::TimeInterpolation::Auto, false, &scene);
  ASSERT_TRUE(roomy.get(four[3], true));
  EXPECT_EQ(roomy.stats().max_resident, 6u);
}

}  // namespace
}  // namespace cv::viewer
