// The renderer's discrete-ordinates slab (core/kernel/ms_slab) against the tests' adding-doubling
// solver (tests/physics/slab_solver), which shares no code with it: the same phase (given to both
// by its Legendre moments), the same double-Gauss quadrature, no delta-M and no TMS in the solver,
// so both answer the same discrete problem by different methods. Reflected radiance at every node
// and azimuth, diffusely transmitted radiance at every node, for the Henyey-Greenstein 0.85 phase cut
// flat at f = g^8 and an isotropic one, thin to thick slabs, high to low suns.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "kernel/ms_slab.hpp"
#include "kernel/ms_source.hpp"
#include "physics/physics.hpp"
#include "physics/slab_solver.hpp"

namespace cv::core {
namespace {
constexpr double kPi = 3.14159265358979323846;

slabcheck::PhaseFunction phase_of_moments(const std::vector<double>& chi) {
  slabcheck::PhaseFunction p;
  p.moments = [chi](int l_max) {
    std::vector<double> out(static_cast<std::size_t>(l_max + 1), 0.0);
    for (std::size_t l = 0; l < out.size() && l < chi.size(); ++l) out[l] = chi[l];
    return out;
  };
  p.value = [chi](double mu) {  // only for TMS, which is off
    double s = 0.0, p0 = 1.0, p1 = mu;
    for (std::size_t l = 0; l < chi.size(); ++l) {
      const double pl = l == 0 ? 1.0 : (l == 1 ? mu : ((2.0 * l - 1.0) * mu * p1 - (l - 1.0) * p0) / l);
      if (l >= 2) p0 = p1, p1 = pl;
      s += (2.0 * l + 1.0) / (4.0 * kPi) * chi[l] * pl;
    }
    return s;
  };
  return p;
}

void compare(const std::vector<double>& chi_in, double omega, double tau, double mu0, double tol) {
  const int n = 8;
  const MsSlab slab(chi_in, omega, n, 2 * n - 1);
  const std::vector<double>& chi = slab.chi();  // as the slab keeps it (to 2 n - 2)
  slabcheck::SlabProblem prob;
  prob.tau = tau;
  prob.omega = omega;
  prob.phase = phase_of_moments(chi);
  prob.mu_extra = slab.nodes();  // the wanted directions: the nodes themselves, and the sun's
  prob.mu_extra.push_back(mu0);
  slabcheck::SlabOptions opt;
  opt.streams = n;
  opt.delta_m = false;
  opt.tms = false;
  opt.azimuth_modes = 0;
  const slabcheck::SlabSolution ad = slabcheck::solve_slab(prob, opt);
  const MsSlabField f = slab.solve(tau, mu0);
  double peak = 0.0;
  for (int i = 0; i < n; ++i) peak = std::max(peak, std::abs(f.radiance(0, n + i, 0.0)));
  ASSERT_GT(peak, 0.0);
  for (int i = 0; i < n; ++i) {
    const double mu = slab.nodes()[static_cast<std::size_t>(i)];
    for (double dphi : {0.0, 0.9, kPi / 2.0, 2.4, kPi}) {
      double up = 0.0;
      for (int m = 0; m < slab.modes(); ++m) up += f.radiance(m, n + i, 0.0) * std::cos(m * dphi);
      EXPECT_NEAR(up, ad.radiance(mu, mu0, dphi), tol * peak) << "reflected, tau " << tau << " mu0 " << mu0 << " mu " << mu << " dphi " << dphi;
    }
    // Diffusely transmitted, the azimuthal mean: I = mu0 T / pi.
    EXPECT_NEAR(f.radiance(0, i, tau), mu0 * ad.diffuse_transmission(mu, mu0) / kPi, tol * peak)
        << "transmitted, tau " << tau << " mu0 " << mu0 << " mu " << mu;
  }
  EXPECT_NEAR(f.reflected_flux(), ad.plane_albedo(mu0), tol);
}

TEST(MsSlabCheck, DiscreteOrdinatesAgreeWithAddingDoublingOnTheCutHenyeyGreenstein) {
  const double g = 0.85;
  auto hg = [g](double mu) { return physics::f64::phase_hg(mu, g); };
  const std::vector<double> chi = ms_clipped_moments(hg, ms_peak(hg, std::pow(g, 8)).cut, 40);
  for (double tau : {0.1, 1.0, 6.0, 40.0}) {
    for (double mu0 : {1.0, 0.6, 0.17}) compare(chi, 1.0, tau, mu0, 1e-8);
  }
  compare(chi, 0.9, 6.0, 0.6, 1e-8);  // absorbing: no conservative pair
}

TEST(MsSlabCheck, DiscreteOrdinatesAgreeWithAddingDoublingOnAnIsotropicSlab) {
  for (double tau : {0.03125, 1.0, 32.0}) {
    for (double mu0 : {1.0, 0.1}) compare({1.0}, 1.0, tau, mu0, 1e-8);
  }
}

}  // namespace
}  // namespace cv::core
