// Overlays composited with the clouds by depth (issue 15): the GPU overlay pass against the CPU
// cast of the same primitives; an opaque plane inside a uniform cloud on the GPU and the CPU
// reference against the closed form; a coastline vertex on the pixel the camera's projection
// gives, from orbit and from 100 m; an isosurface of an analytic sphere field; and no overlay, no
// VTK call and no pass.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <cstdio>
#include <map>
#include <memory>
#include <vector>

#include <glm/glm.hpp>

#include "support/scratch_dir.hpp"
#include "geo/geodesy.hpp"
#include "geometry/overlay_mesh.hpp"
#include "importer.hpp"
#include "kernel/prepared_volume.hpp"
#include "overlays/overlays.hpp"
#include "physics/physics.hpp"
#include "reference/monte_carlo.hpp"
#include "reference/raymarcher.hpp"
#include "render/context.hpp"
#include "render/frame_renderer.hpp"
#include "render/land_sea_mask.hpp"
#include "render/overlay_pass.hpp"
#include "support/cf_writer.hpp"

namespace {
using namespace cv;

const double kSigma = static_cast<double>(0.002f);  // 1/m, as the volume stores it
constexpr int kSize = 9;

// A uniform liquid cloud from the ground to 4 km over a 4 x 4 degree box; the camera inside it at
// 2 km looks straight up at the sun overhead (as tests/render/depth_io_test.cpp).
struct UniformCloud {
  core::VolumeGrid grid;
  core::TimeStepData data;
  core::FrameSpec frame;
  UniformCloud() {
    grid.lon_deg = {-2.0, 0.25, 17};
    grid.lat_deg = {-2.0, 0.25, 17};
    grid.alt_m = {0.0, 250.0, 17};
    data[core::Field::ExtinctionLiquid].assign(grid.points(), static_cast<float>(kSigma));
    core::Camera& cam = frame.camera;
    cam.alt_m = 2000.0, cam.pitch_deg = 90.0, cam.fov_deg = 30.0, cam.width = kSize, cam.height = kSize;
    frame.march_camera = cam;
    frame.march.quality.view_step_m = 50.0;
    frame.march.quality.octaves = 1;
  }
};

// A square plane `height_m` above the camera, normal up, 2 half_m wide, two triangles of one colour.
std::shared_ptr<core::OverlayMesh> plane_above(const core::Camera& cam, double r0, double height_m, glm::vec4 color, double half_m = 3000.0) {
  auto m = std::make_shared<core::OverlayMesh>();
  const glm::dvec3 up = glm::normalize(core::camera_ecef(cam, r0));
  const geo::EnuFrame f = geo::sphere_enu(cam.lat_deg, cam.lon_deg);
  const glm::dvec3 c = core::camera_ecef(cam, r0) + height_m * up;
  const double s = half_m;
  m->positions = {c - s * f.east - s * f.north, c + s * f.east - s * f.north, c + s * f.east + s * f.north, c - s * f.east + s * f.north};
  m->colors.assign(4, color);
  m->triangles = {0, 1, 2, 0, 2, 3};
  return m;
}

double pixel_up_cosine(const core::Camera& cam, int i, double r0) {
  return glm::dot(core::camera_ray(cam, i % cam.width, i / cam.width), glm::normalize(core::camera_ecef(cam, r0)));
}

TEST(OverlayPass, DrawsTheLayerTheCpuCasts) {
  auto ctx = render::make_headless_context();
  render::ShaderLoader loader({render::ShaderLoader::default_shader_dir()});
  render::OverlayPass pass(loader);
  const UniformCloud u;
  const double r0 = u.grid.earth_radius_m;
  const auto mesh = plane_above(u.frame.camera, r0, 600.0, {0.5f, 0.25f, 0.125f, 1.0f});
  pass.begin(u.frame.camera, r0);
  pass.draw(*mesh);
  const core::OpaqueLayer gpu = pass.read(), cpu = core::cast_overlay(*mesh, u.frame.camera, r0);
  for (int i = 0; i < kSize * kSize; ++i) {
    const double expected = 600.0 / pixel_up_cosine(u.frame.camera, i, r0);
    EXPECT_NEAR(cpu.distance_m[i], expected, 1e-3) << i;
    // float: the camera-relative vertices and the interpolated position, a few ulps of 600 m.
    EXPECT_NEAR(gpu.distance_m[i], expected, 2e-3) << i;
    // Both interpolate the vertices' colour (equal here) in float: a few ulps.
    for (int c = 0; c < 4; ++c) EXPECT_NEAR(gpu.radiance_rgba[4 * i + c], cpu.radiance_rgba[4 * i + c], 1e-6) << i;
  }
}

// A mesh held by a shared_ptr is uploaded once and kept while it is drawn each frame: a moving
// camera draws exactly the layer a fresh upload of the same mesh draws (the shader takes the camera
// off in double), and a mesh left out of a frame is released.
TEST(OverlayPass, KeptMeshesAreUploadedOnceAndDrawLikeFreshOnes) {
  auto ctx = render::make_headless_context();
  render::ShaderLoader loader({render::ShaderLoader::default_shader_dir()});
  render::OverlayPass kept(loader), fresh(loader);
  const UniformCloud u;
  const double r0 = u.grid.earth_radius_m;
  const std::shared_ptr<const core::OverlayMesh> mesh = plane_above(u.frame.camera, r0, 600.0, {0.5f, 0.25f, 0.125f, 1.0f});
  int drawn = 0;
  for (int frame = 0; frame < 4; ++frame) {
    core::Camera cam = u.frame.camera;
    cam.lon_deg += 0.001 * frame, cam.heading_deg += 2.0 * frame, cam.alt_m += 25.0 * frame;
    kept.begin(cam, r0);
    kept.draw(mesh);
    fresh.begin(cam, r0);
    fresh.draw(*mesh);
    const core::OpaqueLayer a = kept.read(), b = fresh.read();
    ASSERT_EQ(a.distance_m.size(), b.distance_m.size());
    for (std::size_t i = 0; i < a.distance_m.size(); ++i) {
      ASSERT_EQ(a.distance_m[i], b.distance_m[i]) << "frame " << frame << ", pixel " << i;
      drawn += a.distance_m[i] > 0.0f ? 1 : 0;
    }
    EXPECT_EQ(a.radiance_rgba, b.radiance_rgba) << "frame " << frame;
  }
  EXPECT_GT(drawn, 0);
  EXPECT_EQ(kept.uploads(), 1u);   // once, for four frames from four cameras
  EXPECT_EQ(fresh.uploads(), 4u);  // once per draw
  EXPECT_EQ(mesh.use_count(), 2);  // the pass holds it while it is drawn
  kept.begin(u.frame.camera, r0);  // a frame that does not draw it
  EXPECT_EQ(mesh.use_count(), 2);
  kept.begin(u.frame.camera, r0);  // and the next one: released
  EXPECT_EQ(mesh.use_count(), 1);
  kept.draw(mesh);
  EXPECT_EQ(kept.uploads(), 2u);
}

// The composite of an opaque plane inside the cloud: each pixel is the cloud in front of the plane
// (the march stopped at its distance, alpha the transmittance there) plus the plane's radiance
// times exp(-sigma d), d the distance to the plane along the pixel's ray; on the GPU through the
// frame renderer's overlay pass and on the CPU reference through the CPU cast.
TEST(OverlayComposite, OpaquePlaneInsideACloudOnTheGpuAndTheCpuReference) {
  auto ctx = render::make_headless_context();
  render::ShaderLoader loader({render::ShaderLoader::default_shader_dir()});
  const UniformCloud u;
  const double r0 = u.grid.earth_radius_m;
  const glm::vec4 color(0.5f, 0.25f, 0.125f, 1.0f);
  const auto mesh = plane_above(u.frame.camera, r0, 600.0, color);
  const auto volume = std::make_shared<const core::PreparedVolume>(core::prepare_volume(u.grid, u.data));

  render::FrameRenderer renderer(loader);
  renderer.use_volume(volume);
  renderer.set_overlays({{"plane", mesh, nullptr, 1.0f}});
  const std::vector<glm::vec4> gpu = renderer.render(u.frame);
  const core::OpaqueLayer drawn = renderer.read_overlays();
  // The cloud in front alone: the same distances, no radiance given (alpha is then the transmittance).
  core::OpaqueLayer depth_only = drawn;
  depth_only.radiance_rgba.clear();
  render::GpuRaymarcher& march = renderer.raymarcher();
  GLuint depth_tex = 0;
  glCreateTextures(GL_TEXTURE_2D, 1, &depth_tex);
  glTextureStorage2D(depth_tex, 1, GL_R32F, kSize, kSize);
  glTextureSubImage2D(depth_tex, 0, 0, 0, kSize, kSize, GL_RED, GL_FLOAT, drawn.distance_m.data());
  const std::vector<glm::vec4> front = march.render(u.frame.march_camera, u.frame.sun, u.frame.march, {}, {depth_tex, 0});
  glDeleteTextures(1, &depth_tex);

  const core::OpaqueLayer cast = core::cast_overlay(*mesh, u.frame.camera, r0);
  const core::ReferenceImage cpu = core::render_reference(*volume, u.frame.camera, u.frame.sun, u.frame.march, nullptr, nullptr, &cast);
  core::OpaqueLayer cast_depth = cast;
  cast_depth.radiance_rgba.clear();
  const core::ReferenceImage cpu_front =
      core::render_reference(*volume, u.frame.camera, u.frame.sun, u.frame.march, nullptr, nullptr, &cast_depth);

  double l_max = 0.0;
  for (int i = 0; i < kSize * kSize; ++i) l_max = std::max(l_max, cpu.radiance[i].y);
  ASSERT_GT(l_max, 0.0);
  for (int i = 0; i < kSize * kSize; ++i) {
    // The layers hold float distances and colours: the closed forms take what they hold, and
    // those are the plane's own to float precision.
    const double d = 600.0 / pixel_up_cosine(u.frame.camera, i, r0);
    ASSERT_NEAR(cast.distance_m[i], d, 1e-3) << i;
    ASSERT_NEAR(drawn.distance_m[i], d, 2e-3) << i;
    const double t_cpu = std::exp(-kSigma * static_cast<double>(cast.distance_m[i]));
    const double t_gpu = std::exp(-kSigma * static_cast<double>(drawn.distance_m[i]));
    // Transmittance in front of the plane: the closed form.
    EXPECT_NEAR(cpu_front.transmittance[i], t_cpu, 1e-12) << i;
    EXPECT_NEAR(front[i].w, t_gpu, 5e-6) << i;
    for (int c = 0; c < 3; ++c) {
      ASSERT_NEAR(cast.radiance_rgba[4 * i + c], color[c], 1e-6) << i;
      // CPU reference: cloud in front + colour x exp(-tau), to double precision.
      EXPECT_NEAR(cpu.radiance[i][c], cpu_front.radiance[i][c] + t_cpu * cast.radiance_rgba[4 * i + c], 1e-12) << i;
      // GPU: the same composite to float precision, and against the CPU within 1e-4 of the brightest pixel.
      EXPECT_NEAR(gpu[i][c], front[i][c] + t_gpu * drawn.radiance_rgba[4 * i + c], 1e-5) << i;
      EXPECT_NEAR(gpu[i][c], cpu.radiance[i][c], 1e-4 * l_max) << i;
    }
    EXPECT_EQ(gpu[i].w, 0.0f);  // nothing shows through the opaque plane
    EXPECT_EQ(cpu.transmittance[i], 0.0);
  }
}

// Translucent planes inside the uniform cloud, rendered on the GPU (the frame renderer's overlay
// pass, peeled) and on the CPU reference (the CPU cast), each as one image with the planes.
struct TranslucentRender {
  std::vector<glm::vec4> gpu;
  core::ReferenceImage cpu;
  core::OpaqueLayer drawn, cast;
};
TranslucentRender render_with(const UniformCloud& u, const std::vector<std::shared_ptr<core::OverlayMesh>>& planes) {
  render::ShaderLoader loader({render::ShaderLoader::default_shader_dir()});
  const auto volume = std::make_shared<const core::PreparedVolume>(core::prepare_volume(u.grid, u.data));
  render::FrameRenderer renderer(loader);
  renderer.use_volume(volume);
  std::vector<render::OverlayDraw> draws;
  core::OverlayMesh all;
  for (const auto& p : planes) draws.push_back({"plane", p, nullptr, 1.0f}), all.append(*p);
  renderer.set_overlays(draws);
  TranslucentRender r;
  r.gpu = renderer.render(u.frame);
  r.drawn = renderer.read_overlays();
  r.cast = core::cast_overlay(all, u.frame.camera, u.grid.earth_radius_m);
  r.cpu = core::render_reference(*volume, u.frame.camera, u.frame.sun, u.frame.march, nullptr, nullptr, &r.cast);
  return r;
}

// Without sunlight the cloud gathers no light of its own: a translucent plane (alpha a, radiance C)
// d from the camera gives exactly exp(-sigma d) a C, and the view transmittance is (1 - a) times
// the plane-free one. Two planes drawn far first come out nearest first: exp(-sigma d1) a1 C1 +
// exp(-sigma d2) (1 - a1) a2 C2, which the other order would not give.
TEST(OverlayComposite, TranslucentPlanesInsideACloudInDepthOrder) {
  auto ctx = render::make_headless_context();
  UniformCloud u;
  u.frame.sun.irradiance = glm::dvec3(0.0);
  const double r0 = u.grid.earth_radius_m;
  const glm::vec4 near_c(0.8f, 0.1f, 0.05f, 0.5f), far_c(0.05f, 0.6f, 0.3f, 0.25f);
  const auto near_p = plane_above(u.frame.camera, r0, 400.0, near_c), far_p = plane_above(u.frame.camera, r0, 800.0, far_c);
  const TranslucentRender none = render_with(u, {});
  const TranslucentRender one = render_with(u, {near_p});
  const TranslucentRender two = render_with(u, {far_p, near_p});
  ASSERT_EQ(one.cast.layers, core::kTranslucentLayers);
  ASSERT_EQ(one.drawn.layers, core::kTranslucentLayers);
  const std::size_t n = static_cast<std::size_t>(kSize) * kSize;
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t x = i % kSize, y = i / kSize;
    auto at = [&](int k) { return (y * core::kTranslucentLayers + static_cast<std::size_t>(k)) * kSize + x; };
    const double cosine = pixel_up_cosine(u.frame.camera, static_cast<int>(i), r0);
    // No opaque geometry; the layers nearest first, the third empty.
    EXPECT_EQ(two.drawn.distance_m[i], 0.0f) << i;
    EXPECT_EQ(two.cast.distance_m[i], 0.0f) << i;
    for (const core::OpaqueLayer* l : {&two.drawn, &two.cast}) {
      EXPECT_NEAR(l->layer_distance_m[at(0)], 400.0 / cosine, 2e-3) << i;
      EXPECT_NEAR(l->layer_distance_m[at(1)], 800.0 / cosine, 2e-3) << i;
      EXPECT_EQ(l->layer_distance_m[at(2)], 0.0f) << i;
    }
    for (int side = 0; side < 2; ++side) {  // 0: GPU, 1: CPU
      const core::OpaqueLayer& l1 = side ? one.cast : one.drawn;
      const core::OpaqueLayer& l2 = side ? two.cast : two.drawn;
      const double tol = side ? 1e-12 : 2e-6;  // double; float (exp of a float distance)
      // The closed forms take what the layers hold (float distances, and colours interpolated in
      // float), which are the planes' own to float precision.
      const double d1 = l2.layer_distance_m[at(0)], d2 = l2.layer_distance_m[at(1)];
      const double t1 = std::exp(-kSigma * d1), t2 = std::exp(-kSigma * d2);
      const float* c1 = &l2.layer_rgba[4 * at(0)];
      const float* c2 = &l2.layer_rgba[4 * at(1)];
      const float* c0 = &l1.layer_rgba[4 * at(0)];
      for (int c = 0; c < 4; ++c) {
        EXPECT_NEAR(c1[c], near_c[c], 1e-6) << i;
        EXPECT_NEAR(c2[c], far_c[c], 1e-6) << i;
      }
      for (int c = 0; c < 3; ++c) {
        const double single = std::exp(-kSigma * l1.layer_distance_m[at(0)]) * c0[3] * c0[c];
        const double pair = t1 * c1[3] * c1[c] + t2 * (1.0 - c1[3]) * c2[3] * c2[c];
        const double got1 = side ? one.cpu.radiance[i][c] : one.gpu[i][c];
        const double got2 = side ? two.cpu.radiance[i][c] : two.gpu[i][c];
        EXPECT_NEAR(got1, single, tol) << (side ? "CPU" : "GPU") << " pixel " << i << " channel " << c;
        EXPECT_NEAR(got2, pair, tol) << (side ? "CPU" : "GPU") << " pixel " << i << " channel " << c;
      }
      const double t_none = side ? none.cpu.transmittance[i] : none.gpu[i].w;
      const double t_two = side ? two.cpu.transmittance[i] : two.gpu[i].w;
      ASSERT_GT(t_none, 0.0);
      EXPECT_NEAR(t_two / t_none, (1.0 - c1[3]) * (1.0 - c2[3]), side ? 1e-12 : 1e-5) << i;
    }
  }
}

