// The GPU raymarcher (llvmpipe in CI) against the CPU reference: the same scene, pixel by pixel.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>

#include "kernel/march_params.hpp"
#include "reference/raymarcher.hpp"
#include "render/context.hpp"
#include "render/raymarcher.hpp"
#include "support/bubble_scene.hpp"

namespace {
using namespace cv;

using Scene = cv::test::BubbleScene;  // the bubble under a thin ice layer

// A headless context, the GPU raymarcher, and the bubble scene uploaded to it.
struct BubbleOnGpu {
  std::unique_ptr<render::GlContext> ctx = render::make_headless_context();
  render::ShaderLoader loader{{render::ShaderLoader::default_shader_dir()}};
  render::GpuRaymarcher gpu{loader};
  Scene sc;
  core::GridMeanExtinction medium = core::grid_mean_extinction(sc.grid, sc.data);
  BubbleOnGpu() { gpu.upload(sc.grid, medium); }
};

// The bubble seen from 1.5 degrees south, 2 km up, looking 5 degrees up, at width x height.
core::Camera bubble_camera(int width, int height) {
  core::Camera cam;
  cam.lat_deg = -1.5;
  cam.alt_m = 2000.0;
  cam.pitch_deg = 5.0;
  cam.fov_deg = 60.0;
  cam.width = width;
  cam.height = height;
  return cam;
}

// The sun low in the east of the bubble.
core::Sun low_eastern_sun() {
  core::Sun sun;
  sun.subsolar_lat_deg = 10.0;
  sun.subsolar_lon_deg = 60.0;
  return sun;
}

// The march of the bubble tests: 200 m view steps, 16 sun steps, 4 octaves.
core::MarchSettings bubble_march() {
  core::MarchSettings s;
  s.quality.view_step_m = 200.0;
  s.quality.sun_steps = 16;
  s.quality.octaves = 4;
  return s;
}

TEST(Raymarch, GpuMatchesTheCpuReference) {
  BubbleOnGpu g;
  auto& [ctx, loader, gpu, sc, medium] = g;
  const core::Camera cam = bubble_camera(48, 27);
  core::Sun sun = low_eastern_sun();
  sun.irradiance = glm::dvec3(1.0, 0.8, 0.5);  // distinct channels: a channel mix-up shows
  core::MarchSettings s;
  s.quality.view_step_m = 200.0;
  s.quality.sun_steps = 16;
  s.quality.octaves = 4;
  const auto cpu = core::render_reference(sc.grid, medium, cam, sun, s);
  const auto img = gpu.render(cam, sun, s);
  double max_l = 0.0;
  for (const auto& l : cpu.radiance) max_l = std::max(max_l, l.x);
  ASSERT_GT(max_l, 0.0);
  double worst = 0.0, mean = 0.0, worst_t = 0.0;
  for (std::size_t i = 0; i < img.size(); ++i) {
    ASSERT_TRUE(std::isfinite(img[i].x) && std::isfinite(img[i].w)) << i;
    double e = 0.0;
    for (int c = 0; c < 3; ++c) e = std::max(e, std::abs(img[i][c] - cpu.radiance[i][c]) / max_l);
    worst = std::max(worst, e);
    mean += e;
    worst_t = std::max(worst_t, std::abs(img[i].w - cpu.transmittance[i]));
  }
  mean /= static_cast<double>(img.size());
  std::printf("GPU vs CPU reference, %dx%d: radiance error (relative to the brightest pixel) mean %.3g, worst %.3g; "
              "transmittance worst %.3g\n", cam.width, cam.height, mean, worst, worst_t);
  EXPECT_LT(worst, 1e-3);
  EXPECT_LT(worst_t, 1e-3);
  // With jittered steps (an accumulation frame) both march through the same points.
  s.per_frame.frame = 7;
  const auto cpu_j = core::render_reference(sc.grid, medium, cam, sun, s);
  const auto gpu_j = gpu.render(cam, sun, s);
  double worst_j = 0.0, changed = 0.0;
  for (std::size_t i = 0; i < gpu_j.size(); ++i) {
    worst_j = std::max(worst_j, std::abs(gpu_j[i].x - cpu_j.radiance[i].x) / max_l);
    changed = std::max(changed, std::abs(cpu_j.radiance[i].x - cpu.radiance[i].x) / max_l);
  }
  std::printf("with jitter (frame 7): worst %.3g; jitter moved pixels by up to %.3g\n", worst_j, changed);
  EXPECT_LT(worst_j, 1e-3);
  EXPECT_GT(changed, 1e-4);  // the jitter does move the samples
  // The white-noise hash the blue noise replaced (march.blue_noise = false) is still the same on both.
  s.quality.blue_noise = false;
  const auto cpu_h = core::render_reference(sc.grid, medium, cam, sun, s);
  const auto gpu_h = gpu.render(cam, sun, s);
  double worst_h = 0.0, differs = 0.0;
  for (std::size_t i = 0; i < gpu_h.size(); ++i) {
    worst_h = std::max(worst_h, std::abs(gpu_h[i].x - cpu_h.radiance[i].x) / max_l);
    differs = std::max(differs, std::abs(cpu_h.radiance[i].x - cpu_j.radiance[i].x) / max_l);
  }
  std::printf("with the hash jitter (frame 7): worst %.3g; differs from blue noise by up to %.3g\n", worst_h, differs);
  EXPECT_LT(worst_h, 1e-3);
  EXPECT_GT(differs, 1e-4);
}

// Anti-aliasing (march.anti_alias, march.glsl pixel_jitter): accumulated frames spread their rays
// over the pixel, so their mean tends to the pixel's box-filtered radiance. The truth: the same view
// marched at 4 x 4 times the pixels (at their centres) and averaged over each 4 x 4 block. The
// anti-aliased mean of 64 frames must be much closer to it than the mean of 64 frames at the
// centres, which keeps the centres' stairs at the bubble's edges; the CPU kernel jitters the same
// way; frame 0 stays at the centres.
TEST(Raymarch, AccumulatedFramesConvergeToThePixelsBoxFilteredRadiance) {
  BubbleOnGpu g;
  auto& [ctx, loader, gpu, sc, medium] = g;
  const core::Camera cam = bubble_camera(48, 27);
  const core::Sun sun = low_eastern_sun();
  core::MarchSettings s = bubble_march();
  auto mean_of = [&](const core::Camera& c, bool aa, int frames) {
    core::MarchSettings m = s;
    m.quality.anti_alias = aa;
    std::vector<glm::dvec4> sum(static_cast<std::size_t>(c.width * c.height), glm::dvec4(0.0));
    for (int k = 0; k < frames; ++k) {
      m.per_frame.frame = k;
      const auto img = gpu.render(c, sun, m);
      for (std::size_t i = 0; i < sum.size(); ++i) sum[i] += glm::dvec4(img[i]) / double(frames);
    }
    return sum;
  };
  core::Camera fine = cam;
  fine.width *= 4, fine.height *= 4;
  const auto super = mean_of(fine, false, 4);
  std::vector<glm::dvec4> truth(static_cast<std::size_t>(cam.width * cam.height), glm::dvec4(0.0));
  for (int y = 0; y < fine.height; ++y)
    for (int x = 0; x < fine.width; ++x)
      truth[static_cast<std::size_t>((y / 4) * cam.width + x / 4)] += super[static_cast<std::size_t>(y * fine.width + x)] / 16.0;
  const auto aa = mean_of(cam, true, 64), centres = mean_of(cam, false, 64);
  double max_l = 0.0;
  for (const auto& t : truth) max_l = std::max(max_l, t.x);
  ASSERT_GT(max_l, 0.0);
  double err_aa = 0.0, err_centres = 0.0, worst_aa = 0.0, worst_centres = 0.0;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    const double a = std::abs(aa[i].x - truth[i].x) / max_l, c = std::abs(centres[i].x - truth[i].x) / max_l;
    err_aa += a / double(truth.size()), err_centres += c / double(truth.size());
    worst_aa = std::max(worst_aa, a), worst_centres = std::max(worst_centres, c);
  }
  std::printf("against the 4x4 box-filtered image, %dx%d, 64 frames: anti-aliased mean %.4f worst %.4f; pixel centres mean %.4f "
              "worst %.4f (|dL| / brightest)\n", cam.width, cam.height, err_aa, worst_aa, err_centres, worst_centres);
  EXPECT_LT(err_aa, 0.5 * err_centres);
  EXPECT_LT(worst_aa, 0.5 * worst_centres);

