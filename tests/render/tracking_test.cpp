// The kernel's tracking (shaders/kernel/tracking.glsl), compiled by the GPU and by C++: ratio and
// delta tracking along a ray through the bubble's flank estimate its transmittance without bias, held
// against a fine quadrature of the optical depth through the same medium fetch, with the volume's
// majorant and with the pyramid's brick majorants.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

#include "geo/geodesy.hpp"
#include "kernel/bindings.glsl"
#include "kernel/prepared_volume.hpp"
#include "reference/track_kernel.hpp"
#include "render/context.hpp"
#include "render/gl.hpp"
#include "render/shader_loader.hpp"
#include "support/bubble_scene.hpp"

namespace {
using namespace cv;

struct Ray {
  glm::dvec3 origin, dir;
  double length_m = 0.0;
};

// Eastward and level from 1.5 degrees west of the bubble, 0.85 degrees north of its axis at 3 km:
// through the flank, where the optical depth is a few.
Ray flank_ray(const core::VolumeGrid& g) {
  Ray r;
  r.origin = geo::sphere_to_ecef({0.85, -1.5, 3000.0}, g.earth_radius_m);
  r.dir = geo::sphere_enu(0.85, -1.5).east;
  r.length_m = 330e3;
  return r;
}

// The CPU kernel for the volume, its medium and tracking ready.
std::unique_ptr<kernel::f64::TrackKernel> cpu_kernel(const core::PreparedVolume& v, bool bricks) {
  auto k = std::make_unique<kernel::f64::TrackKernel>();
  static_cast<kernel::MarchParams&>(*k) = core::march_params(v, core::Camera{}, core::Sun{}, core::MarchSettings{});
  const glm::ivec3 n(v.grid.lon_deg.count, v.grid.lat_deg.count, v.grid.alt_m.count);
  k->u_liquid = {v.extinction.liquid_per_m.data(), n};
  k->u_ice = {v.extinction.ice_per_m.data(), n};
  k->u_min_max = v.pyramid_packed.data();
  k->u_track_majorant = v.sigma_max_per_m;
  k->u_track_bricks = bricks;
  return k;
}

// exp(-optical depth) by the midpoint rule at 5 m through the kernel's own medium fetch.
double quadrature_transmittance(kernel::f64::TrackKernel& k, const Ray& r) {
  const double dt = 5.0;
  double tau = 0.0;
  for (double t = 0.5 * dt; t < r.length_m; t += dt) {
    double sl, si;
    k.medium_at_point(r.origin + t * r.dir, sl, si);
    tau += (sl + si) * dt;
  }
  return std::exp(-tau);
}

struct Estimate {
  double mean = 0.0, standard_error = 0.0;
};
Estimate summarise(const std::vector<double>& e) {
  Estimate s;
  double sum = 0.0, sum2 = 0.0;
  for (double x : e) sum += x, sum2 += x * x;
  const double n = static_cast<double>(e.size());
  s.mean = sum / n;
  s.standard_error = std::sqrt(std::max(0.0, sum2 / n - s.mean * s.mean) / (n - 1.0));
  return s;
}

class Tracking : public ::testing::Test {
 protected:
  void SetUp() override {
    const test::BubbleScene bubble(false);
    volume_ = std::make_shared<const core::PreparedVolume>(core::prepare_volume(bubble.grid, bubble.data));
    ray_ = flank_ray(volume_->grid);
    auto k = cpu_kernel(*volume_, false);
    expected_ = quadrature_transmittance(*k, ray_);
  }
  std::shared_ptr<const core::PreparedVolume> volume_;
  Ray ray_;
  double expected_ = 0.0;
};

TEST_F(Tracking, TheRayCrossesAFewOpticalDepths) {
  // The test means something only where the transmittance is neither ~0 nor ~1.
  EXPECT_GT(expected_, 0.02);
  EXPECT_LT(expected_, 0.8);
  std::printf("flank ray: transmittance %.5f (optical depth %.3f)\n", expected_, -std::log(expected_));
}

TEST_F(Tracking, CpuRatioAndDeltaTrackingAreUnbiased) {
  for (bool bricks : {false, true}) {
    auto k = cpu_kernel(*volume_, bricks);
    std::vector<double> ratio, delta;
    const glm::dvec4 seg(0.0, ray_.length_m, 0.0, 0.0);
    for (std::uint64_t s = 0; s < 4000; ++s) {
      core::PathRng rng(7, 0, s);
      auto c = k->track_counts();
      ratio.push_back(k->ratio_track(ray_.origin, ray_.dir, seg, 1, rng, c));
      delta.push_back(k->delta_track(ray_.origin, ray_.dir, seg, 1, rng, c) >= 3.0e38 ? 1.0 : 0.0);
      EXPECT_EQ(c.exceeded, 0u);
    }
    for (const auto* e : {&ratio, &delta}) {
      const Estimate s = summarise(*e);
      EXPECT_NEAR(s.mean, expected_, 4.0 * s.standard_error + 1e-4) << (bricks ? "brick majorants" : "volume majorant");
    }
  }
}

TEST_F(Tracking, GpuRatioAndDeltaTrackingAreUnbiased) {
  auto ctx = render::make_headless_context();
  render::ShaderLoader loader({render::ShaderLoader::default_shader_dir()});
  const render::GlProgram prog = render::load_compute(loader, render::ShaderLoader::default_shader_dir() / "tests" / "tracking.comp");
  const GLuint p = prog.id();
  const core::VolumeGrid& g = volume_->grid;
  GLuint tex[2];
  glCreateTextures(GL_TEXTURE_3D, 2, tex);
  const std::vector<float>* fields[2] = {&volume_->extinction.liquid_per_m, &volume_->extinction.ice_per_m};
  for (int i = 0; i < 2; ++i) {
    glTextureStorage3D(tex[i], 1, GL_R32F, g.lon_deg.count, g.lat_deg.count, g.alt_m.count);
    glTextureSubImage3D(tex[i], 0, 0, 0, 0, g.lon_deg.count, g.lat_deg.count, g.alt_m.count, GL_RED, GL_FLOAT, fields[i]->data());
  }
  const kernel::MarchParamsStd140 block = kernel::pack_std140(core::march_params(*volume_, core::Camera{}, core::Sun{}, core::MarchSettings{}));
  GLuint buf[3];
  glCreateBuffers(3, buf);
  glNamedBufferStorage(buf[0], sizeof(block), &block, 0);
  glNamedBufferStorage(buf[1], static_cast<GLsizeiptr>(volume_->pyramid_packed.size() * sizeof(glm::vec2)), volume_->pyramid_packed.data(), 0);
  const GLuint count = 16384;
  glNamedBufferStorage(buf[2], count * sizeof(float), nullptr, GL_DYNAMIC_STORAGE_BIT);
  glBindBufferBase(GL_UNIFORM_BUFFER, CV_UBO_MARCH, buf[0]);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CV_SSBO_PYRAMID, buf[1]);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 5, buf[2]);
  glBindTextureUnit(CV_TEX_LIQUID, tex[0]);
  glBindTextureUnit(CV_TEX_ICE, tex[1]);
  // Positions as float on the GPU: the origin's own rounding (0.5 m at the Earth's radius) moves the
  // ray by less than the 5 m quadrature step.
  glProgramUniform3f(p, glGetUniformLocation(p, "u_origin"), float(ray_.origin.x), float(ray_.origin.y), float(ray_.origin.z));
  glProgramUniform3f(p, glGetUniformLocation(p, "u_dir"), float(ray_.dir.x), float(ray_.dir.y), float(ray_.dir.z));
  glProgramUniform4f(p, glGetUniformLocation(p, "u_seg"), 0.0f, float(ray_.length_m), 0.0f, 0.0f);
  glProgramUniform1i(p, glGetUniformLocation(p, "u_parts"), 1);
  glProgramUniform1ui(p, glGetUniformLocation(p, "u_count"), count);
  glProgramUniform1f(p, glGetUniformLocation(p, "u_track_majorant"), float(volume_->sigma_max_per_m));
  glUseProgram(p);
  for (int bricks = 0; bricks < 2; ++bricks) {
    for (int mode = 0; mode < 2; ++mode) {
      glProgramUniform1i(p, glGetUniformLocation(p, "u_track_bricks"), bricks);
      glProgramUniform1i(p, glGetUniformLocation(p, "u_mode"), mode);
      glDispatchCompute(count / 64, 1, 1);
      glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
      std::vector<float> out(count);
      glGetNamedBufferSubData(buf[2], 0, count * sizeof(float), out.data());
      render::check_gl("running the tracking test");
      const Estimate s = summarise(std::vector<double>(out.begin(), out.end()));
      std::printf("GPU %s tracking, %s: mean %.5f +- %.5f against %.5f\n", mode == 0 ? "ratio" : "delta",
                  bricks ? "brick majorants" : "volume majorant", s.mean, s.standard_error, expected_);
      EXPECT_NEAR(s.mean, expected_, 4.0 * s.standard_error + 2e-3) << "mode " << mode << ", bricks " << bricks;
      EXPECT_GT(s.standard_error, 0.0);  // the estimates differ: each invocation drew its own stream
    }
  }
  glDeleteBuffers(3, buf);
  glDeleteTextures(2, tex);
}

}  // namespace
