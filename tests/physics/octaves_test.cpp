// The multiple-scattering octave sum against its definition and its closed forms.
#include <gtest/gtest.h>

#include <cmath>

#include "physics/physics.hpp"

namespace {
using namespace cv::physics;

TEST(Octaves, OneOctaveIsSingleScattering) {
  for (double g : {-0.5, 0.0, 0.85}) {
    for (double tau : {0.0, 0.7, 30.0}) {
      EXPECT_NEAR(f64::ms_octaves_hg(0.02, 0.4, g, tau, 1, 0.5, 0.5, 0.5), 0.02 * f64::phase_hg(0.4, g) * std::exp(-tau),
                  1e-16);
    }
  }
  EXPECT_EQ(f64::ms_octaves_hg(0.02, 0.4, 0.8, 1.0, 0, 0.5, 0.5, 0.5), 0.0);
}

TEST(Octaves, IsotropicClosedForm) {
  // g = 0: sum_i b^i exp(-a^i tau) / (4 pi); at tau = 0 a geometric series (1 - b^N) / (1 - b).
  const double s = 0.01, a = 0.6, b = 0.45;
  for (int n : {1, 2, 4, 8}) {
    EXPECT_NEAR(f64::ms_octaves_hg(s, -0.3, 0.0, 0.0, n, a, b, 0.5),
                s / (4 * 3.14159265358979323846) * (1 - std::pow(b, n)) / (1 - b), 1e-15);
    double sum = 0;
    for (int i = 0; i < n; ++i) sum += std::pow(b, i) * std::exp(-std::pow(a, i) * 3.0);
    EXPECT_NEAR(f64::ms_octaves_hg(s, -0.3, 0.0, 3.0, n, a, b, 0.5), s * sum / (4 * 3.14159265358979323846), 1e-15);
  }
}

TEST(Octaves, MatchesTheDefinitionTermByTerm) {
  const double s = 0.05, mu = 0.9, g = 0.8, tau = 4.0, a = 0.5, b = 0.5, c = 0.5;
  const auto p = f64::mie_params(20.0);
  double hg = 0, mie = 0;
  for (int i = 0; i < 8; ++i) {
    const double ci = std::pow(c, i);
    hg += std::pow(b, i) * f64::phase_hg(mu, ci * g) * std::exp(-std::pow(a, i) * tau);
    const double g_hg = ci * p.g_hg, g_d = ci * p.g_d;
    const double phase = (1 - p.w_d) * f64::phase_hg(mu, g_hg) + p.w_d * f64::phase_draine(mu, g_d, p.alpha);
    mie += std::pow(b, i) * phase * std::exp(-std::pow(a, i) * tau);
  }
  EXPECT_NEAR(f64::ms_octaves_hg(s, mu, g, tau, 8, a, b, c), s * hg, 1e-15);
  EXPECT_NEAR(f64::ms_octaves_mie(s, mu, p, tau, 8, a, b, c), s * mie, 1e-14);
}

TEST(Octaves, MoreOctavesBrightenThickCloudsAndStayFinite) {
  // Deep inside a cloud (tau_sun = 50) single scattering is ~exp(-50); octaves carry light in.
  const double one = f64::ms_octaves_hg(0.05, 0.0, 0.8, 50.0, 1, 0.25, 0.5, 0.5);
  const double eight = f64::ms_octaves_hg(0.05, 0.0, 0.8, 50.0, 8, 0.25, 0.5, 0.5);
  EXPECT_GT(eight, 1e6 * one);
  EXPECT_TRUE(std::isfinite(f32::ms_octaves_mie(0.05f, 1.0f, f32::mie_params(20.0f), 1e4f, 16, 0.5f, 0.5f, 0.5f)));
}

}  // namespace