  // The CPU kernel jitters as the GPU does (frame 5), and frame 0 is the centres' image.
  core::MarchSettings m = s;
  m.per_frame.frame = 5;
  const auto cpu = core::render_reference(sc.grid, medium, cam, sun, m);
  const auto gpu5 = gpu.render(cam, sun, m);
  m.quality.anti_alias = false;
  const auto cpu_centres = core::render_reference(sc.grid, medium, cam, sun, m);
  double worst = 0.0, moved = 0.0;
  for (std::size_t i = 0; i < gpu5.size(); ++i) {
    worst = std::max(worst, std::abs(gpu5[i].x - cpu.radiance[i].x) / max_l);
    moved = std::max(moved, std::abs(cpu.radiance[i].x - cpu_centres.radiance[i].x) / max_l);
  }
  EXPECT_LT(worst, 1e-3) << "the GPU and the CPU kernel pass the same jittered rays";
  EXPECT_GT(moved, 1e-2) << "the jitter moves the rays within the pixel";
  m.per_frame.frame = 0;
  const auto f0 = gpu.render(cam, sun, m);
  m.quality.anti_alias = true;
  const auto f0_aa = gpu.render(cam, sun, m);
  for (std::size_t i = 0; i < f0.size(); ++i) ASSERT_EQ(f0[i], f0_aa[i]) << "frame 0 marches the centres: " << i;
}

