// Depth in and out of the march, without any geometry yet: a depth texture at a known distance
// stops the march there, on the GPU and in the CPU kernel alike, with the closed forms of a uniform
// cloud; the opaque geometry's radiance composites behind; and the written cloud depth (where the
// view transmittance falls to 0.5) is ln 2 / sigma in a uniform cloud and matches the CPU's on a
// standard scene.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "kernel/prepared_volume.hpp"
#include "reference/raymarcher.hpp"
#include "render/context.hpp"
#include "render/gl.hpp"
#include "render/raymarcher.hpp"
#include "bench/standard_scenes.hpp"

namespace {
using namespace cv;

// 1/m, everywhere in the grid: the float the volume stores, so the closed forms use what is marched.
const double kSigma = static_cast<double>(0.002f);
constexpr int kSize = 9;          // odd: the centre pixel looks along the camera's axis

// A uniform liquid cloud filling a 4 x 4 degree box from the ground to 4 km; the camera inside it at
// 2 km looks straight up at the sun overhead. Along that ray the optical depth to the sun and from
// the camera add up to sigma (4000 - 2000) at every point, so the single-scattered radiance of the
// march up to distance D is a constant times D (in exact arithmetic, and for the march's steps too
// when D is a multiple of the view step: the step middles and the segment integral give every step
// the same factor).
struct UniformCloud {
  core::VolumeGrid grid;
  core::TimeStepData data;
  core::Camera cam;
  core::Sun sun;
  core::MarchSettings march;
  UniformCloud() {
    grid.lon_deg = {-2.0, 0.25, 17};
    grid.lat_deg = {-2.0, 0.25, 17};
    grid.alt_m = {0.0, 250.0, 17};
    data[core::Field::ExtinctionLiquid].assign(grid.points(), static_cast<float>(kSigma));
    cam.alt_m = 2000.0, cam.pitch_deg = 90.0, cam.fov_deg = 30.0, cam.width = kSize, cam.height = kSize;
    march.quality.view_step_m = 50.0;
    march.quality.octaves = 1;
  }
};

// A w x h float texture of 1 (R32F) or 4 (RGBA32F) channels holding v.
GLuint float_texture(int w, int h, int channels, const std::vector<float>& v) {
  GLuint t = 0;
  glCreateTextures(GL_TEXTURE_2D, 1, &t);
  glTextureStorage2D(t, 1, channels == 1 ? GL_R32F : GL_RGBA32F, w, h);
  glTextureSubImage2D(t, 0, 0, 0, w, h, channels == 1 ? GL_RED : GL_RGBA, GL_FLOAT, v.data());
  return t;
}

struct Both {
  std::vector<glm::vec4> gpu;
  std::vector<float> gpu_depth;
  core::ReferenceImage cpu;
};

// The scene rendered with opaque geometry at distance_m everywhere (0: none), optionally with its
// radiance, on the GPU and by the CPU kernel.
Both render_both(const UniformCloud& u, double distance_m, const std::vector<float>& rgba = {}) {
  auto ctx = render::make_headless_context();
  render::ShaderLoader loader({render::ShaderLoader::default_shader_dir()});
  render::GpuRaymarcher gpu(loader);
  const auto volume = std::make_shared<const core::PreparedVolume>(core::prepare_volume(u.grid, u.data));
  gpu.upload(volume);
  core::OpaqueLayer layer;
  layer.distance_m.assign(kSize * kSize, static_cast<float>(distance_m));
  layer.radiance_rgba = rgba;
  render::OpaqueInput in;
  if (distance_m > 0.0) in.depth = float_texture(kSize, kSize, 1, layer.distance_m);
  if (distance_m > 0.0 && !rgba.empty()) in.color = float_texture(kSize, kSize, 4, rgba);
  Both b;
  b.gpu = gpu.render(u.cam, u.sun, u.march, {}, in);
  b.gpu_depth = gpu.read_cloud_depth();
  b.cpu = core::render_reference(*volume, u.cam, u.sun, u.march, nullptr, nullptr, distance_m > 0.0 ? &layer : nullptr);
  if (in.depth) glDeleteTextures(1, &in.depth);
  if (in.color) glDeleteTextures(1, &in.color);
  return b;
}

constexpr int kCentre = (kSize / 2) * kSize + kSize / 2;

TEST(DepthIn, StopsTheMarchAtTheDistanceWithTheClosedFormTransmittance) {
  const UniformCloud u;
  for (double d : {200.0, 600.0}) {
    const Both b = render_both(u, d);
    for (int i = 0; i < kSize * kSize; ++i) {
      // Every ray crosses the uniform cloud for d: transmittance exp(-sigma d), whatever its direction.
      EXPECT_NEAR(b.cpu.transmittance[i], std::exp(-kSigma * d), 1e-12) << "pixel " << i << " at " << d << " m";
      EXPECT_NEAR(b.gpu[i].w, std::exp(-kSigma * d), 2e-6) << "pixel " << i << " at " << d << " m";
    }
  }
}

TEST(DepthIn, RadianceEqualsTheMarchTruncatedThere) {
  const UniformCloud u;
  const Both full = render_both(u, 0.0);  // the march to the top of the cloud, 2000 m up
  const Both at200 = render_both(u, 200.0), at600 = render_both(u, 600.0);
  const double l_full = full.cpu.radiance[kCentre].y;
  ASSERT_GT(l_full, 0.0);
  // Radiance proportional to the distance marched (see UniformCloud).
  EXPECT_NEAR(at200.cpu.radiance[kCentre].y / l_full, 200.0 / 2000.0, 1e-9);
  EXPECT_NEAR(at600.cpu.radiance[kCentre].y / l_full, 600.0 / 2000.0, 1e-9);
  EXPECT_NEAR(at200.gpu[kCentre].y / full.gpu[kCentre].y, 200.0 / 2000.0, 2e-5);
  EXPECT_NEAR(at600.gpu[kCentre].y / full.gpu[kCentre].y, 600.0 / 2000.0, 2e-5);
  // GPU and CPU kernel agree on every pixel.
  for (const Both* b : {&full, &at200, &at600}) {
    for (int i = 0; i < kSize * kSize; ++i) {
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(b->gpu[i][c], b->cpu.radiance[i][c], 1e-4 * l_full) << "pixel " << i;
    }
  }
}

TEST(DepthIn, CompositesTheGeometrysRadianceBehindTheCloud) {
  const UniformCloud u;
  std::vector<float> rgba(4 * kSize * kSize);
  for (int i = 0; i < kSize * kSize; ++i) rgba[4 * i] = 0.5f, rgba[4 * i + 1] = 0.25f, rgba[4 * i + 2] = 0.125f, rgba[4 * i + 3] = 1.0f;
  const Both open = render_both(u, 600.0), shown = render_both(u, 600.0, rgba);
  const double t = std::exp(-kSigma * 600.0);
  for (int i = 0; i < kSize * kSize; ++i) {
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(shown.cpu.radiance[i][c], open.cpu.radiance[i][c] + t * rgba[4 * i + c], 1e-12);
      EXPECT_NEAR(shown.gpu[i][c], open.gpu[i][c] + t * rgba[4 * i + c], 1e-5);
    }
    EXPECT_EQ(shown.cpu.transmittance[i], 0.0);
    EXPECT_EQ(shown.gpu[i].w, 0.0f);
  }
}