// The GPU path tracer with the overlays (path.glsl path_front): each view ray ends on the opaque
// geometry with its radiance, and the translucent fragments in front of its first vertex
// composite nearest first. Without sunlight the cloud adds no light, so a pixel's expectation is
// the closed form the march gives: exp(-sigma d) C behind an opaque plane d away, and
// exp(-sigma d1) a1 C1 + exp(-sigma d2) (1 - a1) a2 C2 through two translucent ones (a collision
// before a plane hides it). Each pixel's mean is held within 5 of its standard errors.
TEST(OverlayComposite, ThePathTracerSeesThePlanesInsideACloudAsTheClosedForms) {
  auto ctx = render::make_headless_context();
  UniformCloud u;
  u.frame.sun.irradiance = glm::dvec3(0.0);
  u.frame.march.features.atmosphere = false;
  const double r0 = u.grid.earth_radius_m;
  render::ShaderLoader loader({render::ShaderLoader::default_shader_dir()});
  const auto volume = std::make_shared<const core::PreparedVolume>(core::prepare_volume(u.grid, u.data));
  const glm::vec4 wall(0.5f, 0.25f, 0.125f, 1.0f), near_c(0.8f, 0.1f, 0.05f, 0.5f), far_c(0.05f, 0.6f, 0.3f, 0.25f);
  const int spp = 256;
  struct Case {
    const char* name;
    std::vector<std::shared_ptr<core::OverlayMesh>> planes;
  };
  const std::vector<Case> cases = {{"opaque", {plane_above(u.frame.camera, r0, 600.0, wall)}},
                                   {"translucent", {plane_above(u.frame.camera, r0, 800.0, far_c), plane_above(u.frame.camera, r0, 400.0, near_c)}}};
  for (const Case& k : cases) {
    render::FrameRenderer renderer(loader);
    renderer.use_volume(volume);
    std::vector<render::OverlayDraw> draws;
    for (const auto& p : k.planes) draws.push_back({"plane", p, nullptr, 1.0f});
    renderer.set_overlays(draws);
    core::MonteCarloImage img;
    renderer.trace_paths(img, u.frame, spp);
    const core::OpaqueLayer drawn = renderer.read_overlays();
    ASSERT_EQ(img.spp, static_cast<std::uint64_t>(spp));
    double worst_z = 0.0;
    for (int i = 0; i < kSize * kSize; ++i) {
      const std::size_t x = static_cast<std::size_t>(i % kSize), y = static_cast<std::size_t>(i / kSize);
      auto at = [&](int layer) { return (y * core::kTranslucentLayers + static_cast<std::size_t>(layer)) * kSize + x; };
      for (int c = 0; c < 3; ++c) {
        double expected = 0.0;
        if (k.planes.size() == 1) {
          ASSERT_GT(drawn.distance_m[i], 0.0f) << i;
          expected = std::exp(-kSigma * drawn.distance_m[i]) * drawn.radiance_rgba[4 * i + c];
        } else {
          const float* c1 = &drawn.layer_rgba[4 * at(0)];
          const float* c2 = &drawn.layer_rgba[4 * at(1)];
          ASSERT_NEAR(c1[3], near_c[3], 1e-6) << i;
          expected = std::exp(-kSigma * drawn.layer_distance_m[at(0)]) * c1[3] * c1[c] +
                     std::exp(-kSigma * drawn.layer_distance_m[at(1)]) * (1.0 - c1[3]) * c2[3] * c2[c];
        }
        const double mean = img.sum[static_cast<std::size_t>(i)][c] / spp;
        const double var = std::max(img.sum_sq[static_cast<std::size_t>(i)][c] / spp - mean * mean, 0.0);
        const double se = std::sqrt(var / (spp - 1));
        ASSERT_GT(expected, 0.0) << i;
        ASSERT_GT(se, 0.0) << "pixel " << i << ": the samples must differ (some paths collide before the planes)";
        const double z = (mean - expected) / se;
        worst_z = std::max(worst_z, std::abs(z));
        EXPECT_LT(std::abs(z), 5.0) << k.name << " pixel " << i << " channel " << c << ": " << mean << " against " << expected;
      }
    }
    std::printf("path tracer, %s planes inside the cloud, %d spp: largest |z| %.2f over %d pixels\n", k.name, spp, worst_z, kSize * kSize);
  }
}