// An image wider and taller than the 64 x 64 blue-noise mask: pixels past it take the mask again
// (texelFetch at px mod 64 on the GPU, BlueNoiseMask::at on the CPU), the same on both.
TEST(Raymarch, BlueNoiseJitterTilesPastTheMaskOnGpuAsOnCpu) {
  BubbleOnGpu g;
  auto& [ctx, loader, gpu, sc, medium] = g;
  const core::Camera cam = bubble_camera(80, 70);
  const core::Sun sun = low_eastern_sun();
  core::MarchSettings s;
  s.quality.view_step_m = 400.0;  // coarse: the offsets matter, and llvmpipe stays quick on 5600 pixels
  s.quality.sun_steps = 8;
  s.per_frame.frame = 3;
  const auto cpu = core::render_reference(sc.grid, medium, cam, sun, s);
  const auto img = gpu.render(cam, sun, s);
  double max_l = 0.0;
  for (const auto& l : cpu.radiance) max_l = std::max(max_l, l.x);
  ASSERT_GT(max_l, 0.0);
  double worst_inside = 0.0, worst_past = 0.0;
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * cam.width + x;
      const double e = std::abs(img[i].x - cpu.radiance[i].x) / max_l;
      double& worst = x < 64 && y < 64 ? worst_inside : worst_past;
      worst = std::max(worst, e);
    }
  std::printf("blue-noise jitter, 80x70: worst inside the first tile %.3g, past it %.3g\n", worst_inside, worst_past);
  EXPECT_LT(worst_inside, 1e-3);
  EXPECT_LT(worst_past, 1e-3);
}

TEST(Raymarch, FarCamerasMatchTheCpuReference) {
  // Geostationary distance and 400 000 km, looking straight down at the cloud box: the box spans
  // 0.06 degree of the view from 4e8 m.
  BubbleOnGpu g;
  auto& [ctx, loader, gpu, sc, medium] = g;
  core::Sun sun;
  sun.subsolar_lat_deg = 5.0;
  sun.subsolar_lon_deg = 20.0;
  core::MarchSettings s;
  s.quality.view_step_m = 200.0;
  s.quality.sun_steps = 16;
  s.quality.octaves = 4;
  for (const auto& [alt, fov] : {std::pair{3.6e7, 0.8}, std::pair{4e8, 0.07}}) {
    core::Camera cam;
    cam.alt_m = alt;
    cam.pitch_deg = -90.0;
    cam.fov_deg = fov;
    cam.width = 32;
    cam.height = 32;
    const auto cpu = core::render_reference(sc.grid, medium, cam, sun, s);
    const auto img = gpu.render(cam, sun, s);
    double max_l = 0.0, worst = 0.0, worst_t = 0.0;
    int cloudy = 0;
    for (const auto& l : cpu.radiance) max_l = std::max(max_l, l.x);
    for (std::size_t i = 0; i < img.size(); ++i) {
      for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(img[i][c] - cpu.radiance[i][c]) / max_l);
      worst_t = std::max(worst_t, std::abs(img[i].w - cpu.transmittance[i]));
      cloudy += cpu.transmittance[i] < 0.5;
    }
    std::printf("camera at %.3g m: radiance worst %.3g of the brightest, transmittance worst %.3g, %d cloudy pixels\n",
                alt, worst, worst_t, cloudy);
    EXPECT_GT(cloudy, 50) << alt;
    EXPECT_LT(worst, 1e-3) << alt;
    EXPECT_LT(worst_t, 1e-3) << alt;
  }
}

}  // namespace

