// A medium between two forecast steps (advected) is one field on the GPU and in the CPU reference:
// the interpolation happens before either marches, on the prepared volume.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>

#include "reference/raymarcher.hpp"
#include "render/context.hpp"
#include "render/raymarcher.hpp"
#include "support/bubble_scene.hpp"
#include "volume/grid_mean.hpp"
#include "volume/time_interpolation.hpp"

namespace {
using namespace cv;

TEST(TimeInterpolationRender, GpuMatchesTheCpuReferenceBetweenSteps) {
  const cv::test::BubbleScene sc;
  const core::VolumeGrid& g = sc.grid;
  const core::GridMeanExtinction e0 = core::grid_mean_extinction(g, sc.data);
  // The later step: the bubble carried 1 degree east and a little north by a uniform wind over 3 h.
  const double gap_s = 3 * 3600.0;
  core::StepWinds w;
  w.u.assign(g.points(), static_cast<float>(111195.0 / gap_s));
  w.v.assign(g.points(), static_cast<float>(30000.0 / gap_s));
  const core::GridMeanExtinction e1{core::advect_field(g, e0.liquid_per_m, w, w, gap_s, 1.0, 0),
                                    core::advect_field(g, e0.ice_per_m, w, w, gap_s, 1.0, 0)};
  core::TimeInterpolationReport r;
  const core::GridMeanExtinction mid = core::interpolate_extinction(g, e0, e1, w, w, gap_s, 0.5, core::TimeInterpolation::Advected, &r);
  ASSERT_EQ(r.used, core::TimeInterpolation::Advected);
  ASSERT_NE(mid.liquid_per_m, e0.liquid_per_m);
  ASSERT_NE(mid.liquid_per_m, e1.liquid_per_m);

  auto ctx = render::make_headless_context();
  const render::ShaderLoader loader{{render::ShaderLoader::default_shader_dir()}};
  render::GpuRaymarcher gpu{loader};
  gpu.upload(g, mid);
  core::Camera cam;
  cam.lat_deg = -1.5, cam.alt_m = 2000.0, cam.pitch_deg = 5.0, cam.fov_deg = 60.0, cam.width = 32, cam.height = 18;
  core::Sun sun;
  sun.subsolar_lat_deg = 10.0, sun.subsolar_lon_deg = 60.0;
  core::MarchSettings s;
  s.quality.view_step_m = 200.0;
  s.quality.sun_steps = 16;
  const auto cpu = core::render_reference(g, mid, cam, sun, s);
  const auto img = gpu.render(cam, sun, s);
  double max_l = 0.0;
  for (const auto& l : cpu.radiance) max_l = std::max(max_l, l.x);
  ASSERT_GT(max_l, 0.0);
  double worst = 0.0, worst_t = 0.0;
  for (std::size_t i = 0; i < img.size(); ++i) {
    for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(img[i][c] - cpu.radiance[i][c]) / max_l);
    worst_t = std::max(worst_t, std::abs(img[i].w - cpu.transmittance[i]));
  }
  std::printf("between steps (advected, %d sub-steps): GPU vs CPU reference worst radiance error %.3g of the brightest, "
              "transmittance %.3g\n", r.substeps, worst, worst_t);
  // The tolerance of Raymarch.GpuMatchesTheCpuReference: the same march on one field.
  EXPECT_LT(worst, 1e-3);
  EXPECT_LT(worst_t, 1e-3);
}

}  // namespace