// With the air and the sun on and no cloud, a path's view ray meets nothing before the opaque
// plane: its light is the air's in front of the plane plus the plane's radiance through the air,
// in every sample alike, which is the march's composite: the two images agree to float rounding.
// A plane 3 km above the camera (above the grid's top), and one 70 km above it, beyond the top of
// the air, which the march once dropped (it took the air's end for the geometry's).
TEST(OverlayComposite, ThePathTracerSeesAPlaneThroughTheAirAsTheMarchDoes) {
  auto ctx = render::make_headless_context();
  UniformCloud u;
  u.data[core::Field::ExtinctionLiquid].assign(u.grid.points(), 0.0f);
  u.frame.march.features.atmosphere = true;
  u.frame.march.quality.anti_alias = false;  // both through each pixel's centre
  u.frame.sun.subsolar_lat_deg = 30.0;
  const double r0 = u.grid.earth_radius_m;
  render::ShaderLoader loader({render::ShaderLoader::default_shader_dir()});
  const auto volume = std::make_shared<const core::PreparedVolume>(core::prepare_volume(u.grid, u.data));
  for (const double height : {3000.0, 70000.0}) {
    render::FrameRenderer renderer(loader);
    renderer.use_volume(volume);
    renderer.set_overlays({{"plane", plane_above(u.frame.camera, r0, height, {0.5f, 0.25f, 0.125f, 1.0f}, height < 1e4 ? 3000.0 : 40000.0),
                            nullptr, 1.0f}});
    const std::vector<glm::vec4> march = renderer.render(u.frame);
    core::MonteCarloImage img;
    renderer.trace_paths(img, u.frame, 2);
    const core::OpaqueLayer drawn = renderer.read_overlays();
    int on_plane = 0;
    for (int i = 0; i < kSize * kSize; ++i) {
      on_plane += drawn.distance_m[i] > 0.0f ? 1 : 0;
      const glm::dvec3 l = img.mean(static_cast<std::size_t>(i));
      for (int c = 0; c < 3; ++c) {
        ASSERT_GT(march[i][c], 0.0f) << i;
        EXPECT_NEAR(l[c], march[i][c], 1e-5 * march[i][c]) << "plane " << height << " m up, pixel " << i << " channel " << c;
      }
    }
    EXPECT_GT(on_plane, height < 1e4 ? kSize * kSize / 2 : kSize * kSize - 1) << "the test needs pixels that see the plane";
  }
}

// A plane of alpha 0 is translucent geometry that shows nothing: in a sunlit cloud the march
// divides the steps it crosses and the image must not change (the two parts of a step sum to the
// whole), to rounding.
TEST(OverlayComposite, AnInvisibleTranslucentPlaneLeavesTheLitCloudAsItWas) {
  auto ctx = render::make_headless_context();
  const UniformCloud u;
  const double r0 = u.grid.earth_radius_m;
  const TranslucentRender none = render_with(u, {});
  const TranslucentRender clear = render_with(u, {plane_above(u.frame.camera, r0, 437.0, {1.0f, 1.0f, 1.0f, 0.0f})});
  ASSERT_EQ(clear.cast.layers, core::kTranslucentLayers);
  double l_max = 0.0;
  for (const glm::dvec3& l : none.cpu.radiance) l_max = std::max(l_max, l.y);
  ASSERT_GT(l_max, 0.0);
  for (std::size_t i = 0; i < none.gpu.size(); ++i) {
    ASSERT_GT(clear.cast.layer_distance_m[(i / kSize * core::kTranslucentLayers) * kSize + i % kSize], 0.0f) << i;
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(clear.cpu.radiance[i][c], none.cpu.radiance[i][c], 1e-12 * l_max) << i;
      EXPECT_NEAR(clear.gpu[i][c], none.gpu[i][c], 1e-5 * l_max) << i;
    }
    EXPECT_NEAR(clear.cpu.transmittance[i], none.cpu.transmittance[i], 1e-12) << i;
    EXPECT_NEAR(clear.gpu[i].w, none.gpu[i].w, 1e-6) << i;
  }
}

TEST(OverlayComposite, NoOverlayMakesNoPassAndNoVtkCall) {
  auto ctx = render::make_headless_context();
  render::ShaderLoader loader({render::ShaderLoader::default_shader_dir()});
  const UniformCloud u;
  const auto volume = std::make_shared<const core::PreparedVolume>(core::prepare_volume(u.grid, u.data));
  render::FrameRenderer renderer(loader);
  renderer.use_volume(volume);
  const std::uint64_t runs = overlays::vtk_pipeline_runs();
  core::CloudVolume vol;
  vol.grid = u.grid;
  overlays::OverlayBuilder builder;
  const auto built = builder.build({}, vol, 0, u.frame.camera);
  renderer.set_overlays(overlays::OverlayBuilder::draws(built));
  const std::vector<glm::vec4> img = renderer.render(u.frame);
  EXPECT_TRUE(built.empty());
  EXPECT_EQ(overlays::vtk_pipeline_runs(), runs);
  EXPECT_FALSE(renderer.has_overlay_pass());
  EXPECT_TRUE(renderer.overlay_draw_ms().empty());
  // And the image is the march's own, bit for bit.
  const std::vector<glm::vec4> plain = renderer.raymarcher().render(u.frame.march_camera, u.frame.sun, u.frame.march);
  ASSERT_EQ(img.size(), plain.size());
  for (std::size_t i = 0; i < img.size(); ++i) EXPECT_EQ(img[i], plain[i]) << i;
}

TEST(OverlayBuilder, RebuildsOnlyWhenItsInputsChange) {
  core::CloudVolume vol;
  vol.grid.lon_deg = {-2.0, 0.25, 17};
  vol.grid.lat_deg = {-2.0, 0.25, 17};
  vol.grid.alt_m = {0.0, 250.0, 17};
  core::Camera cam;
  cam.alt_m = 5.0e6;
  overlays::OverlayBuilder builder;
  std::vector<core::OverlaySpec> specs = {core::default_overlay("graticule")};
  specs[0].numbers["label_px"] = 0.0;  // labels face the view and are made for each; the lines are cached
  const std::uint64_t r0 = overlays::vtk_pipeline_runs();
  auto a = builder.build(specs, vol, 0, cam);
  EXPECT_TRUE(a[0].rebuilt);
  EXPECT_EQ(overlays::vtk_pipeline_runs(), r0 + 1);
  auto b = builder.build(specs, vol, 1, cam);  // another time step: the graticule does not depend on it
  EXPECT_FALSE(b[0].rebuilt);
  EXPECT_EQ(b[0].mesh, a[0].mesh);
  EXPECT_EQ(overlays::vtk_pipeline_runs(), r0 + 1);
  specs[0].numbers["step_deg"] = 30.0;
  auto c = builder.build(specs, vol, 1, cam);
  EXPECT_TRUE(c[0].rebuilt);
  EXPECT_EQ(overlays::vtk_pipeline_runs(), r0 + 2);
}