#include "importer.hpp"

namespace {

TEST(Raymarch, TheBundledSampleRendersWithCloudAndWithoutNaN) {
  auto ctx = render::make_headless_context();
  render::ShaderLoader loader({render::ShaderLoader::default_shader_dir()});
  render::GpuRaymarcher gpu(loader);
  auto vol = importers::import_file(CV_SAMPLE_FILE);
  const auto& g = vol.grid;
  gpu.upload(g, core::grid_mean_extinction(g, vol.step(3)));
  core::Camera cam;  // from 5000 km above the middle of the domain, straight down
  cam.lat_deg = 45.0;
  cam.lon_deg = 190.0;
  cam.alt_m = 5.0e6;
  cam.pitch_deg = -90.0;
  cam.fov_deg = 60.0;
  cam.width = 64;
  cam.height = 36;
  core::Sun sun;
  sun.subsolar_lat_deg = -21.0;
  sun.subsolar_lon_deg = 190.0;
  core::MarchSettings s;
  s.quality.view_step_m = 500.0;
  s.quality.octaves = 4;
  const auto img = gpu.render(cam, sun, s);
  int cloudy = 0, clear = 0;
  for (const auto& p : img) {
    ASSERT_TRUE(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z) && std::isfinite(p.w));
    ASSERT_GE(p.w, 0.0f);
    ASSERT_LE(p.w, 1.0f);
    (p.w < 0.5f ? cloudy : clear)++;
  }
  // The domain fills part of the view; part of it is cloud, part of the view is clear.
  EXPECT_GT(cloudy, 100);
  EXPECT_GT(clear, 100);
}

}  // namespace