TEST(DepthOut, CloudDepthIsWhereTransmittanceFallsToHalf) {
  const UniformCloud u;
  const Both b = render_both(u, 0.0);
  for (int i = 0; i < kSize * kSize; ++i) {
    EXPECT_NEAR(b.cpu.cloud_depth_m[i], std::log(2.0) / kSigma, 1e-9) << "pixel " << i;
    EXPECT_NEAR(b.gpu_depth[i], std::log(2.0) / kSigma, 1e-2) << "pixel " << i;
  }
  // Stopped before it falls to 0.5: no cloud depth.
  const Both near = render_both(u, 200.0);
  EXPECT_EQ(near.cpu.cloud_depth_m[kCentre], 3.0e38);
  EXPECT_EQ(near.gpu_depth[kCentre], 3.0e38f);
}

TEST(DepthOut, CloudDepthMatchesTheCpuOnTheStratocumulusDeck) {
  const bench::StandardScene sc = bench::standard_scene("stratocumulus", 48, 27);
  auto ctx = render::make_headless_context();
  render::ShaderLoader loader({render::ShaderLoader::default_shader_dir()});
  render::GpuRaymarcher gpu(loader);
  const auto volume = std::make_shared<const core::PreparedVolume>(core::prepare_volume(sc.grid, sc.data));
  gpu.upload(volume);
  gpu.render(sc.camera, sc.sun, sc.march);
  const std::vector<float> depth = gpu.read_cloud_depth();
  const core::ReferenceImage cpu = core::render_reference(*volume, sc.camera, sc.sun, sc.march);
  int finite = 0, differ = 0;
  double worst = 0.0;
  for (std::size_t i = 0; i < depth.size(); ++i) {
    const bool g = depth[i] < 1e38f, c = cpu.cloud_depth_m[i] < 1e38;
    if (g != c) {
      ++differ;  // the transmittance within float rounding of 0.5 at the deck's far edge
      continue;
    }
    if (!g) continue;
    ++finite;
    worst = std::max(worst, std::abs(depth[i] - cpu.cloud_depth_m[i]) / cpu.cloud_depth_m[i]);
  }
  std::printf("cloud depth: %d pixels with one, worst relative difference %.3g, %d decided differently\n", finite, worst, differ);
  EXPECT_GT(finite, static_cast<int>(depth.size()) / 4);
  EXPECT_LT(worst, 1e-4);
  EXPECT_LE(differ, 1);
}

}  // namespace
