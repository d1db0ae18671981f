// Sky, sun colour, ambient light, globe and cloud shadows: the CPU reference on a shadow scene, and
// the GPU raymarcher (llvmpipe) against the CPU reference with sky and globe on.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "reference/raymarcher.hpp"
#include "render/albedo_map.hpp"
#include "render/context.hpp"
#include "render/raymarcher.hpp"
#include "support/bubble_scene.hpp"

namespace {
using namespace cv;

// A narrow slab of cloud (4.4 km wide in longitude, 4-5 km up, optical depth ~20 across) on the
// equator, on a 0.01-degree grid.
struct ShadowScene {
  core::VolumeGrid grid;
  core::TimeStepData data;
  ShadowScene() {
    grid.lon_deg = {-0.3, 0.01, 61};
    grid.lat_deg = {-0.3, 0.01, 61};
    grid.alt_m = {3500.0, 250.0, 9};
    data[core::Field::ExtinctionLiquid].assign(grid.points(), 0.0f);
    for (int k = 0; k < grid.alt_m.count; ++k)
      for (int j = 0; j < grid.lat_deg.count; ++j)
        for (int i = 0; i < grid.lon_deg.count; ++i) {
          const double z = grid.alt_m.at(k);
          if (std::abs(grid.lon_deg.at(i)) <= 0.02 && z >= 4000.0 && z <= 5000.0)
            data[core::Field::ExtinctionLiquid][grid.index(i, j, k)] = 0.005f;
        }
  }
};

// Looking straight down from 100 km at (0, 0), 31 degrees wide: the image's columns run west to
// east over +-0.25 degree. The sun stands 20 degrees above the eastern horizon, so the slab's
// shadow falls 4.5 km / tan 20 = 12 km (0.11 degree) west of it.
core::Camera nadir_camera() {
  core::Camera cam;
  cam.alt_m = 1e5;
  cam.pitch_deg = -90.0;
  cam.fov_deg = 31.0;
  cam.width = 48;
  cam.height = 9;
  return cam;
}

// The column whose ray meets the ground nearest longitude lon_deg (row 4, the image's middle).
int column_at(const core::Camera& cam, double lon_deg) {
  const double x = std::tan(lon_deg * 3.14159265358979323846 / 180.0 * 6371000.0 / cam.alt_m);
  const double tan_half = std::tan(0.5 * cam.fov_deg * 3.14159265358979323846 / 180.0);
  return static_cast<int>(std::lround(((x / tan_half) + 1.0) * 0.5 * cam.width - 0.5));
}

TEST(SkyGlobe, ACloudShadowsTheGroundBesideIt) {
  ShadowScene sc;
  const core::Camera cam = nadir_camera();
  core::Sun sun;
  sun.subsolar_lon_deg = 70.0;  // 20 degrees above the eastern horizon of (0, 0)
  core::MarchSettings s;
  s.quality.view_step_m = 100.0;
  s.quality.sun_steps = 32;
  s.features.globe = true;
  const int west = column_at(cam, -0.11), east = column_at(cam, 0.11);
  ASSERT_GT(east, west);
  for (bool atmosphere : {false, true}) {
    s.features.atmosphere = atmosphere;
    s.medium.ambient = atmosphere ? 1.0 : 0.0;
    const auto img = core::render_reference(sc.grid, sc.data, cam, sun, s);
    auto at = [&](int x) { return img.radiance[static_cast<std::size_t>(4 * cam.width + x)]; };
    // The ground is opaque, and neither pixel looks through the cloud.
    EXPECT_EQ(img.transmittance[static_cast<std::size_t>(4 * cam.width + west)], 0.0);
    const double shade = at(west).y / at(east).y;
    std::printf("atmosphere %s: ground in the shadow %.4g, beside it %.4g (green), ratio %.3f\n", atmosphere ? "on" : "off",
                at(west).y, at(east).y, shade);
    // Without air the shadow is total (the slab's slant optical depth is ~60); with air, sky light
    // and the in-scatter between the camera and the ground fill about half of it in.
    EXPECT_LT(shade, atmosphere ? 0.6 : 0.01);
    // Without the slab, the same two pixels agree (the difference above is the shadow).
    core::TimeStepData empty = sc.data;
    empty[core::Field::ExtinctionLiquid].assign(sc.grid.points(), 0.0f);
    const auto clear = core::render_reference(sc.grid, empty, cam, sun, s);
    const double clear_ratio = clear.radiance[static_cast<std::size_t>(4 * cam.width + west)].y /
                               clear.radiance[static_cast<std::size_t>(4 * cam.width + east)].y;
    // (Within 5 %: the two pixels see the sun at 20.1 and 19.9 degrees, and the air's Mie lobe
    // differently.)
    EXPECT_NEAR(clear_ratio, 1.0, 0.05);
    EXPECT_LT(shade, 0.7 * clear_ratio);
  }
}


struct Case {
  const char* name;
  core::Camera cam;
  double sun_lat, sun_lon;
};

core::Camera camera(double lat, double lon, double alt, double heading, double pitch, double fov, int w, int h) {
  core::Camera c;
  c.lat_deg = lat, c.lon_deg = lon, c.alt_m = alt, c.heading_deg = heading, c.pitch_deg = pitch, c.fov_deg = fov;
  c.width = w, c.height = h;
  return c;
}

void expect_gpu_matches_cpu_with_sky(std::initializer_list<Case> cases) {
  auto ctx = render::make_headless_context();
  render::ShaderLoader loader({render::ShaderLoader::default_shader_dir()});
  render::GpuRaymarcher gpu(loader);
  const test::BubbleScene sc(false);  // the bubble without its ice layer
  const core::GridMeanExtinction medium = core::grid_mean_extinction(sc.grid, sc.data);
  gpu.upload(sc.grid, medium);
  core::MarchSettings s;
  s.quality.view_step_m = 200.0;
  s.quality.sun_steps = 16;
  s.quality.octaves = 4;
  s.features.atmosphere = true;
  s.features.globe = true;
  s.medium.ambient = 1.0;
  // The Natural Earth relief when python-cartopy-data is installed (scripts/setup installs it),
  // else a constant albedo: both paths use the same sampling on both sides.
  std::unique_ptr<core::AlbedoMap> map;
  if (std::filesystem::exists(render::kNaturalEarthRelief)) {
    s.medium.ground_texture = render::kNaturalEarthRelief;
    map = std::make_unique<core::AlbedoMap>(render::load_albedo_map(s.medium.ground_texture));
  }
  for (const Case& c : cases) {
    core::Sun sun;
    sun.subsolar_lat_deg = c.sun_lat;
    sun.subsolar_lon_deg = c.sun_lon;
    sun.irradiance = glm::dvec3(1.0, 0.9, 0.8);
    const auto cpu = core::render_reference(sc.grid, medium, c.cam, sun, s, nullptr, map.get());
    const auto img = gpu.render(c.cam, sun, s);
    double max_l = 1e-30, worst = 0.0, mean = 0.0, worst_t = 0.0;
    int ground = 0;
    for (const auto& l : cpu.radiance) max_l = std::max({max_l, l.x, l.y, l.z});
    for (std::size_t i = 0; i < img.size(); ++i) {
      ASSERT_TRUE(std::isfinite(img[i].x) && std::isfinite(img[i].y) && std::isfinite(img[i].z) && std::isfinite(img[i].w))
          << c.name;
      double e = 0.0;
      for (int k = 0; k < 3; ++k) e = std::max(e, std::abs(img[i][k] - cpu.radiance[i][k]) / max_l);
      worst = std::max(worst, e);
      mean += e;
      worst_t = std::max(worst_t, std::abs(img[i].w - cpu.transmittance[i]));
      ground += cpu.transmittance[i] == 0.0;
    }
    mean /= static_cast<double>(img.size());
    std::printf("%-26s radiance error (of the brightest pixel) mean %.2e worst %.2e; alpha worst %.2e; %d ground pixels\n",
                c.name, mean, worst, worst_t, ground);
    EXPECT_LT(worst, 2e-3) << c.name;
    EXPECT_LT(mean, 2e-4) << c.name;
    EXPECT_LT(worst_t, 1e-3) << c.name;
  }
}

TEST(SkyGlobe, GpuMatchesTheCpuReferenceWithSkyAndGlobe) {
  expect_gpu_matches_cpu_with_sky({
      Case{"geostationary, terminator", camera(0.0, 0.0, 3.6e7, 0.0, -90.0, 20.0, 32, 32), 0.0, 80.0},
      Case{"400 000 km", camera(0.0, 0.0, 4e8, 0.0, -90.0, 2.2, 32, 32), 20.0, -30.0},
  });
}

// The sea's sun glint (Cox-Munk, shaders/common/ground.glsl) with the relief texture's water: seen
// from geostationary distance with the sun high over the Gulf of Guinea beside the bubble, and as
// the glitter path toward a sun 10 degrees up, from 2 km over the sea (grazing sun and view).
TEST(SkyGlobe, GpuMatchesTheCpuReferenceOnTheSunGlint) {
  expect_gpu_matches_cpu_with_sky({
      Case{"geostationary, sun glint", camera(0.0, 0.0, 3.6e7, 0.0, -90.0, 20.0, 32, 32), 5.0, 8.0},
      Case{"glitter path, low sun", camera(-1.0, -2.0, 2000.0, 90.0, -4.0, 60.0, 48, 27), 0.0, 78.0},
  });
}

// Views along the horizon from inside the air, whose view rays run for hundreds of kilometres
// through the cloud shell and the air. They used to differ by up to 0.22 of the brightest pixel
// (alpha 1.1e-2; 1.1e-3 at the surface), for two reasons. (1) llvmpipe lets all loops of one
// invocation run 65 535 iterations in all and then ends every loop after one pass: a long march
// spent it, and every sky integral after it ran one step per side (tests/render/loop_budget_test.cpp;
// the march now goes in several dispatches). (2) A faint cloud's mean depth, where the sky is split
// around it, came from float differences T - T_next that are multiples of 6e-8; it is now
// T (1 - exp(-sigma dt)) through segment_integral on both sides.
TEST(SkyGlobe, GpuMatchesTheCpuReferenceAlongTheHorizon) {
  expect_gpu_matches_cpu_with_sky({
      Case{"horizon, sky and ground", camera(-1.5, 0.0, 2000.0, 0.0, -2.0, 60.0, 48, 27), 10.0, 60.0},
      Case{"low sun from 1 km", camera(-1.0, 0.0, 1000.0, 20.0, 3.0, 60.0, 48, 27), 0.0, 85.0},
      Case{"at the surface", camera(-1.5, 0.5, 0.0, 0.0, 10.0, 60.0, 32, 18), 5.0, 30.0},
  });
}

}  // namespace