namespace {

// A global grid (5 degrees, the poles' rows at +-90): a stratiform layer at 2-3 km everywhere, a
// thick blob over the north pole and one on the date line.
struct GlobalScene {
  core::VolumeGrid grid;
  core::TimeStepData data;
  GlobalScene() {
    grid.lon_deg = {0.0, 5.0, 72};
    grid.lat_deg = {-90.0, 5.0, 37};
    grid.alt_m = {500.0, 500.0, 21};
    data[core::Field::ExtinctionLiquid].assign(grid.points(), 0.0f);
    for (int k = 0; k < grid.alt_m.count; ++k)
      for (int j = 0; j < grid.lat_deg.count; ++j)
        for (int i = 0; i < grid.lon_deg.count; ++i) {
          const double lon = grid.lon_deg.at(i), lat = grid.lat_deg.at(j), z = grid.alt_m.at(k);
          double sigma = (z >= 2000.0 && z <= 3000.0) ? 5e-4 : 0.0;
          const double dl = std::remainder(lon - 180.0, 360.0);
          if (lat >= 80.0 && z < 6000.0) sigma += 5e-3;
          if (std::abs(lat) <= 10.0 && std::abs(dl) <= 10.0 && z < 8000.0) sigma += 3e-3;
          data[core::Field::ExtinctionLiquid][grid.index(i, j, k)] = static_cast<float>(sigma);
        }
  }
};

struct GlobalCase {
  const char* name;
  core::Camera cam;
  core::Sun sun;
};

core::Camera global_camera(double lat, double lon, double alt, double heading, double pitch, double fov, int w, int h) {
  core::Camera c;
  c.lat_deg = lat, c.lon_deg = lon, c.alt_m = alt, c.heading_deg = heading, c.pitch_deg = pitch, c.fov_deg = fov;
  c.width = w, c.height = h;
  return c;
}

core::Sun global_sun(double lat, double lon) {
  core::Sun s;
  s.subsolar_lat_deg = lat, s.subsolar_lon_deg = lon;
  return s;
}

// Renders each case on the GPU and the CPU reference and holds them within 1e-3 of the brightest
// pixel (radiance, all channels) and 1e-3 in transmittance.
void expect_gpu_matches_cpu(std::initializer_list<GlobalCase> cases) {
  auto ctx = render::make_headless_context();
  render::ShaderLoader loader({render::ShaderLoader::default_shader_dir()});
  render::GpuRaymarcher gpu(loader);
  GlobalScene sc;
  ASSERT_TRUE(sc.grid.wraps_lon());
  const core::GridMeanExtinction medium = core::grid_mean_extinction(sc.grid, sc.data);
  gpu.upload(sc.grid, medium);
  core::MarchSettings s;
  s.quality.view_step_m = 250.0;
  s.quality.sun_steps = 16;
  s.quality.octaves = 4;
  for (const GlobalCase& c : cases) {
    const auto cpu = core::render_reference(sc.grid, medium, c.cam, c.sun, s);
    const auto img = gpu.render(c.cam, c.sun, s);
    double max_l = 1e-30, worst = 0.0, worst_t = 0.0;
    int cloudy = 0;
    for (const auto& l : cpu.radiance) max_l = std::max(max_l, l.x);
    for (std::size_t i = 0; i < img.size(); ++i) {
      ASSERT_TRUE(std::isfinite(img[i].x) && std::isfinite(img[i].w)) << c.name;
      for (int k = 0; k < 3; ++k) worst = std::max(worst, std::abs(img[i][k] - cpu.radiance[i][k]) / max_l);
      worst_t = std::max(worst_t, std::abs(img[i].w - cpu.transmittance[i]));
      cloudy += cpu.transmittance[i] < 0.99;
    }
    std::printf("%-28s radiance worst %.3g, transmittance worst %.3g, %d pixels with cloud\n", c.name, worst, worst_t,
                cloudy);
    EXPECT_GT(cloudy, 0) << c.name;
    EXPECT_LT(worst, 1e-3) << c.name;
    EXPECT_LT(worst_t, 1e-3) << c.name;
  }
}

TEST(Raymarch, PoleDateLineLimbAndInsideACloud) {
  expect_gpu_matches_cpu({
      {"pole, looking away from sun", global_camera(80.0, 0.0, 3e5, 180.0, -30.0, 60.0, 32, 18), global_sun(20.0, 0.0)},
      {"across the date line", global_camera(0.0, 165.0, 5000.0, 90.0, 2.0, 60.0, 32, 18), global_sun(0.0, 150.0)},
      {"limb, two shell segments", global_camera(0.0, 0.0, 4e5, 0.0, -19.5, 20.0, 32, 18), global_sun(0.0, 0.0)},
      {"inside a cloud", global_camera(0.0, 180.0, 2500.0, 45.0, 0.0, 90.0, 32, 18), global_sun(0.0, 170.0)},
      {"one pixel, wide field", global_camera(30.0, 30.0, 1e6, 0.0, -90.0, 179.0, 1, 1), global_sun(30.0, 30.0)},
  });
}

// The sun near the samples' horizon: sun paths of optical depth ~20-100 that run for hundreds of
// kilometres through the ramp between two grid levels. With altitudes from |p| - R of float
// positions (+-0.25 m) the GPU was 0.5-2 % off per pixel (4.7e-3 of the brightest pixel looking
// away from the sun); ray_altitude keeps those digits.
TEST(Raymarch, GrazingSunMatchesTheReference) {
  expect_gpu_matches_cpu({
      {"over the pole, sunward", global_camera(80.0, 0.0, 3e5, 0.0, -30.0, 60.0, 32, 18), global_sun(20.0, 0.0)},
      {"terminator, sunward", global_camera(0.0, 0.0, 8000.0, 90.0, -10.0, 90.0, 32, 18), global_sun(0.0, 90.0)},
      {"terminator, away", global_camera(0.0, 0.0, 8000.0, 270.0, -10.0, 90.0, 32, 18), global_sun(0.0, 90.0)},
  });
}

}  // namespace