TEST(Coastlines, ResolutionFollowsTheView) {
  EXPECT_EQ(overlays::coastline_resolution("auto", 3.6e7), 'c');
  EXPECT_EQ(overlays::coastline_resolution("auto", 5.0e5), 'l');
  EXPECT_EQ(overlays::coastline_resolution("auto", 5.0e4), 'i');
  EXPECT_EQ(overlays::coastline_resolution("auto", 1.0e4), 'h');
  EXPECT_EQ(overlays::coastline_resolution("auto", 100.0), 'f');
  EXPECT_EQ(overlays::coastline_resolution("l", 100.0), 'l');
}

TEST(Coastlines, MissingDataNamesThePackage) {
  try {
    overlays::build_coastlines("/nonexistent/gshhg", 'c', 6371000.0, glm::vec4(1.0f));
    FAIL() << "no error";
  } catch (const overlays::OverlayError& e) {
    EXPECT_EQ(std::string(e.what()),
              "overlays: coastlines: no GSHHG files (binned_GSHHS_c.nc) under /nonexistent/gshhg, expected the files of the Debian "
              "package gmt-gshhg-low (apt-get install gmt-gshhg-low gmt-common)");
  }
}

// The GMT library keeps a gmt.history file in the working folder unless told not to: reading the
// shorelines (every `render --overlay coastlines`) must leave the user's folder as it was.
TEST(Coastlines, ReadingThemLeavesNoFileInTheWorkingFolder) {
  const std::filesystem::path folder = std::filesystem::path(test_support::scratch_dir()) / "gmt_cwd";
  std::filesystem::create_directories(folder);
  const std::filesystem::path before = std::filesystem::current_path();
  std::filesystem::current_path(folder);
  std::size_t lines = 0;
  try {
    lines = overlays::read_gshhg_lines(overlays::GshhgFeature::Shore, 'c', "", {}).size();
  } catch (...) {
    std::filesystem::current_path(before);
    throw;
  }
  std::filesystem::current_path(before);
  EXPECT_GT(lines, 0u);
  std::vector<std::string> left;
  for (const auto& e : std::filesystem::directory_iterator(folder)) left.push_back(e.path().filename().string());
  EXPECT_TRUE(left.empty()) << "left in the working folder: " << left.front();
}

// The crude GSHHG shoreline's vertex nearest 64.1 N, 21.9 W (Iceland), and its distance in degrees.
static void icelandic_shore_vertex(double& best, double& lat, double& lon) {
  for (const auto& line : overlays::read_gshhg_lines(overlays::GshhgFeature::Shore, 'c', "", {})) {
    for (const glm::dvec2& p : line) {
      const double dd = std::hypot(p.y - 64.1, (p.x + 21.9) * std::cos(64.1 * 3.14159265358979 / 180.0));
      if (dd < best) best = dd, lon = p.x, lat = p.y;
    }
  }
}

// A GSHHG vertex of Iceland's shore (the crude shoreline's point nearest 64.1 N, 21.9 W), its
// lat/lon as the GMT library reads it, drawn by the overlay pass from the camera: it lands on the
// pixel the camera's projection gives (within one pixel), from orbit and from 100 m.
TEST(Coastlines, AVertexLandsOnThePixelTheProjectionGives) {
  double best = 1e9, lat = 0.0, lon = 0.0;
  icelandic_shore_vertex(best, lat, lon);
  ASSERT_LT(best, 1.0) << "no Icelandic vertex in the crude GSHHG shorelines";
  const double r0 = 6371000.0;
  const core::OverlayMesh coast = overlays::build_coastlines(overlays::kGshhgDir, 'c', r0, glm::vec4(1.0f));
  const glm::dvec3 v = geo::sphere_to_ecef({lat, lon, 0.0}, r0);
  std::size_t vi = coast.positions.size();
  for (std::size_t i = 0; i < coast.positions.size(); ++i) {
    // The vertex is lifted so its chords stay above the sphere: 8 cm at most for 2 km pieces.
    if (glm::length(coast.positions[i] - v) < 0.1) vi = i;
  }
  ASSERT_LT(vi, coast.positions.size()) << "the vertex " << lat << ", " << lon << " is not in the mesh";
  // The vertex's own segments only, so no other shore can cover the pixel.
  core::OverlayMesh near;
  near.positions = coast.positions;
  near.colors = coast.colors;
  for (std::size_t k = 0; k + 1 < coast.lines.size(); k += 2) {
    if (coast.lines[k] == vi || coast.lines[k + 1] == vi) near.lines.insert(near.lines.end(), {coast.lines[k], coast.lines[k + 1]});
  }
  ASSERT_FALSE(near.lines.empty());

  auto ctx = render::make_headless_context();
  render::ShaderLoader loader({render::ShaderLoader::default_shader_dir()});
  render::OverlayPass pass(loader);
  struct View {
    const char* name;
    double back_deg, alt_m, pitch_deg;
  };
  // From orbit: 400 km up, 3 degrees south, looking north and down; from 100 m: 2 km south, level.
  for (const View& view : {View{"orbit", 3.0, 4.0e5, -55.0}, View{"100 m", 2000.0 / 111195.0, 100.0, -2.0}}) {
    core::Camera cam;
    cam.lat_deg = lat - view.back_deg, cam.lon_deg = lon, cam.alt_m = view.alt_m, cam.pitch_deg = view.pitch_deg;
    cam.heading_deg = 0.0, cam.fov_deg = 40.0, cam.width = 320, cam.height = 180;
    const core::Projected q = core::project_point(cam, v - core::camera_ecef(cam, r0));
    ASSERT_TRUE(q.in_front) << view.name;
    ASSERT_TRUE(q.x > 0 && q.x < cam.width && q.y > 0 && q.y < cam.height) << view.name << ": " << q.x << ", " << q.y;
    pass.begin(cam, r0);
    pass.draw(near);
    const core::OpaqueLayer layer = pass.read();
    const int px = static_cast<int>(q.x), py = static_cast<int>(q.y);
    // A drawn pixel within one pixel of the prediction, at the vertex's distance there: within the
    // distance one pixel spans along the line (its footprint over the grazing angle, bounded here
    // by 2 % of the distance from 100 m and 0.5 % from orbit).
    int found = 0;
    double nearest = 1e30;
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        const float d = layer.distance_m[static_cast<std::size_t>(py + dy) * cam.width + px + dx];
        if (d > 0.0f) ++found, nearest = std::min(nearest, std::abs(d - q.distance_m));
      }
    }
    EXPECT_GT(found, 0) << view.name << ": nothing drawn within a pixel of " << q.x << ", " << q.y;
    EXPECT_LT(nearest, (view.alt_m < 1000.0 ? 0.02 : 0.005) * q.distance_m) << view.name;
    // Nothing drawn far from the vertex's segments: the line is where the projection puts it.
    const core::OpaqueLayer cpu = core::cast_overlay(near, cam, r0);
    int gpu_only = 0;
    for (int y = 0; y < cam.height; ++y) {
      for (int x = 0; x < cam.width; ++x) {
        if (layer.distance_m[static_cast<std::size_t>(y) * cam.width + x] == 0.0f) continue;
        bool cpu_near = false;
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) {
            const int xx = x + dx, yy = y + dy;
            if (xx >= 0 && yy >= 0 && xx < cam.width && yy < cam.height && cpu.distance_m[static_cast<std::size_t>(yy) * cam.width + xx] > 0.0f) cpu_near = true;
          }
        }
        gpu_only += cpu_near ? 0 : 1;
      }
    }
    EXPECT_EQ(gpu_only, 0) << view.name << ": GPU pixels more than a pixel from the CPU's cast of the same lines";
  }
}

// The coastlines lie on the renderer's globe as the ground and the clouds do: geodetic latitude and
// longitude placed as the sphere's own (the march's ground lookup inverts a point with the shared
// ecef_to_sphere and reads the equirectangular texel there; the importers place the clouds' columns
// by the same latitudes). A GSHHG vertex of Iceland's shore, taken from the built mesh and inverted
// by the march's own functions (compiled in double), lands on the texel its latitude and longitude
// name. Put on the WGS84 ellipsoid instead, it would land 0.15 degrees (17 km) south of that
// texel's coast on this globe.
TEST(Coastlines, AVertexLiesOnTheTexelTheGroundLookupGivesItsLatLon) {
  double best = 1e9, lat = 0.0, lon = 0.0;
  icelandic_shore_vertex(best, lat, lon);
  ASSERT_LT(best, 1.0) << "no Icelandic vertex in the crude GSHHG shorelines";
  const double r0 = 6371000.0, kRad = 3.14159265358979323846 / 180.0;
  const core::OverlayMesh coast = overlays::build_coastlines(overlays::kGshhgDir, 'c', r0, glm::vec4(1.0f));
  const glm::dvec3 v = geo::sphere_to_ecef({lat, lon, 0.0}, r0);
  std::size_t vi = coast.positions.size();
  for (std::size_t i = 0; i < coast.positions.size(); ++i) {
    if (glm::length(coast.positions[i] - v) < 0.1) vi = i;  // lifted by 8 cm at most (2 km chords)
  }
  ASSERT_LT(vi, coast.positions.size()) << "the vertex " << lat << ", " << lon << " is not in the mesh";
  // The march's inverse (shaders/common/geodesy.glsl) and texel lookup (ground.glsl), in double.
  const glm::dvec3 g = physics::f64::ecef_to_sphere(coast.positions[vi], r0);
  EXPECT_NEAR(g.x / kRad, lat, 1e-9);
  EXPECT_NEAR(g.y / kRad, lon, 1e-9);
  EXPECT_LT(g.z, 0.1);  // on the ground (the lift of its chords)
  const int w = 8192, h = 4096;  // a fine ground image: 0.044 degrees a texel
  const glm::dvec4 at_vertex = physics::f64::equirect_texel(g.x, g.y, w, h);
  const glm::dvec4 at_latlon = physics::f64::equirect_texel(lat * kRad, lon * kRad, w, h);
  EXPECT_NEAR(at_vertex.x + at_vertex.z, at_latlon.x + at_latlon.z, 1e-6) << "texels across";
  EXPECT_NEAR(at_vertex.y + at_vertex.w, at_latlon.y + at_latlon.w, 1e-6) << "texels down";
  // The ellipsoid's point for the same latitude, inverted the same way: its geocentric latitude,
  // 3.4 texels away. The test tells the two mappings apart.
  const glm::dvec3 e = physics::f64::ecef_to_sphere(geo::wgs84_to_ecef({lat, lon, 0.0}), r0);
  const glm::dvec4 at_ellipsoid = physics::f64::equirect_texel(e.x, e.y, w, h);
  EXPECT_GT(std::abs(at_ellipsoid.y + at_ellipsoid.w - (at_latlon.y + at_latlon.w)), 3.0) << "texels down";
}

