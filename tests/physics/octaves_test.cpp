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

// The octave gate (octaves.glsl): w -> 0 leaves single scattering exactly, w = 1 the classic sum
// exactly, and in between octave i carries (b w)^i until that falls below the tolerance.
TEST(OctaveGate, NoColumnDepthLeavesSingleScatteringExactly) {
  EXPECT_EQ(f64::octave_gate_weight(0.0), 0.0);
  const double tol = f64::CV_OCTAVE_GATE_TOL;
  for (double tau : {0.0, 0.7, 4.0}) {
    EXPECT_EQ(f64::ms_octaves_hg_gated(0.02, 0.4, 0.8, tau, 8, 0.5, 0.5, 0.5, 0.0, tol),
              f64::ms_octaves_hg(0.02, 0.4, 0.8, tau, 1, 0.5, 0.5, 0.5));
    const f64::MieParams p = f64::mie_params(20.0);
    EXPECT_EQ(f64::ms_octaves_mie_gated(0.02, -0.2, p, tau, 8, 0.5, 0.5, 0.5, f64::octave_gate_weight(0.0), tol),
              f64::ms_octaves_mie(0.02, -0.2, p, tau, 1, 0.5, 0.5, 0.5));
  }
}

TEST(OctaveGate, FullWeightIsTheClassicSumExactly) {
  // Thick cloud: w = 1 - exp(-tau_col) rounds to 1 in double from tau_col ~ 37.
  EXPECT_EQ(f64::octave_gate_weight(50.0), 1.0);
  const double w = f64::octave_gate_weight(50.0), tol = f64::CV_OCTAVE_GATE_TOL;
  const f64::MieParams p = f64::mie_params(20.0);
  for (int n : {1, 4, 8}) {
    // Against the sum written out here, and against the ungated function, bit for bit.
    double sum = 0.0;
    for (int i = 0; i < n; ++i) {
      sum += std::pow(0.5, i) * f64::phase_hg(0.3, std::pow(0.5, i) * 0.8) * std::exp(-std::pow(0.5, i) * 2.0);
    }
    const double gated = f64::ms_octaves_hg_gated(0.05, 0.3, 0.8, 2.0, n, 0.5, 0.5, 0.5, w, tol);
    EXPECT_NEAR(gated, 0.05 * sum, 1e-15) << n;
    EXPECT_EQ(gated, f64::ms_octaves_hg(0.05, 0.3, 0.8, 2.0, n, 0.5, 0.5, 0.5)) << n;
    EXPECT_EQ(f64::ms_octaves_mie_gated(0.05, 0.3, p, 2.0, n, 0.5, 0.5, 0.5, w, tol),
              f64::ms_octaves_mie(0.05, 0.3, p, 2.0, n, 0.5, 0.5, 0.5))
        << n;
  }
}

TEST(OctaveGate, ThinColumnsWeightOctavesAndStopEarly) {
  // b w = 0.2: weights 1, 0.2, 0.04, 0.008, 0.0016, then 0.00032 < 1e-3 ends the sum at 5 octaves.
  const double a = 0.5, b = 0.5, c = 0.5, w = 0.4, tau = 0.3, g = 0.75, mu = 0.1;
  double five = 0.0;
  for (int i = 0; i < 5; ++i) {
    five += std::pow(b * w, i) * f64::phase_hg(mu, std::pow(c, i) * g) * std::exp(-std::pow(a, i) * tau);
  }
  const double tol = f64::CV_OCTAVE_GATE_TOL;
  EXPECT_NEAR(f64::ms_octaves_hg_gated(1.0, mu, g, tau, 16, a, b, c, w, tol), five, 1e-15);
  EXPECT_NEAR(f64::ms_octaves_hg_gated(1.0, mu, g, tau, 5, a, b, c, w, tol), five, 1e-15);
  // The statistics' count is the sum's: 5 terms here, all of them without the gate, 1 at w = 0.
  EXPECT_EQ(f64::octave_terms(16, b, w, tol), 5);
  EXPECT_EQ(f32::octave_terms(16, 0.5f, 0.4f, f32::CV_OCTAVE_GATE_TOL), 5);
  EXPECT_EQ(f64::octave_terms(4, b, 1.0, 0.0), 4);
  EXPECT_EQ(f64::octave_terms(4, b, 0.0, tol), 1);
  // Without the tolerance the sixth octave is there.
  EXPECT_GT(f64::ms_octaves_hg_gated(1.0, mu, g, tau, 16, a, b, c, w, 0.0), five + 1e-5);
  // Thin cirrus (tau_col 0.2): the second octave carries b w = 0.5 (1 - e^-0.2) = 0.09 of the first.
  EXPECT_NEAR(f64::octave_gate_weight(0.2), 1.0 - std::exp(-0.2), 1e-15);
  // The float instantiation (the GPU's) agrees.
  EXPECT_NEAR(f32::ms_octaves_hg_gated(1.0f, 0.1f, 0.75f, 0.3f, 16, 0.5f, 0.5f, 0.5f, 0.4f, f32::CV_OCTAVE_GATE_TOL), five,
              1e-6 * five);
}

}  // namespace