namespace {
// The liquid phase choice: Henyey-Greenstein with the Mie fit's mean cosine instead of the fit.
// GPU and CPU agree with either, and the choice changes the image (the fit's forward peak and
// backscatter differ from HG's).
TEST(Raymarch, LiquidPhaseChoiceMatchesTheReference) {
  BubbleOnGpu g;
  auto& [ctx, loader, gpu, sc, medium] = g;
  const core::Camera cam = bubble_camera(32, 18);
  const core::Sun sun = low_eastern_sun();
  core::MarchSettings s = bubble_march();
  const auto mie = core::render_reference(sc.grid, medium, cam, sun, s);
  s.medium.liquid_phase_hg = true;
  const auto cpu = core::render_reference(sc.grid, medium, cam, sun, s);
  const auto img = gpu.render(cam, sun, s);
  double max_l = 0.0, worst = 0.0, change = 0.0;
  for (const auto& l : cpu.radiance) max_l = std::max(max_l, l.x);
  ASSERT_GT(max_l, 0.0);
  for (std::size_t i = 0; i < img.size(); ++i) {
    worst = std::max(worst, std::abs(img[i].x - cpu.radiance[i].x) / max_l);
    change = std::max(change, std::abs(mie.radiance[i].x - cpu.radiance[i].x) / max_l);
  }
  std::printf("liquid phase HG: GPU vs CPU worst %.3g of the brightest pixel; HG against the Mie fit moves pixels by up to %.3g\n",
              worst, change);
  EXPECT_LT(worst, 1e-3);
  EXPECT_GT(change, 1e-2);
}
// The layer masks (issue 17) in the shader as in the CPU kernel: the ice hidden, then a band of
// heights, each the CPU reference's image and each unlike the whole cloud's.
TEST(Raymarch, LayerMasksMatchTheReference) {
  BubbleOnGpu g;
  auto& [ctx, loader, gpu, sc, medium] = g;
  const core::Camera cam = bubble_camera(32, 18);
  const core::Sun sun = low_eastern_sun();
  core::MarchSettings s;
  s.quality.view_step_m = 200.0;
  s.quality.sun_steps = 16;
  const auto whole = core::render_reference(sc.grid, medium, cam, sun, s);
  double max_l = 0.0;
  for (const auto& l : whole.radiance) max_l = std::max(max_l, l.x);
  ASSERT_GT(max_l, 0.0);
  auto check = [&](const core::MarchSettings& m, const char* what) {
    const auto cpu = core::render_reference(sc.grid, medium, cam, sun, m);
    const auto img = gpu.render(cam, sun, m);
    double worst = 0.0, worst_t = 0.0, change = 0.0;
    for (std::size_t i = 0; i < img.size(); ++i) {
      worst = std::max(worst, std::abs(img[i].x - cpu.radiance[i].x) / max_l);
      worst_t = std::max(worst_t, std::abs(img[i].w - cpu.transmittance[i]));
      change = std::max(change, std::abs(cpu.transmittance[i] - whole.transmittance[i]));
    }
    std::printf("%s: GPU vs CPU worst %.3g (transmittance %.3g); the mask moves transmittance by up to %.3g\n", what, worst, worst_t, change);
    EXPECT_LT(worst, 1e-3) << what;
    EXPECT_LT(worst_t, 1e-3) << what;
    EXPECT_GT(change, 1e-2) << what;
  };
  core::MarchSettings no_ice = s;
  no_ice.medium.hide_ice = true;
  check(no_ice, "ice hidden");
  core::MarchSettings band = s;
  band.medium.layer_bottom_m = 2000.0;
  band.medium.layer_top_m = 6000.0;
  check(band, "band 2-6 km");
  // The octave gate reads the column depth of what is shown (the GPU uploads the masked map as the
  // CPU kernel reads it): the thin ice alone, its octaves weighted by its own depth, not the bubble's.
  core::MarchSettings gated = bubble_march();
  gated.features.octave_gate = true;
  gated.medium.hide_liquid = true;
  const auto cpu = core::render_reference(sc.grid, medium, cam, sun, gated);
  const auto img = gpu.render(cam, sun, gated);
  double worst = 0.0, lit = 0.0;
  for (std::size_t i = 0; i < img.size(); ++i) {
    for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(img[i][c] - cpu.radiance[i][c]) / max_l);
    lit = std::max(lit, cpu.radiance[i].x / max_l);
  }
  std::printf("liquid hidden, octave gate: GPU vs CPU worst %.3g of the whole cloud's brightest pixel (the ice's brightest %.3g)\n", worst,
              lit);
  EXPECT_GT(lit, 1e-3);  // the ice is seen
  EXPECT_LT(worst, 1e-4);
}