TEST(GraticuleLabels, StrokesStandBesideTheirCrossingsInTheImage) {
  EXPECT_EQ(overlays::label_strokes("60N").size(), 6u + 6u + 3u);  // 6: afgedc, 0: abcdef, N: three strokes
  EXPECT_EQ(overlays::label_strokes("1").size(), 2u);
  core::Camera cam;
  cam.lat_deg = -20.0, cam.alt_m = 3.0e6, cam.pitch_deg = -70.0, cam.fov_deg = 50.0, cam.width = 160, cam.height = 90;
  const double r0 = 6371000.0;
  const core::OverlayMesh labels = overlays::graticule_labels(10.0, cam, r0, glm::vec4(1.0f), 12.0);
  ASSERT_GT(labels.lines.size(), 20u);
  // Every stroke end lands in the image, and the strokes are about 12 px high: their projected
  // heights (y spans per label) never exceed 13 px.
  const glm::dvec3 c = core::camera_ecef(cam, r0);
  for (const glm::dvec3& p : labels.positions) {
    const core::Projected q = core::project_point(cam, p - c);
    ASSERT_TRUE(q.in_front);
    EXPECT_GT(q.x, -1.0);
    EXPECT_LT(q.y, cam.height + 13.0);
  }
  // Drawn by the overlay pass: the labels cover pixels the lines alone do not.
  auto ctx = render::make_headless_context();
  render::ShaderLoader loader({render::ShaderLoader::default_shader_dir()});
  render::OverlayPass pass(loader);
  const core::OverlayMesh lines = overlays::build_graticule(10.0, r0, glm::vec4(1.0f));
  core::OverlayMesh both = lines;
  both.append(labels);
  auto covered = [&](const core::OverlayMesh& m) {
    pass.begin(cam, r0);
    pass.draw(m);
    int n = 0;
    for (float d : pass.read().distance_m) n += d > 0.0f ? 1 : 0;
    return n;
  };
  const int n_lines = covered(lines), n_both = covered(both);
  EXPECT_GT(n_lines, 100);
  EXPECT_GT(n_both, n_lines + 50) << "labels drew " << n_both - n_lines << " pixels";
}

// A solid-body rotation of the wind about the grid's centre column, written so that in grid
// indices (where the tracer integrates) it is a rotation at omega: u = -omega (j - j0) dx_j,
// v = omega (i - i0) dy, dx_j the cell's width at its latitude. A streamline started r cells from
// the centre and followed 2 pi r cells closes on itself: within 1e-3 of r (RK45 at a 1e-8 error
// per step; the field is linear in the indices, so the trilinear interpolation is exact).
TEST(Wind, AStreamlineInAUniformRotationClosesOnItself) {
  core::VolumeGrid g;
  g.lon_deg = {-0.5, 0.05, 21};
  g.lat_deg = {-0.5, 0.05, 21};
  g.alt_m = {0.0, 500.0, 5};
  const double kDeg = 3.14159265358979323846 / 180.0, omega = 1e-4, i0 = 10.0, j0 = 10.0;
  std::vector<float> u(g.points()), v(g.points()), w;
  for (int k = 0; k < g.alt_m.count; ++k) {
    const double r = g.earth_radius_m + g.alt_m.at(k);
    for (int j = 0; j < g.lat_deg.count; ++j) {
      const double dx = r * std::cos(g.lat_deg.at(j) * kDeg) * g.lon_deg.step * kDeg, dy = r * g.lat_deg.step * kDeg;
      for (int i = 0; i < g.lon_deg.count; ++i) {
        u[g.index(i, j, k)] = static_cast<float>(-omega * (j - j0) * dx);
        v[g.index(i, j, k)] = static_cast<float>(omega * (i - i0) * dy);
      }
    }
  }
  for (double radius : {3.0, 6.0}) {
    std::vector<std::vector<glm::dvec3>> lines;
    const core::OverlayMesh m = overlays::build_streamlines_from(g, u, v, w, {{i0 + radius, j0, 2.0}}, 2.0 * 3.14159265358979323846 * radius,
                                                                  30.0, 1.0, &lines);
    ASSERT_EQ(lines.size(), 1u);
    ASSERT_GT(lines[0].size(), 20u);
    const glm::dvec3 start = lines[0].front(), end = lines[0].back();
    double worst_radius = 0.0;
    for (const glm::dvec3& p : lines[0]) worst_radius = std::max(worst_radius, std::abs(std::hypot(p.x - i0, p.y - j0) - radius));
    EXPECT_LT(glm::length(end - start), 1e-3 * radius) << "radius " << radius << ": the streamline ends " << glm::length(end - start)
                                                        << " cells from its start";
    EXPECT_LT(worst_radius, 1e-3 * radius) << "radius " << radius;
    EXPECT_EQ(m.lines.size(), 2 * (lines[0].size() - 1));
  }
}

// Sections: a horizontal slice through a field that grows with longitude lies at its altitude and
// carries the field's colours; a vertical curtain between two points stands on their great circle;
// the legend's bar and text lie 1 m in front of the camera, inside the image.
TEST(Section, SlicesLieWhereAskedAndCarryTheField) {
  core::VolumeGrid g;
  g.lon_deg = {-1.0, 0.1, 21};
  g.lat_deg = {-1.0, 0.1, 21};
  g.alt_m = {0.0, 500.0, 9};
  std::vector<float> f(g.points());
  for (int k = 0; k < g.alt_m.count; ++k) {
    for (int j = 0; j < g.lat_deg.count; ++j) {
      for (int i = 0; i < g.lon_deg.count; ++i) f[g.index(i, j, k)] = static_cast<float>(i) / 20.0f;  // 0..1 west to east
    }
  }
  const overlays::FieldColor by{nullptr, 0.0, 1.0, 1.0};
  const core::OverlayMesh h = overlays::build_horizontal_section(g, f, 1250.0, by);
  ASSERT_GT(h.triangles.size(), 100u);
  for (std::size_t i = 0; i < h.positions.size(); ++i) {
    const geo::Geodetic p = geo::ecef_to_sphere(h.positions[i], g.earth_radius_m);
    EXPECT_NEAR(p.alt_m, 1250.0, 1e-6);
    const glm::vec4 expected = overlays::colormap((p.lon_deg + 1.0) / 2.0);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(h.colors[i][c], expected[c], 1e-5) << i;
  }
  const core::OverlayMesh v = overlays::build_vertical_section(g, f, -0.5, -0.5, 0.5, 0.5, by, 32);
  ASSERT_EQ(v.triangles.size(), 6u * 31u * 8u);
  const glm::dvec3 n = glm::normalize(glm::cross(geo::sphere_to_ecef({-0.5, -0.5, 0.0}, 1.0), geo::sphere_to_ecef({0.5, 0.5, 0.0}, 1.0)));
  for (const glm::dvec3& p : v.positions) EXPECT_NEAR(glm::dot(glm::normalize(p), n), 0.0, 1e-12);  // on the great circle's plane

  core::Camera cam;
  cam.alt_m = 3000.0, cam.pitch_deg = -30.0, cam.width = 160, cam.height = 90;
  const core::OverlayMesh bar = overlays::colour_bar(cam, g.earth_radius_m, "extinction_liquid 1/m", 0.0, 1e-3, 1.0, 8.0);
  ASSERT_GT(bar.triangles.size(), 30u);
  ASSERT_GT(bar.lines.size(), 100u);
  const glm::dvec3 c = core::camera_ecef(cam, g.earth_radius_m);
  for (const glm::dvec3& p : bar.positions) {
    const core::Projected q = core::project_point(cam, p - c);
    EXPECT_NEAR(glm::dot(p - c, core::camera_frame(cam).forward), 1.0, 1e-6);
    EXPECT_TRUE(q.x >= 0.0 && q.x <= cam.width && q.y >= 0.0 && q.y <= cam.height) << q.x << ", " << q.y;
  }
}

