// The GPU march's acceleration against itself and the CPU reference: skipping empty bricks leaves
// the image unchanged, adapted steps match the reference, and the GPU's counters agree with it.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>

#include "reference/raymarcher.hpp"
#include "render/context.hpp"
#include "render/raymarcher.hpp"

namespace {
using namespace cv;

// Two separate cells (one liquid, one ice-topped) in a 4 x 4 degree box, nothing elsewhere: most
// bricks are empty, and view rays cross empty gaps between and around the cells.
struct Cells {
  core::VolumeGrid grid;
  core::TimeStepData data;
  Cells() {
    grid.lon_deg = {-2.0, 0.1, 41};
    grid.lat_deg = {-2.0, 0.1, 41};
    grid.alt_m = {0.0, 500.0, 25};
    data[core::Field::ExtinctionLiquid].assign(grid.points(), 0.0f);
    data[core::Field::ExtinctionIce].assign(grid.points(), 0.0f);
    for (int k = 0; k < grid.alt_m.count; ++k)
      for (int j = 0; j < grid.lat_deg.count; ++j)
        for (int i = 0; i < grid.lon_deg.count; ++i) {
          const double x = grid.lon_deg.at(i), y = grid.lat_deg.at(j), z = grid.alt_m.at(k);
          const double a = ((x + 0.8) * (x + 0.8) + y * y) / 0.09, b = ((x - 0.9) * (x - 0.9) + (y - 0.5) * (y - 0.5)) / 0.04;
          if (a < 1.0 && z > 1000.0 && z < 9000.0)  // a towering cell: ~0.05/m, optical depth ~ 1000 across
            data[core::Field::ExtinctionLiquid][grid.index(i, j, k)] = static_cast<float>(0.05 * (1.0 - a));
          if (b < 1.0 && z > 2000.0 && z < 4000.0)
            data[core::Field::ExtinctionLiquid][grid.index(i, j, k)] = static_cast<float>(0.005 * (1.0 - b));
          if (b < 1.0 && z > 7000.0 && z < 8000.0) data[core::Field::ExtinctionIce][grid.index(i, j, k)] = 3e-4f;
        }
  }
};

struct CellsOnGpu {
  std::unique_ptr<render::GlContext> ctx = render::make_headless_context();
  render::ShaderLoader loader{{render::ShaderLoader::default_shader_dir()}};
  render::GpuRaymarcher gpu{loader};
  Cells sc;
  core::GridMeanExtinction medium = core::grid_mean_extinction(sc.grid, sc.data);
  CellsOnGpu() { gpu.upload(sc.grid, medium); }
};

core::Camera cells_camera() {
  core::Camera c;  // south of the cells, a little above their bases, looking north
  c.lat_deg = -1.8;
  c.alt_m = 3000.0;
  c.pitch_deg = 3.0;
  c.fov_deg = 70.0;
  c.width = 48;
  c.height = 27;
  return c;
}

core::Sun cells_sun() {
  core::Sun s;
  s.subsolar_lat_deg = 15.0;
  s.subsolar_lon_deg = 50.0;
  s.irradiance = glm::dvec3(1.0, 0.8, 0.5);
  return s;
}

core::MarchSettings cells_settings() {
  core::MarchSettings s;
  s.quality.view_step_m = 200.0;
  s.quality.sun_steps = 16;
  s.quality.octaves = 4;
  return s;
}

struct Diff {
  double radiance = 0.0, transmittance = 0.0;  // worst; radiance relative to the brightest pixel
};
Diff compare(const std::vector<glm::vec4>& a, const std::vector<glm::dvec3>& rad, const std::vector<double>& t) {
  double max_l = 1e-30;
  for (const auto& l : rad) max_l = std::max(max_l, l.x);
  Diff d;
  for (std::size_t i = 0; i < a.size(); ++i) {
    for (int c = 0; c < 3; ++c) d.radiance = std::max(d.radiance, std::abs(a[i][c] - rad[i][c]) / max_l);
    d.transmittance = std::max(d.transmittance, std::abs(a[i].w - t[i]));
  }
  return d;
}
Diff compare(const std::vector<glm::vec4>& a, const std::vector<glm::vec4>& b) {
  std::vector<glm::dvec3> rad(b.size());
  std::vector<double> t(b.size());
  for (std::size_t i = 0; i < b.size(); ++i) rad[i] = glm::dvec3(b[i]), t[i] = b[i].w;
  return compare(a, rad, t);
}

void print_stats(const char* what, const core::MarchStats& s) {
  std::printf("%-26s view samples %8llu skipped %8llu, jumps %7llu, sun samples %9llu skipped %9llu, missed %llu\n", what,
              static_cast<unsigned long long>(s.view_samples), static_cast<unsigned long long>(s.view_skipped),
              static_cast<unsigned long long>(s.bricks_jumped), static_cast<unsigned long long>(s.sun_samples),
              static_cast<unsigned long long>(s.sun_skipped), static_cast<unsigned long long>(s.rays_missed));
}

TEST(Accel, SkippingEmptyBricksLeavesTheGpuImageUnchanged) {
  CellsOnGpu g;
  core::MarchSettings s = cells_settings();
  for (int frame : {-1, 3}) {
    s.per_frame.frame = frame;
    s.features.skip_empty = false;
    const auto plain = g.gpu.render(cells_camera(), cells_sun(), s);
    const core::MarchStats plain_stats = g.gpu.last_stats();
    s.features.skip_empty = true;
    const auto skip = g.gpu.render(cells_camera(), cells_sun(), s);
    const core::MarchStats skip_stats = g.gpu.last_stats();
    const auto cpu = core::render_reference(g.sc.grid, g.medium, cells_camera(), cells_sun(), s);
    const Diff gg = compare(skip, plain), gc = compare(skip, cpu.radiance, cpu.transmittance);
    std::printf("frame %d: GPU skipping vs not: radiance %.3g, transmittance %.3g; vs the CPU reference: %.3g, %.3g\n",
                frame, gg.radiance, gg.transmittance, gc.radiance, gc.transmittance);
    print_stats("GPU, no skipping", plain_stats);
    print_stats("GPU, skipping", skip_stats);
    print_stats("CPU reference, skipping", cpu.stats);
    // Skipped samples are exactly the zero ones: to float rounding (measured: 0).
    EXPECT_LE(gg.radiance, 1e-6);
    EXPECT_LE(gg.transmittance, 1e-6);
    EXPECT_LT(gc.radiance, 1e-3);
    EXPECT_LT(gc.transmittance, 1e-3);
    // Every step position was sampled or skipped, and skipping saved most of them.
    EXPECT_EQ(plain_stats.view_samples, skip_stats.view_samples + skip_stats.view_skipped);
    EXPECT_LT(skip_stats.view_samples * 2, plain_stats.view_samples);
    EXPECT_LE(skip_stats.sun_samples, plain_stats.sun_samples);  // the cloud layer may leave nothing to skip
    EXPECT_GT(skip_stats.bricks_jumped, 0u);
    // The GPU marches the reference's samples: its counts agree within the few decisions that
    // float rounding tips the other way.
    EXPECT_NEAR(double(skip_stats.view_samples), double(cpu.stats.view_samples), 1e-3 * double(cpu.stats.view_samples));
    EXPECT_NEAR(double(skip_stats.sun_samples), double(cpu.stats.sun_samples), 1e-3 * double(cpu.stats.sun_samples));
  }
}

TEST(Accel, AdaptedStepsOnTheGpuMatchTheReference) {
  CellsOnGpu g;
  core::MarchSettings s = cells_settings();
  s.features.adaptive_steps = true;
  s.quality.max_step_optical_depth = 0.5;
  const auto img = g.gpu.render(cells_camera(), cells_sun(), s);
  const core::MarchStats gs = g.gpu.last_stats();
  const auto cpu = core::render_reference(g.sc.grid, g.medium, cells_camera(), cells_sun(), s);
  s.features.adaptive_steps = false;
  const auto fixed = core::render_reference(g.sc.grid, g.medium, cells_camera(), cells_sun(), s);
  const Diff d = compare(img, cpu.radiance, cpu.transmittance);
  std::printf("adapted steps: GPU vs CPU radiance %.3g, transmittance %.3g\n", d.radiance, d.transmittance);
  print_stats("GPU, adapted", gs);
  print_stats("CPU, adapted", cpu.stats);
  print_stats("CPU, fixed", fixed.stats);
  EXPECT_LT(d.radiance, 1e-3);
  EXPECT_LT(d.transmittance, 1e-3);
  EXPECT_GT(cpu.stats.view_samples, fixed.stats.view_samples);  // the thick cell did get substeps
  EXPECT_NEAR(double(gs.view_samples), double(cpu.stats.view_samples), 1e-3 * double(cpu.stats.view_samples));
}

TEST(Accel, RaysThatMissTheShellAreCounted) {
  CellsOnGpu g;
  core::Camera c;  // from 2000 km up, looking at the horizon: the upper rows see space
  c.alt_m = 2.0e6;
  c.lat_deg = -20.0;
  c.pitch_deg = -40.0;
  c.fov_deg = 90.0;
  c.width = 32;
  c.height = 18;
  const core::MarchSettings s = cells_settings();
  g.gpu.render(c, cells_sun(), s);
  const auto cpu = core::render_reference(g.sc.grid, g.medium, c, cells_sun(), s);
  print_stats("GPU, far camera", g.gpu.last_stats());
  EXPECT_GT(cpu.stats.rays_missed, 0u);
  EXPECT_LT(cpu.stats.rays_missed, 32u * 18u);
  EXPECT_EQ(g.gpu.last_stats().rays_missed, cpu.stats.rays_missed);
}

}  // namespace