// False colour (march.tint_liquid / tint_ice, `compare --render`): each sample's light takes the hue
// of its tints at its own luminance. Without the air the untinted light is grey, so a tinted image
// has the untinted one's luminance at every pixel; with one tint for both, every pixel has that
// tint's hue exactly; the GPU's compiled-in tint is the CPU kernel's; white tints change nothing.
TEST(Raymarch, TintKeepsTheLuminanceAndTakesTheHueOnGpuAsOnCpu) {
  BubbleOnGpu g;
  auto& [ctx, loader, gpu, sc, medium] = g;
  const core::Camera cam = bubble_camera(32, 18);
  const core::Sun sun = low_eastern_sun();
  const core::MarchSettings s = bubble_march();
  ASSERT_FALSE(s.features.atmosphere);
  const auto grey = core::render_reference(sc.grid, medium, cam, sun, s);
  auto lum = [](const glm::dvec3& c) { return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z; };
  double max_l = 0.0;
  for (const auto& l : grey.radiance) max_l = std::max(max_l, lum(l));
  ASSERT_GT(max_l, 0.0);
  const glm::dvec3 orange(1.0, 0.525, 0.05), blue(0.05, 0.525, 1.0);

  core::MarchSettings one = s;
  one.medium.tint_liquid = one.medium.tint_ice = orange;
  EXPECT_NE(kernel::MarchVariant::of(one).key(), kernel::MarchVariant::of(s).key());
  const auto cpu_one = core::render_reference(sc.grid, medium, cam, sun, one);
  const glm::dvec3 hue = orange / lum(orange);
  int lit = 0;
  for (std::size_t i = 0; i < cpu_one.radiance.size(); ++i) {
    const glm::dvec3 t = cpu_one.radiance[i], w = grey.radiance[i];
    EXPECT_NEAR(lum(t), lum(w), 1e-9 * max_l) << i;
    if (lum(w) < 1e-3 * max_l) continue;
    ++lit;
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(t[c], hue[c] * lum(w), 1e-9 * max_l) << i << " channel " << c;
  }
  EXPECT_GT(lit, 20);

  core::MarchSettings two = s;
  two.medium.tint_liquid = orange;
  two.medium.tint_ice = blue;
  const auto cpu = core::render_reference(sc.grid, medium, cam, sun, two);
  const auto img = gpu.render(cam, sun, two);
  double worst = 0.0, warm = 0.0, cool = 0.0;
  for (std::size_t i = 0; i < img.size(); ++i) {
    for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(img[i][c] - cpu.radiance[i][c]) / max_l);
    EXPECT_NEAR(lum(cpu.radiance[i]), lum(grey.radiance[i]), 1e-9 * max_l) << i;
    if (lum(grey.radiance[i]) < 1e-3 * max_l) continue;
    const double r_minus_b = (cpu.radiance[i].x - cpu.radiance[i].z) / lum(grey.radiance[i]);
    warm = std::max(warm, r_minus_b), cool = std::max(cool, -r_minus_b);
  }
  std::printf("tint liquid orange, ice blue: GPU vs CPU worst %.3g of the brightest pixel; most orange (r - b) / lum %.3g, most blue %.3g\n",
              worst, warm, cool);
  EXPECT_LT(worst, 1e-3);
  EXPECT_GT(warm, 0.5);  // the liquid bubble's light is orange
  EXPECT_GT(cool, 0.5);  // and the ice layer's blue

  core::MarchSettings white = s;
  white.medium.tint_liquid = white.medium.tint_ice = glm::dvec3(1.0);
  EXPECT_EQ(kernel::MarchVariant::of(white).key(), kernel::MarchVariant::of(s).key());
  const auto same = core::render_reference(sc.grid, medium, cam, sun, white);
  for (std::size_t i = 0; i < same.radiance.size(); ++i) EXPECT_EQ(same.radiance[i], grey.radiance[i]) << i;
}

}  // namespace