// An analytic sphere in a field (the distance from a point 3 km up, in metres): the isosurface at
// 2 km lies on that sphere within a tenth of a cell.
TEST(Isosurface, AnalyticSphereWithinATenthOfACell) {
  core::VolumeGrid g;
  g.lon_deg = {-0.05, 0.0025, 41};  // 278 m cells
  g.lat_deg = {-0.05, 0.0025, 41};
  g.alt_m = {0.0, 250.0, 25};
  const glm::dvec3 centre = geo::sphere_to_ecef({0.0, 0.0, 3000.0}, g.earth_radius_m);
  std::vector<float> f(g.points());
  for (int k = 0; k < g.alt_m.count; ++k) {
    for (int j = 0; j < g.lat_deg.count; ++j) {
      for (int i = 0; i < g.lon_deg.count; ++i) {
        const glm::dvec3 p = geo::sphere_to_ecef({g.lat_deg.at(j), g.lon_deg.at(i), g.alt_m.at(k)}, g.earth_radius_m);
        f[g.index(i, j, k)] = static_cast<float>(glm::length(p - centre));
      }
    }
  }
  const core::OverlayMesh m = overlays::build_isosurface(g, f, 2000.0, glm::vec4(1.0f));
  ASSERT_GT(m.triangles.size(), 300u);
  const double cell = std::min({g.alt_m.step, g.lat_deg.step * 111195.0});
  double worst = 0.0;
  for (const glm::dvec3& p : m.positions) worst = std::max(worst, std::abs(glm::length(p - centre) - 2000.0));
  EXPECT_LT(worst, 0.1 * cell) << "largest radius error " << worst << " m against cells of " << cell << " m";
  // Closed: every edge of the triangles shared by two of them.
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> edges;
  for (std::size_t t = 0; t + 2 < m.triangles.size(); t += 3) {
    for (int e = 0; e < 3; ++e) {
      std::uint32_t a = m.triangles[t + e], b = m.triangles[t + (e + 1) % 3];
      ++edges[{std::min(a, b), std::max(a, b)}];
    }
  }
  for (const auto& [edge, n] : edges) EXPECT_EQ(n, 2);
}

// Borders and rivers from GSHHG through GMT (Debian's gmt-gshhg-low): the US-Canada border runs
// along 49 N from the Lake of the Woods to the Strait of Georgia, the Nile's branches meet at
// Khartoum (15.6 N, 32.5 E), every vertex lies on the sphere, a regional box keeps what is inside
// it, and missing files are named with their package.
std::vector<geo::Geodetic> vertices_of(const core::OverlayMesh& m, double r0) {
  std::vector<geo::Geodetic> out;
  for (const glm::dvec3& p : m.positions) out.push_back(geo::ecef_to_sphere(p, r0));
  return out;
}

TEST(OverlayGshhg, BordersAndRiversLieWhereTheMapsPutThem) {
  const double r0 = 6371000.0;
  const core::OverlayMesh borders = overlays::build_gshhg(overlays::GshhgFeature::Border, 'l', "1", {}, r0, glm::vec4(1.0f));
  ASSERT_FALSE(borders.lines.empty());
  int on_49 = 0;
  double worst = 0.0;
  for (const geo::Geodetic& g : vertices_of(borders, r0)) {
    EXPECT_LT(std::abs(g.alt_m), 100.0);  // on the sphere (lifted a little so chords stay above it)
    if (g.lon_deg > -120.0 && g.lon_deg < -96.0 && g.lat_deg > 46.0 && g.lat_deg < 52.0) {
      ++on_49;
      worst = std::max(worst, std::abs(g.lat_deg - 49.0));
    }
  }
  EXPECT_GT(on_49, 10);
  EXPECT_LT(worst, 0.01) << "a national border vertex between 120 W and 96 W off the 49th parallel";

  const core::OverlayMesh rivers = overlays::build_gshhg(overlays::GshhgFeature::River, 'l', "1", {}, r0, glm::vec4(1.0f));
  double nearest = 1e30;
  for (const geo::Geodetic& g : vertices_of(rivers, r0)) nearest = std::min(nearest, std::hypot(g.lat_deg - 15.6, g.lon_deg - 32.53));
  EXPECT_LT(nearest, 0.15) << "no major river vertex near Khartoum";

  overlays::GeoBox box;
  box.global = false, box.lon_min = 30.0, box.lon_max = 34.0, box.lat_min = 13.0, box.lat_max = 18.0;
  const core::OverlayMesh inside = overlays::build_gshhg(overlays::GshhgFeature::River, 'l', "1", box, r0, glm::vec4(1.0f));
  ASSERT_FALSE(inside.lines.empty());
  for (const geo::Geodetic& g : vertices_of(inside, r0)) {
    // Within 1e-5 degrees (a metre): the great-circle pieces between two vertices on the box's edge
    // (0.05 degrees apart at most) bulge from it by that much.
    EXPECT_TRUE(g.lon_deg >= 30.0 - 1e-5 && g.lon_deg <= 34.0 + 1e-5 && g.lat_deg >= 13.0 - 1e-5 && g.lat_deg <= 18.0 + 1e-5)
        << g.lat_deg << ", " << g.lon_deg;
  }
  EXPECT_LT(inside.positions.size(), rivers.positions.size() / 10);

  try {
    overlays::build_gshhg(overlays::GshhgFeature::Border, 'h', "1", {}, r0, glm::vec4(1.0f), "/nonexistent");
    ADD_FAILURE() << "no error without the files";
  } catch (const overlays::OverlayError& e) {
    EXPECT_EQ(std::string(e.what()),
              "overlays: borders: no GSHHG files (binned_border_h.nc) under /nonexistent, expected the files of the Debian package "
              "gmt-gshhg-high (apt-get install gmt-gshhg-high gmt-common)");
  }
}

// A scene's borders and rivers through the builder: the class is checked, and the geometry is
// kept until the resolution the view asks for changes.
TEST(OverlayGshhg, TheBuilderChecksTheClassAndKeepsTheGeometry) {
  core::CloudVolume vol;
  vol.grid.lon_deg = {-2.0, 0.25, 17};
  vol.grid.lat_deg = {-2.0, 0.25, 17};
  vol.grid.alt_m = {0.0, 250.0, 17};
  std::vector<core::OverlaySpec> specs = {core::default_overlay("borders"), core::default_overlay("rivers")};
  specs[1].texts["class"] = "lakes";
  try {
    overlays::check_overlays(specs, vol);
    ADD_FAILURE() << "no error for class lakes";
  } catch (const overlays::OverlayError& e) {
    EXPECT_EQ(std::string(e.what()), "overlays[1].class: found \"lakes\", expected major, permanent or all");
  }
  specs[1].texts["class"] = "major";
  overlays::check_overlays(specs, vol);
  overlays::OverlayBuilder builder;
  core::Camera cam;
  cam.alt_m = 5.0e6;  // crude
  const auto a = builder.build(specs, vol, 0, cam);
  ASSERT_EQ(a.size(), 2u);
  EXPECT_TRUE(a[0].rebuilt && a[1].rebuilt);
  EXPECT_FALSE(a[0].mesh->lines.empty());
  EXPECT_FALSE(a[1].mesh->lines.empty());
  const auto b = builder.build(specs, vol, 0, cam);
  EXPECT_FALSE(b[0].rebuilt || b[1].rebuilt);
  EXPECT_EQ(b[0].mesh, a[0].mesh);
  cam.alt_m = 1.0e6;  // low
  const auto c = builder.build(specs, vol, 0, cam);
  EXPECT_TRUE(c[0].rebuilt);
  EXPECT_GT(c[0].mesh->positions.size(), a[0].mesh->positions.size());
}

// Wind arrows (instanced): a grid whose wind turns about (0, 0) as a solid body, u = -omega y and
// v = omega x (x, y the node's east and north distances from the centre, m), times 1 + 0.25 k on
// level k, so the wind at a level between two is their linear mix.
struct RotatingWind {
  core::VolumeGrid grid;
  std::vector<float> u, v;
  static constexpr double kOmega = 1e-4, kDeg = 3.14159265358979323846 / 180.0;
  explicit RotatingWind(double step_deg) {
    grid.lon_deg = {-10 * step_deg, step_deg, 21};
    grid.lat_deg = {-10 * step_deg, step_deg, 21};
    grid.alt_m = {0.0, 500.0, 9};
    u.resize(grid.points()), v.resize(grid.points());
    for (int k = 0; k < grid.alt_m.count; ++k) {
      for (int j = 0; j < grid.lat_deg.count; ++j) {
        for (int i = 0; i < grid.lon_deg.count; ++i) {
          const glm::dvec2 w = wind(i, j, k);
          u[grid.index(i, j, k)] = static_cast<float>(w.x), v[grid.index(i, j, k)] = static_cast<float>(w.y);
        }
      }
    }
  }
  // The wind (east, north) at node (i, j) on the fractional level z, in closed form.
  glm::dvec2 wind(int i, int j, double z) const {
    const double lat = grid.lat_deg.at(j), lon = grid.lon_deg.at(i);
    const double x = grid.earth_radius_m * std::cos(lat * kDeg) * lon * kDeg, y = grid.earth_radius_m * lat * kDeg;
    return (1.0 + 0.25 * z) * kOmega * glm::dvec2(-y, x);
  }
};

