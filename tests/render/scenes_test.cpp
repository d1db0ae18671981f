// The GPU raymarcher against the CPU reference on every standard scene (core/scenes): clear sky,
// thin cirrus, a stratocumulus deck, a cumulus field, a towering cell with optical depth ~600, a sun
// on the horizon, a camera inside a cloud, the globe from 400 000 km, the date line and a pole.
// Every pixel must be finite, and the two images agree within 1e-3 of the brightest pixel.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>

#include "reference/raymarcher.hpp"
#include "render/context.hpp"
#include "render/raymarcher.hpp"
#include "bench/standard_scenes.hpp"

namespace {
using namespace cv;

class StandardScenes : public ::testing::TestWithParam<std::string> {};

// A scene rendered on the GPU (llvmpipe) and by the CPU reference, every GPU pixel checked to be
// finite and in range, and the difference summed up (radiance relative to the brightest pixel).
struct Comparison {
  core::ReferenceImage cpu;
  double max_l = 0.0, worst = 0.0, mean = 0.0, worst_t = 0.0;
  int cloudy = 0;  // reference pixels whose transmittance is below 0.99
  std::size_t pixels = 0;
};

Comparison compare_on_gpu(const bench::StandardScene& sc) {
  Comparison c;
  auto ctx = render::make_headless_context();
  render::ShaderLoader loader({render::ShaderLoader::default_shader_dir()});
  render::GpuRaymarcher gpu(loader);
  const core::GridMeanExtinction medium = core::grid_mean_extinction(sc.grid, sc.data);
  gpu.upload(sc.grid, medium);
  c.cpu = core::render_reference(sc.grid, medium, sc.camera, sc.sun, sc.march);
  const auto img = gpu.render(sc.camera, sc.sun, sc.march);
  EXPECT_EQ(img.size(), c.cpu.radiance.size());
  c.pixels = img.size();
  for (const auto& l : c.cpu.radiance) c.max_l = std::max({c.max_l, l.x, l.y, l.z});
  for (std::size_t i = 0; i < img.size(); ++i) {
    const glm::vec4& p = img[i];
    EXPECT_TRUE(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z) && std::isfinite(p.w)) << "pixel " << i;
    EXPECT_TRUE(p.x >= 0.0f && p.y >= 0.0f && p.z >= 0.0f && p.w >= 0.0f && p.w <= 1.0f) << "pixel " << i;
    for (int k = 0; k < 3; ++k) {
      const double e = std::abs(p[k] - c.cpu.radiance[i][k]) / std::max(c.max_l, 1e-30);
      c.worst = std::max(c.worst, e);
      c.mean += e / (3.0 * img.size());
    }
    c.worst_t = std::max(c.worst_t, std::abs(double(p.w) - c.cpu.transmittance[i]));
    c.cloudy += c.cpu.transmittance[i] < 0.99;
  }
  return c;
}

TEST_P(StandardScenes, GpuMatchesTheCpuReferenceWithEveryPixelFinite) {
  const bench::StandardScene sc = bench::standard_scene(GetParam(), 48, 27);
  const Comparison c = compare_on_gpu(sc);
  std::printf("%-14s %4d cloudy pixels of %zu; radiance error (of the brightest pixel) mean %.3g, worst %.3g; "
              "transmittance worst %.3g\n",
              sc.name.c_str(), c.cloudy, c.pixels, c.mean, c.worst, c.worst_t);
  if (sc.name == "clear_sky") {
    EXPECT_EQ(c.cloudy, 0);
    EXPECT_EQ(c.max_l, 0.0);
  } else {
    EXPECT_GT(c.cloudy, 10) << "the camera should see the scene's cloud";
  }
  EXPECT_LT(c.worst, 1e-3);
  EXPECT_LT(c.worst_t, 1e-3);
}

// The same scenes as the product shows them: sunlight through the air, the sky, ambient light and
// the globe (constant albedo) with the clouds' shadows, GPU against CPU within the sky tests' bounds.
TEST_P(StandardScenes, WithSkyAndGlobeTheGpuMatchesTheCpuReference) {
  bench::StandardScene sc = bench::standard_scene(GetParam(), 32, 18);
  sc.march.features.atmosphere = sc.march.features.globe = true;
  sc.march.medium.ambient = 1.0;
  const Comparison c = compare_on_gpu(sc);
  ASSERT_GT(c.max_l, 0.0) << "the sky or the ground should be lit";
  std::printf("%-14s with sky and globe: radiance error (of the brightest pixel) mean %.3g, worst %.3g; alpha worst %.3g\n",
              sc.name.c_str(), c.mean, c.worst, c.worst_t);
  EXPECT_LT(c.worst, 2e-3);
  EXPECT_LT(c.mean, 2e-4);
  EXPECT_LT(c.worst_t, 1e-3);
}

// The two-stream model: the same kernel with its source textures, GPU against CPU within the
// clouds-only bound, every pixel finite.
TEST_P(StandardScenes, TwoStreamGpuMatchesTheCpuReference) {
  bench::StandardScene sc = bench::standard_scene(GetParam(), 32, 18);
  sc.march.medium.ms_two_stream = true;
  const Comparison c = compare_on_gpu(sc);
  std::printf("%-14s two-stream: radiance error (of the brightest pixel) mean %.3g, worst %.3g\n", sc.name.c_str(), c.mean,
              c.worst);
  if (sc.name != "clear_sky") {
    EXPECT_GT(c.max_l, 0.0);
  }
  EXPECT_LT(c.worst, 1e-3);
  EXPECT_LT(c.worst_t, 1e-3);
}

// Skipping empty bricks must not change the image: every skipped sample would have read exactly
// 0, including beside a regional grid's edge, where the data fades out over a border cell.
TEST_P(StandardScenes, SkippingEmptySpaceLeavesTheImageExactlyAsItWas) {
  bench::StandardScene sc = bench::standard_scene(GetParam(), 32, 18);
  const core::GridMeanExtinction medium = core::grid_mean_extinction(sc.grid, sc.data);
  sc.march.features.skip_empty = false;
  const auto plain = core::render_reference(sc.grid, medium, sc.camera, sc.sun, sc.march);
  sc.march.features.skip_empty = true;
  const auto skipped = core::render_reference(sc.grid, medium, sc.camera, sc.sun, sc.march);
  for (std::size_t i = 0; i < plain.radiance.size(); ++i) {
    ASSERT_EQ(plain.radiance[i], skipped.radiance[i]) << sc.name << " pixel " << i;
    ASSERT_EQ(plain.transmittance[i], skipped.transmittance[i]) << sc.name << " pixel " << i;
  }
  std::printf("%-14s skipping: %llu of %llu view positions and %llu sun positions left out, same image\n", sc.name.c_str(),
              static_cast<unsigned long long>(skipped.stats.view_skipped),
              static_cast<unsigned long long>(plain.stats.view_samples),
              static_cast<unsigned long long>(skipped.stats.sun_skipped));
  // Broken cloud leaves empty bricks inside the cloud layer (the decks and bands fill theirs).
  if (sc.name == "cumulus_field" || sc.name == "towering_cell" || sc.name == "sunset" || sc.name == "pole") {
    EXPECT_GT(skipped.stats.view_skipped, 0u) << sc.name;
  }
}

INSTANTIATE_TEST_SUITE_P(All, StandardScenes, ::testing::ValuesIn(bench::standard_scene_names()),
                         [](const auto& info) { return info.param; });

}  // namespace
