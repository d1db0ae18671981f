// The approximate Mie phase (Jendersie & d'Eon 2023): the anchor values at 20 um, the range of its
// parameters over 0.01..50 um, and the jumps of the published piecewise fit at its branch ends.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>

#include "physics/physics.hpp"
#include "support/numeric.hpp"

namespace {
using namespace cv::physics;

TEST(Mie, AnchorValuesAtTwentyMicrometres) {
  const auto p = f64::mie_params(20.0);
  EXPECT_NEAR(p.g_hg, 0.9946, 5e-5);
  EXPECT_NEAR(p.g_d, 0.594, 5e-4);
  EXPECT_NEAR(p.alpha, 27.1, 0.05);
  EXPECT_NEAR(p.w_d, 0.498, 5e-4);
  EXPECT_NEAR(p.c_hg, 1.0 - p.g_hg, 1e-15);
  EXPECT_NEAR(f64::mie_mean_cosine(p), 0.879, 5e-4);
  // The mean cosine is the integral, not just the formula.
  const double mean = cv::test::sphere_integral([&](double mu) { return mu * f64::phase_mie(mu, p); });
  EXPECT_NEAR(mean, f64::mie_mean_cosine(p), 1e-6);
}

TEST(Mie, NormalisedWithValidParametersOverTheWholeRange) {
  for (int i = 0; i <= 160; ++i) {
    const double d = 0.01 * std::pow(5000.0, i / 160.0);  // 0.01 .. 50 um, log-spaced
    const auto p = f64::mie_params(d);
    ASSERT_LT(std::abs(p.g_hg), 1.0) << "d=" << d;
    ASSERT_NEAR(p.c_hg, 1.0 - std::abs(p.g_hg), 1e-14) << "d=" << d;
    ASSERT_LT(std::abs(p.g_d), 1.0) << "d=" << d;
    ASSERT_GE(p.alpha, 0.0) << "d=" << d;
    ASSERT_GE(p.w_d, 0.0) << "d=" << d;
    ASSERT_LE(p.w_d, 1.0) << "d=" << d;
    const double norm = cv::test::sphere_integral([&](double mu) { return f64::phase_mie(mu, p); });
    EXPECT_NEAR(norm, 1.0, 1e-6) << "d=" << d;
    const double mean = cv::test::sphere_integral([&](double mu) { return mu * f64::phase_mie(mu, p); });
    EXPECT_NEAR(mean, f64::mie_mean_cosine(p), 1e-6) << "d=" << d;
  }
}

std::array<double, 5> fields(const f64::MieParams& p) { return {p.g_hg, p.c_hg, p.g_d, p.alpha, p.w_d}; }

TEST(Mie, DiametersOutsideTheFitAreClamped) {
  EXPECT_EQ(fields(f64::mie_params(0.001)), fields(f64::mie_params(0.01)));
  EXPECT_EQ(fields(f64::mie_params(80.0)), fields(f64::mie_params(50.0)));
}

struct Jump {
  double d_um;
  double mean_cosine;      // |mean cosine just below - just above|
  double phase_rel;        // max over mu of |p_below - p_above| / p_above
  double max_param_rel;    // largest relative jump among the four parameters
};

Jump measure_jump(double d) {
  const double below = std::nextafter(d, 0.0), above = std::nextafter(d, 100.0);
  const auto a = f64::mie_params(below), b = f64::mie_params(above);
  Jump j{d, std::abs(f64::mie_mean_cosine(a) - f64::mie_mean_cosine(b)), 0.0, 0.0};
  for (int i = 0; i <= 4000; ++i) {
    const double mu = -1.0 + i / 2000.0;
    const double pa = f64::phase_mie(mu, a), pb = f64::phase_mie(mu, b);
    j.phase_rel = std::max(j.phase_rel, std::abs(pa - pb) / pb);
  }
  const auto fa = fields(a), fb = fields(b);
  for (size_t k = 0; k < fa.size(); ++k) {
    j.max_param_rel = std::max(j.max_param_rel, std::abs(fa[k] - fb[k]) / std::abs(fb[k]));
  }
  return j;
}

TEST(Mie, BranchBoundariesJumpOnlyAsFarAsThePublishedFitDoes) {
  // The published fit is piecewise and not continuous in its parameters; what must stay nearly
  // continuous is the physics it stands for, the mean cosine. Bounds are the measured jumps
  // (0.0143, 0.0022, 0.0008) rounded up, so a wrong coefficient shows up here.
  const double bound[3] = {0.015, 0.0025, 0.001};
  const double ds[3] = {0.1, 1.5, 5.0};
  for (int i = 0; i < 3; ++i) {
    const Jump j = measure_jump(ds[i]);
    std::printf("d=%.1f um: mean-cosine jump %.4f, max phase jump %.1f %%, max parameter jump %.1f %%\n", j.d_um,
                j.mean_cosine, 100 * j.phase_rel, 100 * j.max_param_rel);
    EXPECT_LT(j.mean_cosine, bound[i]) << "d=" << ds[i];
  }
  // At 5 um, where clouds live, the two branches agree closely in shape as well.
  EXPECT_LT(measure_jump(5.0).phase_rel, 0.1);
}

TEST(Mie, FloatBuildMatchesDouble) {
  double worst = 0.0;
  for (int i = 0; i <= 200; ++i) {
    const double d = 0.01 * std::pow(5000.0, i / 200.0);
    const auto pd = fields(f64::mie_params(static_cast<double>(static_cast<float>(d))));
    const auto p = f32::mie_params(static_cast<float>(d));
    const std::array<double, 5> pf = {p.g_hg, p.c_hg, p.g_d, p.alpha, p.w_d};
    for (size_t k = 0; k < pf.size(); ++k) {
      worst = std::max(worst, std::abs(pf[k] - pd[k]) / std::max(std::abs(pd[k]), 1e-3));
    }
  }
  EXPECT_LT(worst, 1e-5);
}

TEST(Mie, FloatForwardPeakKeepsItsDigitsForLargeDroplets) {
  // At 50 um the HG lobe has 1 - g ~ 0.002 and the peak ~2e4/sr; 1 - g taken from a float g would
  // be off by ~3e-5 relative and the peak by twice that.
  double worst = 0.0;
  for (float d : {10.0f, 20.0f, 35.0f, 50.0f}) {
    for (float mu : {1.0f, 0.99999f, 0.999f, 0.9f}) {
      const double ref = f64::phase_mie(mu, f64::mie_params(d));
      worst = std::max(worst, std::abs(f32::phase_mie(mu, f32::mie_params(d)) - ref) / ref);
    }
  }
  EXPECT_LT(worst, 2e-6);
  std::printf("worst float/double Mie phase difference in the forward peak: %.3g\n", worst);
}

}  // namespace
