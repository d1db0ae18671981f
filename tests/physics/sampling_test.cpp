// Importance sampling of HG, Draine, the Mie blend and dual-lobe HG: returned pdf equals eval,
// directions are unit length, and the histogram over (scattering angle, azimuth) passes a
// chi-square test against the pdf integrated over each bin.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "physics/physics.hpp"
#include "support/numeric.hpp"

namespace {
using namespace cv::physics;
using glm::dvec3;

constexpr double kPi = 3.14159265358979323846;
constexpr int kThetaBins = 48;
constexpr int kPhiBins = 4;
constexpr int kSamples = 200000;

// Theta edges crowd quadratically toward theta = 0 (and the last few toward pi), where peaked
// phase functions put their mass.
std::vector<double> mu_edges() {
  std::vector<double> mu;
  for (int k = 0; k <= kThetaBins; ++k) {
    const double t = static_cast<double>(k) / kThetaBins;
    mu.push_back(std::cos(kPi * t * t));
  }
  return mu;  // descending from 1 to -1
}

struct Sampler {
  std::string name;
  std::function<double(double)> pdf_mu;  // eval(mu)
  std::function<dvec3(const dvec3&, f64::uint&, double&)> sample;
};

void check_sampler(const Sampler& s) {
  const dvec3 wi = glm::normalize(dvec3(0.3, -0.5, 0.8));
  dvec3 t, b;
  f64::make_frame(wi, t, b);
  const auto edges = mu_edges();
  std::vector<double> observed(kThetaBins * kPhiBins, 0.0), expected(kThetaBins * kPhiBins, 0.0);
  for (int k = 0; k < kThetaBins; ++k) {
    const double p = 2.0 * kPi * cv::test::adaptive_simpson(s.pdf_mu, edges[k + 1], edges[k], 1e-12);
    for (int j = 0; j < kPhiBins; ++j) expected[k * kPhiBins + j] = kSamples * p / kPhiBins;
  }
  f64::uint rng = 12345u;
  double worst_pdf = 0.0, worst_len = 0.0;
  for (int n = 0; n < kSamples; ++n) {
    double pdf = 0.0;
    const dvec3 wo = s.sample(wi, rng, pdf);
    const double mu = glm::clamp(glm::dot(wi, wo), -1.0, 1.0);
    worst_pdf = std::max(worst_pdf, std::abs(pdf - s.pdf_mu(mu)) / s.pdf_mu(mu));
    worst_len = std::max(worst_len, std::abs(glm::length(wo) - 1.0));
    int k = 0;
    while (k < kThetaBins - 1 && mu < edges[k + 1]) ++k;
    double phi = std::atan2(glm::dot(wo, b), glm::dot(wo, t));
    if (phi < 0) phi += 2 * kPi;
    const int j = std::min(kPhiBins - 1, static_cast<int>(phi / (2 * kPi) * kPhiBins));
    observed[k * kPhiBins + j] += 1.0;
  }
  EXPECT_LT(worst_pdf, 1e-6) << s.name << ": pdf differs from eval";
  EXPECT_LT(worst_len, 1e-12) << s.name << ": direction not unit length";
  const auto r = cv::test::chi2_test(observed, expected);
  EXPECT_TRUE(r.pass()) << s.name << ": chi2 " << r.statistic << " > " << r.critical << " (dof " << r.dof << ")";
}

TEST(Sampling, HenyeyGreenstein) {
  for (double g : {-0.99, -0.7, -0.3, 0.0, 1e-4, 0.3, 0.7, 0.9, 0.99}) {
    check_sampler({"HG g=" + std::to_string(g), [g](double mu) { return f64::phase_hg(mu, g); },
                   [g](const dvec3& wi, f64::uint& rng, double& pdf) {
                     const double u1 = f64::rng_next(rng), u2 = f64::rng_next(rng);
                     return f64::sample_hg(wi, g, glm::dvec2(u1, u2), pdf);
                   }});
  }
}

TEST(Sampling, Draine) {
  for (double alpha : {0.0, 1.0, 27.1, 250.0}) {
    for (double g : {-0.8, 0.0, 0.3, 0.594, 0.95}) {
      check_sampler({"Draine g=" + std::to_string(g) + " alpha=" + std::to_string(alpha),
                     [=](double mu) { return f64::phase_draine(mu, g, alpha); },
                     [=](const dvec3& wi, f64::uint& rng, double& pdf) {
                       return f64::sample_draine(wi, g, alpha, rng, pdf);
                     }});
    }
  }
}

TEST(Sampling, MieBlend) {
  for (double d : {0.01, 0.05, 0.5, 1.5, 3.0, 5.0, 10.0, 20.0, 50.0}) {
    const auto p = f64::mie_params(d);
    check_sampler({"Mie d=" + std::to_string(d), [p](double mu) { return f64::phase_mie(mu, p); },
                   [p](const dvec3& wi, f64::uint& rng, double& pdf) { return f64::sample_mie(wi, p, rng, pdf); }});
  }
}

TEST(Sampling, DualLobeHenyeyGreenstein) {
  check_sampler({"dual HG", [](double mu) { return f64::phase_dual_hg(mu, 0.85, -0.3, 0.7); },
                 [](const dvec3& wi, f64::uint& rng, double& pdf) {
                   return f64::sample_dual_hg(wi, 0.85, -0.3, 0.7, rng, pdf);
                 }});
}

TEST(Sampling, ChiSquareDetectsAWrongSampler) {
  // The test has power: HG samples drawn with g = 0.70 fail against the pdf of g = 0.72.
  const double g = 0.72;
  const dvec3 wi(0, 0, 1);
  const auto edges = mu_edges();
  std::vector<double> observed(kThetaBins, 0.0), expected(kThetaBins, 0.0);
  for (int k = 0; k < kThetaBins; ++k) {
    expected[k] = kSamples * 2 * kPi *
                  cv::test::adaptive_simpson([g](double mu) { return f64::phase_hg(mu, g); }, edges[k + 1], edges[k],
                                             1e-12);
  }
  f64::uint rng = 7u;
  for (int n = 0; n < kSamples; ++n) {
    const double mu = f64::hg_sample_mu(0.70, f64::rng_next(rng));
    int k = 0;
    while (k < kThetaBins - 1 && mu < edges[k + 1]) ++k;
    observed[k] += 1;
  }
  EXPECT_FALSE(cv::test::chi2_test(observed, expected).pass());
}

TEST(Sampling, HgInverseCdfHasNoCancellationForSmallG) {
  // The textbook (1 + g^2 - t^2) / (2 g) loses all digits in float32 for |g| < 1e-4.
  double worst = 0.0;
  for (double g : {1e-7, 1e-5, 1e-3, -1e-4}) {
    for (int i = 0; i <= 1000; ++i) {
      const double u = i / 1000.0;
      const float gf = static_cast<float>(g), uf = static_cast<float>(u);
      const double ref = f64::hg_sample_mu(static_cast<double>(gf), static_cast<double>(uf));
      worst = std::max(worst, std::abs(f32::hg_sample_mu(gf, uf) - ref));
    }
  }
  EXPECT_LT(worst, 1e-6);
}

TEST(Sampling, RngIsUniformAndDeterministic) {
  f64::uint a = 99u, b = 99u;
  std::vector<double> obs(16, 0.0), exp(16, 100000.0 / 16);
  for (int i = 0; i < 100000; ++i) {
    const double x = f64::rng_next(a);
    ASSERT_EQ(x, f64::rng_next(b));
    ASSERT_GE(x, 0.0);
    ASSERT_LT(x, 1.0);
    obs[static_cast<int>(x * 16)] += 1;
  }
  EXPECT_TRUE(cv::test::chi2_test(obs, exp).pass());
}

}  // namespace