// Each arrow stands on its grid point at the level, points along the wind there in the local east
// and north frame, is as long as the speed says (scale x spacing x speed / speed_max) and is
// coloured by the speed.
TEST(Arrows, StandOnTheLevelAlongTheWindWithLengthsProportionalToSpeed) {
  const RotatingWind w(0.1);
  const core::VolumeGrid& g = w.grid;
  overlays::ArrowStyle style;
  style.spacing_cells = 4, style.scale = 0.8, style.speed_min_m_s = 2.0, style.speed_max_m_s = 40.0, style.brightness = 3.0;
  const double level = 1250.0, z = level / g.alt_m.step;  // halfway between levels 2 and 3
  const core::OverlayMesh m = overlays::build_arrows(g, w.u, w.v, level, style);
  const core::OverlayInstances& in = m.instances;
  EXPECT_TRUE(m.triangles.empty() && m.lines.empty());  // all of it instanced
  ASSERT_FALSE(in.glyph_triangles.empty());
  ASSERT_EQ(in.count(), 36u);  // 6 x 6 grid points: 0, 4, ..., 20 each way (the calm centre, 10, is not one)
  ASSERT_EQ(in.axis_x.size(), in.count());
  ASSERT_EQ(in.colors.size(), in.count());
  const double spacing_m = 4 * (g.earth_radius_m + level) * 0.1 * RotatingWind::kDeg;
  const double per_m_s = style.scale * spacing_m / style.speed_max_m_s;
  std::size_t k = 0;
  double worst_angle = 0.0, worst_length = 0.0;
  for (int j = 0; j <= 20; j += 4) {
    for (int i = 0; i <= 20; i += 4) {
      ASSERT_LT(k, in.count());
      const double lat = g.lat_deg.at(j), lon = g.lon_deg.at(i);
      const geo::EnuFrame f = geo::sphere_enu(lat, lon);
      EXPECT_LT(glm::length(in.origins[k] - geo::sphere_to_ecef({lat, lon, level}, g.earth_radius_m)), 1e-6) << k;
      const glm::dvec2 wind = w.wind(i, j, z);
      const double speed = glm::length(wind);
      const glm::dvec3 expected = (wind.x * f.east + wind.y * f.north) / speed;
      const glm::dvec3 ax(in.axis_x[k]), ay(in.axis_y[k]), az(in.axis_z[k]);
      worst_angle = std::max(worst_angle, std::acos(std::clamp(glm::dot(glm::normalize(ax), expected), -1.0, 1.0)));
      worst_length = std::max(worst_length, std::abs(glm::length(ax) / (per_m_s * speed) - 1.0));
      // y to the left of the wind and z up, as long as x: the glyph keeps its proportions.
      EXPECT_NEAR(glm::dot(glm::normalize(ay), glm::cross(f.up, expected)), 1.0, 1e-6) << k;
      EXPECT_NEAR(glm::dot(glm::normalize(az), f.up), 1.0, 1e-6) << k;
      EXPECT_NEAR(glm::length(ay) / glm::length(ax), 1.0, 1e-6) << k;
      EXPECT_NEAR(glm::length(az) / glm::length(ax), 1.0, 1e-6) << k;
      const glm::vec4 c = overlays::colormap((speed - style.speed_min_m_s) / (style.speed_max_m_s - style.speed_min_m_s), style.brightness);
      for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(in.colors[k][ch], c[ch], 1e-5f * style.brightness) << k;
      ++k;
    }
  }
  // The wind is stored in float and the axes are floats: both a few parts in 1e7.
  std::printf("arrows against the rotating wind: worst direction %.3g rad, worst length %.3g relative\n", worst_angle, worst_length);
  EXPECT_LT(worst_angle, 1e-6) << "radians between an arrow and the wind";
  EXPECT_LT(worst_length, 1e-6) << "relative error of an arrow's length against scale x spacing x speed / speed_max";
  // The glyph runs from -0.5 (tail) to 0.5 (tip) along x: the arrow's middle is on the grid point.
  float x0 = 1e9f, x1 = -1e9f;
  for (const glm::vec3& p : in.glyph_positions) x0 = std::min(x0, p.x), x1 = std::max(x1, p.x);
  EXPECT_NEAR(x0, -0.5f, 1e-6f);
  EXPECT_NEAR(x1, 0.5f, 1e-6f);
}

// A uniform wind from the south-west: every arrow points north-east and all are equally long.
TEST(Arrows, AUniformWindGivesParallelArrowsOfOneLength) {
  core::VolumeGrid g;
  g.lon_deg = {10.0, 0.25, 13};
  g.lat_deg = {40.0, 0.25, 9};
  g.alt_m = {0.0, 1000.0, 4};
  const std::vector<float> u(g.points(), 10.0f), v(g.points(), 10.0f);
  overlays::ArrowStyle style;
  style.spacing_cells = 3;
  const core::OverlayMesh m = overlays::build_arrows(g, u, v, 3000.0, style);
  const core::OverlayInstances& in = m.instances;
  ASSERT_EQ(in.count(), 5u * 3u);  // longitudes 0, 3, ..., 12; latitudes 1, 4, 7 (the lattice centred)
  const double length = style.scale * 3 * (g.earth_radius_m + 3000.0) * 0.25 * RotatingWind::kDeg * std::sqrt(200.0) / style.speed_max_m_s;
  for (std::size_t k = 0; k < in.count(); ++k) {
    const geo::Geodetic at = geo::ecef_to_sphere(in.origins[k], g.earth_radius_m);
    const geo::EnuFrame f = geo::sphere_enu(at.lat_deg, at.lon_deg);
    EXPECT_NEAR(at.alt_m, 3000.0, 1e-6) << k;
    const glm::dvec3 d = glm::normalize(glm::dvec3(in.axis_x[k]));
    EXPECT_NEAR(glm::dot(d, glm::normalize(f.east + f.north)), 1.0, 1e-12) << k;
    EXPECT_NEAR(glm::length(glm::dvec3(in.axis_x[k])) / length, 1.0, 1e-6) << k;
  }
  EXPECT_NEAR(geo::ecef_to_sphere(in.origins[0], g.earth_radius_m).lat_deg, 40.25, 1e-9);
}

// The overlay pass draws the arrows with one instanced draw; the CPU cast of the same mesh
// (its instances expanded) gives the same layer, and so does the GPU drawing the expanded mesh.
TEST(Arrows, TheInstancedDrawAgreesWithTheCpuCast) {
  auto ctx = render::make_headless_context();
  render::ShaderLoader loader({render::ShaderLoader::default_shader_dir()});
  render::OverlayPass pass(loader);
  const RotatingWind w(0.01);  // 21 x 21 points 1.1 km apart
  const double r0 = w.grid.earth_radius_m;
  overlays::ArrowStyle style;
  style.spacing_cells = 4, style.scale = 0.9, style.speed_max_m_s = 2.5;  // 1.1 to 3.5 km long
  const auto mesh = std::make_shared<const core::OverlayMesh>(overlays::build_arrows(w.grid, w.u, w.v, 1500.0, style));
  ASSERT_EQ(mesh->instances.count(), 36u);
  core::Camera cam;
  cam.alt_m = 30000.0, cam.pitch_deg = -90.0, cam.fov_deg = 40.0, cam.width = 128, cam.height = 96;
  pass.begin(cam, r0);
  pass.draw(mesh);
  const core::OpaqueLayer gpu = pass.read();
  EXPECT_EQ(pass.uploads(), 1u);
  const core::OpaqueLayer cpu = core::cast_overlay(*mesh, cam, r0);
  render::OverlayPass plain_pass(loader);
  plain_pass.begin(cam, r0);
  plain_pass.draw(core::expand_instances(*mesh));
  const core::OpaqueLayer plain = plain_pass.read();
  const int W = cam.width, H = cam.height;
  auto covered = [&](const core::OpaqueLayer& l, int x, int y) { return l.distance_m[static_cast<std::size_t>(y) * W + x] > 0.0f; };
  int both = 0, differ = 0, differ_inside = 0;
  double worst_distance = 0.0, worst_color = 0.0;
  for (int y = 0; y < H; ++y) {
    for (int x = 0; x < W; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * W + x;
      EXPECT_EQ(gpu.distance_m[i], plain.distance_m[i]) << "pixel " << x << ", " << y;
      const bool a = covered(gpu, x, y), b = covered(cpu, x, y);
      if (a != b) {
        ++differ;
        // Coverage may differ only where a pixel's centre lies on a glyph's edge: there the CPU's
        // cast has a neighbour that differs from the pixel.
        bool edge = false;
        for (const auto& [dx, dy] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}}) {
          if (x + dx >= 0 && x + dx < W && y + dy >= 0 && y + dy < H) edge = edge || covered(cpu, x + dx, y + dy) != b;
        }
        differ_inside += edge ? 0 : 1;
        continue;
      }
      if (!a) continue;
      ++both;
      worst_distance = std::max(worst_distance, std::abs(static_cast<double>(gpu.distance_m[i]) - cpu.distance_m[i]));
      for (int c = 0; c < 3; ++c) worst_color = std::max(worst_color, std::abs(static_cast<double>(gpu.radiance_rgba[4 * i + c]) - cpu.radiance_rgba[4 * i + c]));
    }
  }
  std::printf("arrows, GPU instanced against the CPU cast: %d pixels covered by both, %d differ; worst distance %.3g m, colour %.3g\n",
              both, differ, worst_distance, worst_color);
  EXPECT_GT(both, 200) << "the arrows cover too little of the image for a comparison";
  EXPECT_EQ(differ_inside, 0);
  EXPECT_LE(differ, both / 100) << differ << " pixels' coverage differs, of " << both;
  // Float: camera-relative vertices 28.5 km away (ulp 2 mm) and the interpolated position.
  EXPECT_LT(worst_distance, 0.02) << "m";
  EXPECT_LT(worst_color, 1e-6);
}

