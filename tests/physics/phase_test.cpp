// Every phase function integrates to 1 over the sphere and has the stated or closed-form mean
// cosine, across its whole parameter range; the float build keeps its digits in the forward peak.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "physics/physics.hpp"
#include "support/numeric.hpp"

namespace {
using namespace cv::physics;
using cv::test::sphere_integral;

constexpr double kNormTol = 1e-6;  // the issue asks for 1e-3; the quadrature reaches far below

std::vector<double> g_grid() {
  std::vector<double> g;
  for (int i = -99; i <= 99; ++i) g.push_back(i / 100.0);
  for (double x : {-0.999, -1e-3, 1e-6, 1e-3, 0.999}) g.push_back(x);
  return g;
}

void expect_normalised(const std::function<double(double)>& p, double mean_cos, const std::string& what) {
  const double norm = sphere_integral(p);
  const double mean = sphere_integral([&](double mu) { return mu * p(mu); });
  EXPECT_NEAR(norm, 1.0, kNormTol) << what;
  EXPECT_NEAR(mean, mean_cos, kNormTol) << what << " mean cosine";
}

// Mean cosine of Schlick's function with parameter k, closed form (1/k^2)(k - (1 - k^2) atanh k);
// for small |k| its series 2k/3 + 2k^3/15 + 2k^5/35 + ... avoids the cancellation.
double schlick_mean_cosine(double k) {
  if (std::abs(k) > 0.1) return (k - (1.0 - k * k) * std::atanh(k)) / (k * k);
  double sum = 0.0, kp = k;
  for (int n = 1; n < 20; ++n, kp *= k * k) sum += 2.0 * kp / ((2.0 * n + 1.0) * (2.0 * n - 1.0));
  return sum;
}

TEST(Quadrature, ResolvesTheNarrowestPeakAgainstTheClosedFormCdf) {
  // The HG CDF in mu is (1 - g^2) / (2 g) (1 / sqrt(1 + g^2 - 2 g mu) - 1 / (1 + g)).
  for (double g : {0.9, 0.99, 0.999, -0.999}) {
    auto cdf = [g](double mu) { return (1 - g * g) / (2 * g) * (1 / std::sqrt(1 + g * g - 2 * g * mu) - 1 / (1 + g)); };
    for (auto [a, b] : {std::pair{-1.0, 1.0}, std::pair{0.9, 1.0}, std::pair{0.999, 0.99999}, std::pair{-1.0, -0.99}}) {
      const double num = 2 * 3.14159265358979323846 *
                         cv::test::adaptive_simpson([g](double mu) { return f64::phase_hg(mu, g); }, a, b, 1e-12);
      EXPECT_NEAR(num, cdf(b) - cdf(a), 1e-9) << "g=" << g << " [" << a << ", " << b << "]";
    }
  }
  // A normalisation off by one part in 1e4 is caught.
  EXPECT_GT(std::abs(sphere_integral([](double mu) { return 1.0001 * f64::phase_hg(mu, 0.99); }) - 1.0), 10 * kNormTol);
}

TEST(Phase, IsotropicAndRayleighAreNormalisedWithZeroMeanCosine) {
  expect_normalised([](double) { return f64::phase_isotropic(); }, 0.0, "isotropic");
  expect_normalised([](double mu) { return f64::phase_rayleigh(mu); }, 0.0, "rayleigh");
}

TEST(Phase, HenyeyGreensteinOverFullRange) {
  for (double g : g_grid()) {
    expect_normalised([g](double mu) { return f64::phase_hg(mu, g); }, g, "HG g=" + std::to_string(g));
  }
}

TEST(Phase, CornetteShanksOverFullRange) {
  for (double g : g_grid()) {
    const double mean = 3.0 * g * (4.0 + g * g) / (5.0 * (2.0 + g * g));
    expect_normalised([g](double mu) { return f64::phase_cornette_shanks(mu, g); }, mean,
                      "Cornette-Shanks g=" + std::to_string(g));
  }
}

TEST(Phase, SchlickOverFullRangeOfK) {
  for (double k : g_grid()) {
    expect_normalised([k](double mu) { return f64::phase_schlick(mu, k); }, schlick_mean_cosine(k),
                      "Schlick k=" + std::to_string(k));
  }
}

TEST(Phase, SchlickMappingFromGStaysInsideTheValidRange) {
  // 1.55 g - 0.55 g^3 exceeds 1 for g above ~0.92; the mapping must clamp, or the phase function
  // turns negative.
  for (double g : g_grid()) {
    const double k = f64::schlick_k_from_g(g);
    EXPECT_LT(std::abs(k), 1.0) << "g=" << g;
    expect_normalised([k](double mu) { return f64::phase_schlick(mu, k); }, schlick_mean_cosine(k),
                      "Schlick from g=" + std::to_string(g));
  }
  EXPECT_NEAR(f64::schlick_k_from_g(0.5), 1.55 * 0.5 - 0.55 * 0.125, 1e-15);
}

TEST(Phase, DraineOverFullRange) {
  for (double alpha : {0.0, 0.5, 1.0, 5.0, 27.1, 100.0, 250.0}) {
    for (double g : g_grid()) {
      expect_normalised([=](double mu) { return f64::phase_draine(mu, g, alpha); },
                        f64::draine_mean_cosine(g, alpha),
                        "Draine g=" + std::to_string(g) + " alpha=" + std::to_string(alpha));
    }
  }
  // With alpha = 0 Draine is HG; with alpha = 1 and g = 0 it is Rayleigh.
  EXPECT_DOUBLE_EQ(f64::phase_draine(0.3, 0.7, 0.0), f64::phase_hg(0.3, 0.7));
  EXPECT_NEAR(f64::phase_draine(0.3, 0.0, 1.0), f64::phase_rayleigh(0.3), 1e-15);
}

TEST(Phase, DualLobeHenyeyGreenstein) {
  for (double w : {0.0, 0.3, 0.5, 0.9, 1.0}) {
    for (double g1 : {-0.9, 0.2, 0.85, 0.99}) {
      for (double g2 : {-0.99, -0.3, 0.0, 0.6}) {
        expect_normalised([=](double mu) { return f64::phase_dual_hg(mu, g1, g2, w); }, w * g1 + (1 - w) * g2,
                          "dual HG");
      }
    }
  }
}

TEST(Phase, FloatBuildKeepsItsDigitsInTheForwardPeak) {
  // The plain 1 + g^2 - 2 g mu cancels when g and mu are both near 1; our form does not.
  double worst = 0.0;
  for (double g : {0.9, 0.99, 0.999, -0.99, -0.999}) {
    for (double one_minus_mu : {0.0, 1e-7, 1e-5, 1e-3, 0.1, 1.0, 2.0}) {
      const double mu = (g > 0 ? 1.0 : -1.0) * (1.0 - one_minus_mu);
      const float muf = static_cast<float>(mu), gf = static_cast<float>(g);
      const double ref = f64::phase_hg(static_cast<double>(muf), static_cast<double>(gf));
      const double rel = std::abs(f32::phase_hg(muf, gf) - ref) / ref;
      worst = std::max(worst, rel);
    }
  }
  EXPECT_LT(worst, 1e-5);
  std::printf("worst float/double HG relative difference in the forward peak: %.3g\n", worst);
}

}  // namespace
