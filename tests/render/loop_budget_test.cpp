// Mesa's llvmpipe lets all loops of one shader invocation run 65 535 iterations in all, then ends
// each loop after one pass, silently. The raymarcher's views along the horizon ran out of it (the
// march and then every sky integral stopped early: 0.22 of the brightest pixel off the CPU), so it
// now marches in ranges of steps, one dispatch each (app/render/raymarcher.hpp). These tests pin
// the driver's behaviour and the bound on the steps that the dispatches have to cover.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "physics/physics.hpp"
#include "render/context.hpp"
#include "render/raymarcher.hpp"
#include "render/shader_loader.hpp"

namespace {
using namespace cv::render;
namespace p32 = cv::physics::f32;

// Iterations of the second loop of shaders/tests/loop_budget.comp, and the first loop's count.
std::pair<int, int> run_loops(GLuint prog, int first, int second) {
  GLuint buf = 0;
  glCreateBuffers(1, &buf);
  glNamedBufferStorage(buf, 2 * sizeof(int), nullptr, GL_MAP_READ_BIT);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, buf);
  glUseProgram(prog);
  glUniform1i(glGetUniformLocation(prog, "u_first"), first);
  glUniform1i(glGetUniformLocation(prog, "u_second"), second);
  glDispatchCompute(1, 1, 1);
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  int counts[2] = {-1, -1};
  glGetNamedBufferSubData(buf, 0, sizeof(counts), counts);
  check_gl("running the loop budget shader");
  glDeleteBuffers(1, &buf);
  return {counts[1], counts[0]};
}

TEST(LoopBudget, LlvmpipeSharesOneBudgetAmongAllLoopsOfAnInvocation) {
  auto ctx = make_headless_context();
  ShaderLoader loader({CV_SHADER_DIR});
  GlProgram prog = load_compute(loader, std::string(CV_SHADER_DIR) + "/tests/loop_budget.comp");
  // Within the budget, both loops run in full on every driver.
  EXPECT_EQ(run_loops(prog.id(), 1000, 10).first, 10);
  if (ctx->info().renderer.find("llvmpipe") == std::string::npos) GTEST_SKIP() << "not llvmpipe: " << ctx->info().renderer;
  // 100 iterations short of the budget, the second loop gets about the 100 that are left...
  const int left = run_loops(prog.id(), kLlvmpipeLoopBudget - 100, 1000).first;
  // ...and after a loop that spends it all, the second loop runs once, as does the first beyond it.
  const auto [after, first_quarter] = run_loops(prog.id(), 70000, 10);
  std::printf("%s: after %d iterations a loop of 1000 ran %d; after a loop of 70000 (which counted %d of its 17500 "
              "quarters) a loop of 10 ran %d\n",
              ctx->info().renderer.c_str(), kLlvmpipeLoopBudget - 100, left, first_quarter, after);
  EXPECT_GE(left, 95);
  EXPECT_LE(left, 100);
  EXPECT_EQ(after, 1);
  EXPECT_LT(first_quarter, 17500);
}

// The steps of one ray exactly as raymarch.comp counts them (float, the same physics functions).
int view_steps(float r0, float h, float mu, float nu, float hb, float ht, float step) {
  if (h > ht) {
    float e0, e1;
    if (!p32::ray_sphere_rel_nu(r0, h, mu, nu, ht, e0, e1) || e1 < 0.0f) return 0;
    if (e0 > 0.0f) {
      // Re-anchored where the ray enters the shell: the new cosine with the local up there.
      const float r = r0 + h, rt = r0 + ht;
      mu = (r * mu + e0) / rt;
      mu = std::clamp(mu, -1.0f, 1.0f);
      nu = std::sqrt(std::max(0.0f, 1.0f - mu * mu));
      h = ht;
    }
  }
  glm::vec4 seg;
  const int n = p32::ray_shell_rel_nu(r0, h, mu, nu, hb, ht, seg);
  float g0, g1;
  const float t_ground = p32::ray_sphere_rel_nu(r0, h, mu, nu, 0.0f, g0, g1) && g1 > 0.0f ? std::max(g0, 0.0f) : 3.0e38f;
  int steps = 0;
  for (int k = 0; k < n; ++k) {
    const float t_start = k == 0 ? seg.x : seg.z;
    const float t_end = std::min(k == 0 ? seg.y : seg.w, t_ground);
    if (!(t_end > t_start)) continue;
    steps += std::max(1, static_cast<int>(std::ceil((t_end - t_start) / step)));
  }
  return steps;
}

TEST(LoopBudget, TheDispatchesCoverEveryRaysSteps) {
  const float r0 = 6371000.0f;
  struct Shell {
    float hb, ht, step;
  };
  double worst = 0.0;
  int worst_steps = 0, worst_bound = 0;
  for (const Shell sh : {Shell{500.0f, 10500.0f, 200.0f}, Shell{0.0f, 20000.0f, 50.0f}, Shell{1000.0f, 1200.0f, 10.0f}}) {
    const int bound = max_view_steps(r0, sh.ht, sh.step);
    for (float h : {0.0f, 1.0f, 600.0f, 2000.0f, sh.ht - 1.0f, sh.ht, sh.ht + 1.0f, 1e5f, 3.6e7f}) {
      // Directions from nadir to zenith, densest around the horizon and the shell's tangents.
      for (int i = 0; i <= 200000; ++i) {
        const double u = -1.0 + 2.0 * i / 200000.0;
        const float mu = static_cast<float>(u * u * u);
        const float nu = std::sqrt(std::max(0.0f, 1.0f - mu * mu));
        const int steps = view_steps(r0, h, mu, nu, sh.hb, sh.ht, sh.step);
        if (static_cast<double>(steps) / bound > worst) {
          worst = static_cast<double>(steps) / bound;
          worst_steps = steps;
          worst_bound = bound;
        }
        ASSERT_LE(steps, bound) << "shell " << sh.hb << "-" << sh.ht << " m, camera at " << h << " m, mu " << mu;
      }
    }
  }
  // The bound is tight: a ray from the top of a shell that reaches the ground, tangent to it.
  std::printf("the most steps of any ray against max_view_steps: %d of %d\n", worst_steps, worst_bound);
}

}  // namespace

namespace {
TEST(LoopBudget, OnlyLlvmpipeSplitsTheMarch) {
  EXPECT_TRUE(cv::render::driver_has_loop_budget("llvmpipe (LLVM 15.0.6, 256 bits)"));
  EXPECT_FALSE(cv::render::driver_has_loop_budget("NVIDIA H100 80GB HBM3/PCIe/SSE2"));
  EXPECT_FALSE(cv::render::driver_has_loop_budget("AMD Radeon RX 7900 XTX (radeonsi, navi31, LLVM 15.0.7, DRM 3.54)"));
  // This machine's driver decides what the raymarcher does: on llvmpipe the tests above hold it to
  // the budget; elsewhere a frame is one dispatch per tile.
  auto ctx = cv::render::make_headless_context();
  std::printf("driver %s: march %s\n", ctx->info().renderer.c_str(),
              cv::render::driver_has_loop_budget(ctx->info().renderer) ? "split by the loop budget" : "in one dispatch");
}
}  // namespace