// Bad input: a volume without wind, a level outside the grid, a colour range the wrong way round;
// one line naming the scene key and what was expected.
TEST(Arrows, BadInputNamesTheKeyAndWhatWasExpected) {
  core::CloudVolume vol;
  vol.grid.lon_deg = {-2.0, 0.25, 17};
  vol.grid.lat_deg = {-2.0, 0.25, 17};
  vol.grid.alt_m = {0.0, 250.0, 17};
  vol.has_field[static_cast<std::size_t>(core::Field::ExtinctionLiquid)] = true;
  auto message = [&](const core::OverlaySpec& spec) {
    try {
      overlays::check_overlays({core::default_overlay("graticule"), spec}, vol);
    } catch (const overlays::OverlayError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  core::OverlaySpec arrows = core::default_overlay("arrows");
  EXPECT_EQ(message(arrows), "overlays[1]: found a volume without wind_u and wind_v, expected both for wind arrows (it holds extinction_liquid)");
  vol.has_field[static_cast<std::size_t>(core::Field::WindU)] = vol.has_field[static_cast<std::size_t>(core::Field::WindV)] = true;
  EXPECT_EQ(message(arrows), "(no error)");
  arrows.numbers["altitude_m"] = 4500.0;
  EXPECT_EQ(message(arrows), "overlays[1].altitude_m: found 4500, expected an altitude within the grid's levels, 0..4000 m");
  arrows.numbers["altitude_m"] = 2000.0;
  arrows.numbers["speed_min_m_s"] = 30.0;
  EXPECT_EQ(message(arrows), "overlays[1].speed_max_m_s: found 30, expected more than speed_min_m_s (30)");
}

// Isobaric sections. An isothermal atmosphere whose pressure at sea level rises with longitude,
// p = p_sea(lon) exp(-z / H) with H = R_d T / g0: the surface p = P stands at z = H ln(p_sea / P),
// higher to the east.
struct Isothermal {
  static constexpr double kT = 260.0, kRd = 287.05, kG0 = 9.80665, kH = kRd * kT / kG0;  // 7611 m
  static double p_sea_pa(double lon_deg) { return 101325.0 + 1500.0 * lon_deg; }
  static double altitude_m(double lon_deg, double p_pa) { return kH * std::log(p_sea_pa(lon_deg) / p_pa); }
};

// The builder on a grid given the pressure in closed form: every vertex at its column's altitude
// of the surface, coloured by the field there (here the altitude itself), and no vertex in the
// columns whose surface lies above the grid's top.
TEST(Section, AnIsobaricSurfaceStandsWhereThePressureIs) {
  core::VolumeGrid g;
  g.lon_deg = {-4.0, 0.5, 17};
  g.lat_deg = {50.0, 0.5, 5};
  g.alt_m = {0.0, 250.0, 13};  // to 3 km
  std::vector<float> p(g.points()), z(g.points());
  for (int k = 0; k < g.alt_m.count; ++k) {
    for (int j = 0; j < g.lat_deg.count; ++j) {
      for (int i = 0; i < g.lon_deg.count; ++i) {
        p[g.index(i, j, k)] = static_cast<float>(Isothermal::p_sea_pa(g.lon_deg.at(i)) * std::exp(-g.alt_m.at(k) / Isothermal::kH));
        z[g.index(i, j, k)] = static_cast<float>(g.alt_m.at(k));
      }
    }
  }
  const double level = 70000.0;  // 700 hPa: 2.35 km at 4 W to 2.98 km at 1.5 E, above the grid's top east of that
  const overlays::FieldColor by{nullptr, 0.0, 3000.0, 1.0};
  const core::OverlayMesh m = overlays::build_isobaric_section(g, p, z, level, by);
  int columns = 0;
  for (int i = 0; i < g.lon_deg.count; ++i) columns += Isothermal::altitude_m(g.lon_deg.at(i), level) <= g.alt_m.last() ? 1 : 0;
  ASSERT_EQ(m.positions.size(), static_cast<std::size_t>(columns * g.lat_deg.count));
  ASSERT_LT(columns, g.lon_deg.count);  // the surface leaves the grid: those columns have none
  EXPECT_EQ(m.triangles.size(), static_cast<std::size_t>(6 * (columns - 1) * (g.lat_deg.count - 1)));
  double worst = 0.0;
  for (std::size_t v = 0; v < m.positions.size(); ++v) {
    const geo::Geodetic at = geo::ecef_to_sphere(m.positions[v], g.earth_radius_m);
    const double expected = Isothermal::altitude_m(at.lon_deg, level);
    worst = std::max(worst, std::abs(at.alt_m - expected));
    const glm::vec4 c = overlays::colormap(expected / 3000.0);
    for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(m.colors[v][ch], c[ch], 1e-5f) << v;  // the field linear between nodes: exact
  }
  // Float pressures (6e-8 of the value) move ln p by as much: H x 6e-8, half a millimetre.
  std::printf("isobaric section against the closed form: worst %.3g m\n", worst);
  EXPECT_LT(worst, 0.01) << "m from the closed form";
  // Wind arrows on the same pressure surface: each at its column's altitude of it, none where the
  // surface is above the grid.
  const std::vector<float> u(g.points(), 5.0f), v(g.points(), 0.0f);
  overlays::ArrowStyle style;
  style.spacing_cells = 2, style.pressure_pa = level;
  const core::OverlayMesh arrows = overlays::build_arrows(g, u, v, 0.0, style, &p);
  std::size_t expected_arrows = 0;
  for (int i = 0; i < g.lon_deg.count; i += 2) expected_arrows += Isothermal::altitude_m(g.lon_deg.at(i), level) <= g.alt_m.last() ? 3 : 0;
  ASSERT_EQ(arrows.instances.count(), expected_arrows);
  double worst_arrow = 0.0;
  for (const glm::dvec3& o : arrows.instances.origins) {
    const geo::Geodetic at = geo::ecef_to_sphere(o, g.earth_radius_m);
    worst_arrow = std::max(worst_arrow, std::abs(at.alt_m - Isothermal::altitude_m(at.lon_deg, level)));
  }
  EXPECT_LT(worst_arrow, 0.01) << "m from the closed form";
}

// Through a file: the same atmosphere written as a CF file on pressure levels (geopotential and
// temperature), imported, and the isobaric section built by the overlay builder from a scene's
// entry; and the same entry refused, with the key named, for a volume without pressure.
TEST(Section, AnIsobaricSectionOfAFileOnPressureLevels) {
  const std::string path = cv::test_support::scratch_dir() + "isobaric_section.nc";
  constexpr double kR = 6371000.0;
  const std::vector<double> levels_pa = {100000.0, 92500.0, 85000.0, 77500.0, 70000.0, 62500.0, 55000.0};
  const int nx = 9, ny = 3;
  {
    test::PressureLevelFile f;
    for (int i = 0; i < nx; ++i) f.lon.push_back(-4.0 + i);
    for (int j = 0; j < ny; ++j) f.lat.push_back(50.0 + j);
    f.levels_pa = levels_pa;
    f.time_units = "hours since 2026-12-02 00:00:00";
    f.geopotential = [&](int i, int, int k) {
      const double alt = Isothermal::altitude_m(f.lon[static_cast<std::size_t>(i)], levels_pa[static_cast<std::size_t>(k)]);
      return Isothermal::kG0 * kR * alt / (kR + alt);  // the inverse of the importer's z = Phi R / (g0 R - Phi)
    };
    f.temperature = [](int, int, int) { return Isothermal::kT; };
    f.water = [](int, int, int k) { return k == 2 ? 1e-4 : 0.0; };
    test::write_pressure_level_file(path, f);
  }
  importers::ImportOptions o;
  o.dz_m = 100.0;
  o.keep_cloudless_levels = true;  // the whole column, not just the cloud's levels
  core::CloudVolume vol = importers::import_file(path, o);
  ASSERT_TRUE(vol.has_field[static_cast<std::size_t>(core::Field::Pressure)]);
  core::OverlaySpec spec = core::default_overlay("section");
  spec.texts["kind"] = "isobaric", spec.texts["field"] = "temperature";
  spec.numbers["pressure_hpa"] = 735.0, spec.numbers["legend_px"] = 0.0;
  overlays::check_overlays({spec}, vol);
  overlays::OverlayBuilder builder;
  core::Camera cam;
  cam.alt_m = 5.0e6;
  const auto built = builder.build({spec}, vol, 0, cam);
  ASSERT_EQ(built.size(), 1u);
  const core::OverlayMesh& m = *built[0].mesh;
  ASSERT_EQ(m.positions.size(), static_cast<std::size_t>(nx * ny));  // 735 hPa lies inside every column
  EXPECT_EQ(m.triangles.size(), static_cast<std::size_t>(6 * (nx - 1) * (ny - 1)));
  double worst = 0.0;
  for (const glm::dvec3& v : m.positions) {
    const geo::Geodetic at = geo::ecef_to_sphere(v, vol.grid.earth_radius_m);
    worst = std::max(worst, std::abs(at.alt_m - Isothermal::altitude_m(at.lon_deg, 73500.0)));
  }
  // ln p is linear in altitude here, as the importer interpolates it: only float rounding remains.
  std::printf("isobaric section of the imported file against the closed form: worst %.3g m\n", worst);
  EXPECT_LT(worst, 0.01) << "m from the closed form";
  // A level outside the volume's pressures, and a volume without pressure: the key named.
  spec.numbers["pressure_hpa"] = 400.0;
  try {
    overlays::OverlayBuilder().build({spec}, vol, 0, cam);
    ADD_FAILURE() << "no error for 400 hPa";
  } catch (const overlays::OverlayError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("overlays[0].pressure_hpa: found 400, expected a pressure within the volume's, ", 0), 0u) << e.what();
  }
  vol.has_field[static_cast<std::size_t>(core::Field::Pressure)] = false;
  try {
    overlays::check_overlays({spec}, vol);
    ADD_FAILURE() << "no error without pressure";
  } catch (const overlays::OverlayError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("overlays[0].kind: found \"isobaric\" for a volume without pressure", 0), 0u) << e.what();
  }
}

}  // namespace
