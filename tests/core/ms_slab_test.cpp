// The slab's diffuse radiance by discrete ordinates (core/kernel/ms_slab): the normalised Legendre
// functions against the addition theorem, the clipped phase's moments against closed forms and the
// peak's share, energy kept at every depth of a conservative slab, the isotropic slab's diffusion
// solution, convergence of the moments in the number of streams, and no NaN at the extremes. The
// comparison with the tests' independent adding-doubling solver is in slab_check_test.cpp.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <vector>

#include "kernel/ms_slab.glsl"
#include "kernel/ms_slab.hpp"
#include "kernel/ms_source.hpp"
#include "physics/physics.hpp"

namespace cv::core {
namespace {
constexpr double kPi = 3.14159265358979323846;

double legendre(int l, double x) {
  double p0 = 1.0, p1 = x;
  if (l == 0) return 1.0;
  for (int k = 2; k <= l; ++k) {
    const double p2 = ((2 * k - 1) * x * p1 - (k - 1) * p0) / k;
    p0 = p1;
    p1 = p2;
  }
  return p1;
}

TEST(MsSlab, TheNormalisedLegendreFunctionsKeepTheAdditionTheorem) {
  // P_l(cos theta) = sum_m (2 - delta_m0) Lambda_l^m(mu) Lambda_l^m(mu') cos(m dphi).
  const double mus[] = {-0.93, -0.4, 0.0, 0.27, 0.81, 1.0};
  for (double mu : mus) {
    for (double mu2 : mus) {
      for (double dphi : {0.0, 0.7, 2.9}) {
        const double c = mu * mu2 + std::sqrt((1.0 - mu * mu) * (1.0 - mu2 * mu2)) * std::cos(dphi);
        for (int l = 0; l <= 12; ++l) {
          double sum = 0.0;
          for (int m = 0; m <= l; ++m) {
            const double a = ms_slab_legendre(m, l, mu).back(), b = ms_slab_legendre(m, l, mu2).back();
            sum += (m ? 2.0 : 1.0) * a * b * std::cos(m * dphi);
          }
          EXPECT_NEAR(sum, legendre(l, c), 1e-12) << "l " << l << " mu " << mu << " mu' " << mu2 << " dphi " << dphi;
        }
      }
    }
  }
  // Lambda_l^0 is P_l.
  for (int l = 0; l <= 20; ++l) EXPECT_NEAR(ms_slab_legendre(0, 20, 0.37)[static_cast<std::size_t>(l)], legendre(l, 0.37), 1e-13);
}

TEST(MsSlab, TheClippedPhasesMomentsAreThePhasesOwnWithoutACutAndKeepTheShareBelowIt) {
  const double g = 0.85;
  auto hg = [g](double mu) { return physics::f64::phase_hg(mu, g); };
  // A cut above the peak keeps the whole phase: chi_l = g^l.
  double share = -1.0;
  const std::vector<double> whole = ms_clipped_moments(hg, 1e9, 40, &share);
  for (int l = 0; l <= 40; ++l) EXPECT_NEAR(whole[static_cast<std::size_t>(l)], std::pow(g, l), 2e-9) << "l " << l;
  EXPECT_NEAR(share, 0.0, 1e-9);
  // A cut that leaves f = g^8 above it (ms_peak): the share found again, and the moments are those
  // of (HG - (HG - c)+) / (1 - f): chi_l = (g^l - f chi_l(K)) / (1 - f) with the peak kernel K, whose
  // mean cosine is ms_peak's g.
  const double f = std::pow(g, 8);
  const MsPeak peak = ms_peak(hg, f);
  const std::vector<double> chi = ms_clipped_moments(hg, peak.cut, 16, &share);
  EXPECT_NEAR(share, f, 2e-4 * f);
  EXPECT_NEAR(chi[0], 1.0, 1e-14);
  EXPECT_NEAR(chi[1], (g - f * peak.g) / (1.0 - f), 2e-4);
  // The cut phase is flatter than HG: every moment below the phase's own, and none negative at low l.
  for (int l = 1; l <= 16; ++l) {
    EXPECT_LT(chi[static_cast<std::size_t>(l)], std::pow(g, l)) << "l " << l;
    EXPECT_GT(chi[static_cast<std::size_t>(l)], -0.05) << "l " << l;
  }
  // Droplets' Mie fit at 20 um (its spike lies inside the cone): the moments by the same route stay
  // finite and chi_1 is the cut phase's mean cosine, below the fit's own.
  const physics::f64::MieParams mie = physics::f64::mie_params(20.0);
  auto mie_phase = [&mie](double mu) { return physics::f64::phase_mie(mu, mie); };
  const double gm = physics::f64::mie_mean_cosine(mie);
  const MsPeak pm = ms_peak(mie_phase, std::pow(gm, 8));
  const std::vector<double> cm = ms_clipped_moments(mie_phase, pm.cut, 30, &share);
  EXPECT_NEAR(share, std::pow(gm, 8), 5e-4);
  for (double v : cm) EXPECT_TRUE(std::isfinite(v));
  EXPECT_LT(cm[1], gm);
  EXPECT_GT(cm[1], 0.3);
}

TEST(MsSlab, AConservativeSlabKeepsItsNetFluxAtEveryDepth) {
  const double g = 0.85;
  auto hg = [g](double mu) { return physics::f64::phase_hg(mu, g); };
  const MsPeak peak = ms_peak(hg, std::pow(g, 8));
  const MsSlab slab(ms_clipped_moments(hg, peak.cut, 40), 1.0, 16, 8);
  for (double tau : {0.01, 0.5, 5.0, 50.0, 300.0}) {
    for (double mu0 : {0.05, 0.3, 0.5, 1.0}) {
      const MsSlabField f = slab.solve(tau, mu0);
      const double top = f.net_flux(0.0);
      // What comes in at the top (mu0) less what goes back up.
      EXPECT_NEAR(top, mu0 * (1.0 - f.reflected_flux()), 1e-12);
      for (double x : {0.0, 0.1, 0.37, 0.5, 0.9, 1.0}) EXPECT_NEAR(f.net_flux(x * tau), top, 1e-9 * mu0) << "tau " << tau << " mu0 " << mu0 << " at " << x;
      // Reflected, diffusely transmitted and direct light add to one.
      EXPECT_NEAR(f.reflected_flux() + f.transmitted_diffuse_flux() + std::exp(-tau / mu0), 1.0, 1e-9) << "tau " << tau << " mu0 " << mu0;
      EXPECT_GE(f.reflected_flux(), 0.0);
      EXPECT_LE(f.reflected_flux(), 1.0);
      // No diffuse light enters at the top, none comes up from the black ground.
      for (int i = 0; i < slab.streams(); ++i) {
        for (int m = 0; m < slab.modes(); ++m) {
          EXPECT_NEAR(f.radiance(m, i, 0.0), 0.0, 1e-10);
          EXPECT_NEAR(f.radiance(m, slab.streams() + i, tau), 0.0, 1e-10);
        }
      }
    }
  }
}

TEST(MsSlab, ADeepIsotropicSlabCarriesTheDiffusionSolution) {
  // Deep in a thick conservative slab the radiance is the diffusion solution I = a + b (mu - tau)
  // (isotropic scattering: I' = -(1 - chi_1) = -1): its anisotropy is the flux, 3 psi_10 / psi_00
  // per unit depth... checked as the moments: psi_1,0 = (2 / 3) b, and d psi_00 / dtau = -2 b.
  const MsSlab slab({1.0}, 1.0, 16, 1);
  const double tau = 200.0;
  const MsSlabField f = slab.solve(tau, 0.6);
  const double t = 100.0, h = 1.0;
  const std::vector<double> m0 = f.moments(t, 1), mp = f.moments(t + h, 1), mm = f.moments(t - h, 1);
  const double b = 1.5 * m0[1];  // index l (l + 1) / 2 + m: (1, 0) is 1
  EXPECT_GT(b, 0.0);
  EXPECT_NEAR((mp[0] - mm[0]) / (2.0 * h), -2.0 * b, 1e-9 * std::abs(b));
  // The net flux is 2 pi (2 / 3) b there (the beam is long gone), and equals the slab's.
  EXPECT_NEAR(2.0 * kPi * (2.0 / 3.0) * b, f.net_flux(0.0), 1e-9);
}

TEST(MsSlab, TheMomentsConvergeInTheNumberOfStreams) {
  const double g = 0.85;
  auto hg = [g](double mu) { return physics::f64::phase_hg(mu, g); };
  const MsPeak peak = ms_peak(hg, std::pow(g, 8));
  const std::vector<double> chi = ms_clipped_moments(hg, peak.cut, 126);
  const MsSlab coarse(chi, 1.0, 16, 8), fine(chi, 1.0, 32, 8);
  for (double tau : {1.0, 10.0}) {
    for (double mu0 : {0.5, 0.866}) {
      const MsSlabField a = coarse.solve(tau, mu0), b = fine.solve(tau, mu0);
      for (double x : {0.05, 0.5, 0.95}) {
        const std::vector<double> ma = a.moments(x * tau, 7), mb = b.moments(x * tau, 7);
        const double scale = std::abs(mb[0]);
        for (std::size_t k = 0; k < ma.size(); ++k) EXPECT_NEAR(ma[k], mb[k], 5e-3 * scale) << "tau " << tau << " mu0 " << mu0 << " x " << x << " moment " << k;
        // The diffuse light scattered toward several directions.
        for (double mu : {-0.9, -0.2, 0.4}) {
          for (double phi : {0.0, 1.5, 3.1}) {
            const double ja = a.in_scatter(x * tau, mu, phi, 7), jb = b.in_scatter(x * tau, mu, phi, 7);
            EXPECT_NEAR(ja, jb, 5e-3 * scale) << "tau " << tau << " mu0 " << mu0 << " x " << x << " mu " << mu << " phi " << phi;
          }
        }
      }
    }
  }
}

// The table the march reads (ms_slab_table): at its grid's cells the moments times (2l + 1) / 2
// chi'_l of a discrete-ordinates slab solved here on its own, the diffuse flux going down, and the
// two-stream's I0 of the same slab; the three-node column gives the homogeneous column's I0 at any
// depth; the share is g^8 for HG and holds the droplets' lobe.
TEST(MsSlab, TheTableHoldsTheSlabsLightAtItsCells) {
  const double g = 0.85;
  auto hg = [g](double mu) { return physics::f64::phase_hg(mu, g); };
  const double f = ms_slab_share(hg);
  EXPECT_NEAR(f, std::pow(g, 8), 1e-5);
  const MsSlabTable table = ms_slab_table(hg, f, g);
  ASSERT_EQ(table.values.size(), static_cast<std::size_t>(CV_MS_SLAB_PHASE_SIZE));
  for (float v : table.values) ASSERT_TRUE(std::isfinite(v));
  const MsSlab slab(table.chi, 1.0, 16, CV_MS_SLAB_L + 1);
  constexpr int nd = CV_MS_SLAB_DEPTHS;
  for (const auto& c : {std::array<int, 3>{0, 3, 5}, {4, 7, 1}, {9, 0, 12}, {6, 10, 10}}) {
    const int is = c[0], iv = c[1], iu = c[2];
    auto depth = [](int i) { const double u = double(i) / (nd - 1); return std::max(CV_MS_SLAB_T0 * u / (1.0 - u), 5.0e-4); };
    const double mu0 = CV_MS_SLAB_MU0_LO + (1.0 - CV_MS_SLAB_MU0_LO) * is / (CV_MS_SLAB_SUNS - 1);
    const double t = depth(iu), b = depth(iv);
    const MsSlabField fld = slab.solve((1.0 - f) * (t + b), mu0);
    const std::vector<double> psi = fld.moments((1.0 - f) * t, CV_MS_SLAB_L0);
    const float* cell = table.values.data() + static_cast<std::size_t>(((is * nd + iv) * nd + iu) * CV_MS_SLAB_STRIDE);
    int k = 0;
    for (int m = 0; m <= CV_MS_SLAB_L; ++m) {
      for (int l = m; l <= (m == 0 ? CV_MS_SLAB_L0 : CV_MS_SLAB_L); ++l, ++k) {
        const double want = (2 * l + 1) * 0.5 * table.chi[static_cast<std::size_t>(l)] * psi[static_cast<std::size_t>(l * (l + 1) / 2 + m)];
        EXPECT_NEAR(cell[k], want, 1e-5 * std::abs(psi[0]) + 1e-7) << "cell " << is << " " << iv << " " << iu << " l " << l << " m " << m;
      }
    }
    ASSERT_EQ(k, CV_MS_SLAB_MOMENTS);
    // The diffuse flux going down: 2 pi sum w mu I^0 over the downward nodes.
    double down = 0.0;
    for (int i = 0; i < slab.streams(); ++i)
      down += 2.0 * 3.14159265358979 * slab.weights()[static_cast<std::size_t>(i)] * slab.nodes()[static_cast<std::size_t>(i)] * fld.radiance(0, i, (1.0 - f) * t);
    EXPECT_NEAR(cell[CV_MS_SLAB_FLUX_DOWN], down, 1e-5 * down + 1e-7);
    EXPECT_NEAR(cell[CV_MS_SLAB_TWO_STREAM_I0], ms_slab_two_stream_i0(t, b, mu0, g), 1e-6);
  }
  // The three-node column against a homogeneous column of 401 nodes at its nodes.
  for (double tau : {0.3, 4.0, 60.0}) {
    for (double mu0 : {0.2, 0.9}) {
      const int n = 401;
      std::vector<double> sig(n, tau / (n - 1)), gg(n, g);
      const TwoStreamColumn col = two_stream_column(sig.data(), gg.data(), n, 1.0, mu0, 0.0);
      for (int k : {0, 37, 200, 399, 400}) {
        const double t = tau * (n - 1 - k) / (n - 1);  // node k from the bottom
        EXPECT_NEAR(ms_slab_two_stream_i0(t, tau - t, mu0, g), col.i0[static_cast<std::size_t>(k)], 1e-9 + 1e-7 * col.i0[static_cast<std::size_t>(k)])
            << "tau " << tau << " mu0 " << mu0 << " node " << k;
      }
    }
  }
  // The droplets at 20 um: at least delta-M's chi_8 and the fit's lobe.
  const physics::f64::MieParams mie = physics::f64::mie_params(20.0);
  auto mie_phase = [&mie](double mu) { return physics::f64::phase_mie(mu, mie); };
  const double chi8 = ms_phase_moments(mie_phase, 8)[8];
  const double fm = ms_slab_share(mie_phase, 1.0 - mie.w_d);
  EXPECT_GE(fm, chi8 - 1e-9);
  EXPECT_GE(fm, (1.0 - mie.w_d) / 0.98 - 1e-9);
  EXPECT_LT(fm, 0.6);
  EXPECT_NEAR(ms_phase_moments(mie_phase, 1)[0], 1.0, 1e-4);
  EXPECT_NEAR(ms_phase_moments(mie_phase, 1)[1], physics::f64::mie_mean_cosine(mie), 1e-3);
}

TEST(MsSlab, ExtremesGiveFiniteLight) {
  const double g = 0.85;
  auto hg = [g](double mu) { return physics::f64::phase_hg(mu, g); };
  const MsPeak peak = ms_peak(hg, std::pow(g, 8));
  const MsSlab slab(ms_clipped_moments(hg, peak.cut, 40), 1.0, 16, 8);
  const MsSlab absorbing(ms_clipped_moments(hg, peak.cut, 40), 0.5, 16, 8);
  for (const MsSlab* s : {&slab, &absorbing}) {
    for (double tau : {0.0, 1e-9, 1e4}) {
      for (double mu0 : {1e-4, 1.0}) {
        const MsSlabField f = s->solve(tau, mu0);
        for (double x : {0.0, 0.5, 1.0}) {
          for (double v : f.moments(x * tau, 7)) EXPECT_TRUE(std::isfinite(v)) << "tau " << tau << " mu0 " << mu0;
          EXPECT_TRUE(std::isfinite(f.in_scatter(x * tau, 0.3, 1.0, 7)));
        }
        EXPECT_GE(f.reflected_flux(), -1e-12);
        EXPECT_LE(f.reflected_flux(), 1.0 + 1e-12);
      }
    }
  }
  EXPECT_THROW(slab.solve(-1.0, 0.5), std::invalid_argument);
  EXPECT_THROW(slab.solve(1.0, 0.0), std::invalid_argument);
  EXPECT_THROW(slab.solve(1.0, std::nan("")), std::invalid_argument);
  EXPECT_THROW(MsSlab({0.5}, 1.0), std::invalid_argument);
  EXPECT_THROW(MsSlab({1.0}, 1.5), std::invalid_argument);
}

}  // namespace
}  // namespace cv::core
