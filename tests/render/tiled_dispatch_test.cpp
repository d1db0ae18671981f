// Long renders dispatched in tiles of rows: the same pixels as one dispatch, bit for bit, with the
// progress callback after every tile and the GPU time added up.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "reference/raymarcher.hpp"
#include "render/context.hpp"
#include "render/raymarcher.hpp"

namespace {
using namespace cv;

TEST(TiledDispatch, TilesGiveTheSamePixelsAsOneDispatch) {
  auto ctx = render::make_headless_context();
  const render::ShaderLoader loader({render::ShaderLoader::default_shader_dir()});
  render::GpuRaymarcher gpu(loader);
  // A Gaussian blob of liquid 2 x 2 degrees wide around (0, 0), 1..5 km up.
  core::VolumeGrid grid;
  grid.lon_deg = {-1.0, 0.1, 21};
  grid.lat_deg = {-1.0, 0.1, 21};
  grid.alt_m = {1000.0, 250.0, 17};
  core::GridMeanExtinction medium;
  medium.liquid_per_m.assign(grid.points(), 0.0f);
  medium.ice_per_m.assign(grid.points(), 0.0f);
  for (int k = 0; k < grid.alt_m.count; ++k)
    for (int j = 0; j < grid.lat_deg.count; ++j)
      for (int i = 0; i < grid.lon_deg.count; ++i) {
        const double x = grid.lon_deg.at(i), y = grid.lat_deg.at(j), z = (grid.alt_m.at(k) - 3000.0) / 1000.0;
        medium.liquid_per_m[grid.index(i, j, k)] = static_cast<float>(0.01 * std::exp(-4.0 * (x * x + y * y) - z * z));
      }
  gpu.upload(grid, medium);
  core::Camera cam;
  cam.lat_deg = -1.6, cam.alt_m = 4000.0, cam.pitch_deg = -1.0, cam.fov_deg = 30.0;
  cam.width = 48, cam.height = 27;  // 27 rows: the last tile is a partial one
  core::Sun sun;
  sun.subsolar_lat_deg = 20.0, sun.subsolar_lon_deg = 40.0;
  core::MarchSettings s;
  s.quality.view_step_m = 200.0, s.quality.sun_steps = 8, s.quality.octaves = 2;

  const std::vector<glm::vec4> whole = gpu.render(cam, sun, s);
  std::vector<int> reported;
  double gpu_s = 0.0;
  render::DispatchOptions tiles;
  tiles.rows_per_tile = 5;  // rounded up to 8, the workgroup height
  tiles.on_tile = [&](int done, int total) {
    EXPECT_EQ(total, 27);
    reported.push_back(done);
  };
  tiles.gpu_seconds = &gpu_s;
  const std::vector<glm::vec4> tiled = gpu.render(cam, sun, s, tiles);
  EXPECT_EQ(reported, (std::vector<int>{8, 16, 24, 27}));
  EXPECT_GE(gpu_s, 0.0);
  ASSERT_EQ(whole.size(), tiled.size());
  std::size_t lit = 0;
  for (const auto& p : whole) lit += p.x > 0.0f;
  EXPECT_GT(lit, whole.size() / 10);  // the blob is in view: a blank image would match trivially
  EXPECT_EQ(std::memcmp(whole.data(), tiled.data(), whole.size() * sizeof(glm::vec4)), 0);
}

}  // namespace
