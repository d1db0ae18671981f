// The adding-doubling slab solver (slab_solver.hpp) checked on its own, before it checks the Monte
// Carlo: its phase functions and their moments, published figures (DISORT's test problems, which
// come from van de Hulst 1980), a second independent method (Lambda iteration of the integral
// equation), the known limits (single scattering, the diffusion asymptote with the Hopf constant,
// Chandrasekhar's H-function), energy conservation, and its quadrature convergence on the issue's
// sweep; off nadir, its reflection at an azimuth (every Fourier mode) against a plane-parallel Monte
// Carlo written here. Nothing here includes project code: the solver must not share any with the reference.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <vector>

#include "physics/slab_solver.hpp"

namespace {
using namespace slabcheck;
constexpr double kPi = 3.14159265358979323846;

double rel(double a, double b) { return std::abs(a / b - 1.0); }

TEST(SlabSolver, PhaseMomentsAreTheIntegralsOfThePhaseFunctions) {
  // The moments the solver uses (closed forms: g^l, and Draine's from mu^2 P_l by recurrence) against
  // quadrature of the phase functions themselves; moment 0 is the normalisation, 1 the mean cosine.
  struct Case {
    const char* name;
    PhaseFunction p;
    double mean_cosine;
  };
  const double gd = 0.59379, alpha = 27.114;
  const std::vector<Case> cases = {
      {"HG 0.85", henyey_greenstein_phase(0.85), 0.85},
      {"HG -0.6", henyey_greenstein_phase(-0.6), -0.6},
      {"Draine", draine_phase(gd, alpha), gd * (1 + alpha * (3 + 2 * gd * gd) / 5) / (1 + alpha * (1 + 2 * gd * gd) / 3)},
      // The anchor of the brief and docs/physics.md: mean cosine 0.87931 at 20 um.
      {"Mie 20 um", approximate_mie_phase(20.0), 0.87931},
  };
  for (const auto& c : cases) {
    const std::vector<double> closed = c.p.moments(256), quad = moments_by_quadrature(c.p.value, 256);
    double worst = 0.0;
    for (std::size_t l = 0; l < closed.size(); ++l) worst = std::max(worst, std::abs(closed[l] - quad[l]));
    std::printf("%-10s chi_0 %.12f  chi_1 %.6f  chi_64 %.6f  chi_256 %.6f  |closed - quadrature| <= %.1e\n", c.name, quad[0],
                quad[1], closed[64], closed[256], worst);
    EXPECT_NEAR(quad[0], 1.0, 1e-10) << c.name;
    EXPECT_NEAR(closed[1], c.mean_cosine, 5e-6) << c.name;
    EXPECT_LT(worst, 1e-9) << c.name;
  }
  // The fit's parameters at 20 um, as the brief and docs/physics.md state them.
  const MieFit f = approximate_mie_fit(20.0);
  EXPECT_NEAR(f.g_hg, 0.99461, 5e-6);
  EXPECT_NEAR(f.one_minus_g_hg, 1.0 - f.g_hg, 1e-15);
  EXPECT_NEAR(f.g_d, 0.59379, 5e-6);
  EXPECT_NEAR(f.alpha, 27.114, 5e-4);
  EXPECT_NEAR(f.w_d, 0.49816, 5e-6);
  EXPECT_THROW(approximate_mie_fit(2.0), std::invalid_argument);  // branch not written: refused
}

// DISORT's test problems 1 and 3 (Stamnes et al. 1988; DISOTEST, "compare to van de Hulst 1980,
// Table 12 / Table 37"), with FBEAM = pi / mu0 so that the printed intensities UU are R(mu, mu0) and
// FLUP / pi the plane albedo. Their figures are DISORT's own 16-stream answers: at 8 nodes per
// hemisphere (the same double-Gauss quadrature) the doubling reproduces them to their 6 digits for
// isotropic scattering, while converged (32 nodes) values differ by up to 1e-3 at grazing incidence
// (and agree with the Lambda iteration below to 1e-6).
struct Disort {
  const char* name;
  double tau, omega, g, mu0;
  double r1, r05, r01, flup;
};
const Disort kIsotropic[] = {
    {"1a", 0.03125, 0.2, 0.0, 0.1, 1.34041e-02, 2.64170e-02, 1.17771e-01, 7.99451e-02},
    {"1b", 0.03125, 1.0, 0.0, 0.1, 7.09192e-02, 1.39763e-01, 6.22884e-01, 4.22922e-01},
    {"1d", 32.0, 0.2, 0.0, 0.1, 5.02853e-02, 9.06967e-02, 2.62972e-01, 2.59686e-01},
    {"1e", 32.0, 1.0, 0.0, 0.1, 7.97199e-01, 1.02732e00, 1.93321e00, 3.07390},
};
const Disort kHenyeyGreenstein[] = {
    {"3a", 1.0, 1.0, 0.75, 1.0, 3.95460e-02, 1.01103e-01, 1.51159e-01, 2.47374e-01},
    {"3b", 8.0, 1.0, 0.75, 1.0, 4.93302e-01, 5.19598e-01, 3.79740e-01, 1.59096},
};

SlabSolution solve(const Disort& c, int streams) {
  SlabProblem p;
  p.tau = c.tau;
  p.omega = c.omega;
  p.phase = c.g == 0.0 ? isotropic_phase() : henyey_greenstein_phase(c.g);
  p.mu_extra = {1.0, 0.5, 0.1};
  SlabOptions o;
  o.streams = streams;
  return solve_slab(p, o);
}

TEST(SlabSolver, ReproducesDisortsIsotropicProblemsAtTheSameQuadrature) {
  for (const auto& c : kIsotropic) {
    const SlabSolution s = solve(c, 8);
    const double a = c.flup / kPi;
    std::printf("DISORT %s (tau %g, omega %g, mu0 %g): R(1) %.6f [%.6f]  R(0.5) %.6f [%.6f]  R(0.1) %.6f [%.6f]  A %.6f [%.6f]\n",
                c.name, c.tau, c.omega, c.mu0, s.reflection(1.0, c.mu0), c.r1, s.reflection(0.5, c.mu0), c.r05,
                s.reflection(0.1, c.mu0), c.r01, s.plane_albedo(c.mu0), a);
    // The figures carry 6 digits: 1e-5 relative.
    EXPECT_LT(rel(s.reflection(1.0, c.mu0), c.r1), 1e-5) << c.name;
    EXPECT_LT(rel(s.reflection(0.5, c.mu0), c.r05), 1e-5) << c.name;
    EXPECT_LT(rel(s.reflection(0.1, c.mu0), c.r01), 1e-5) << c.name;
    EXPECT_LT(rel(s.plane_albedo(c.mu0), a), 1e-5) << c.name;
  }
}

TEST(SlabSolver, MatchesDisortsHenyeyGreensteinFluxes) {
  // Problem 3 (HG g = 0.75, sun overhead). Fluxes converge fast in the number of streams, so the
  // converged plane albedo must match DISORT's to its digits. The intensities are DISORT's 16-stream
  // values with its delta-M and intensity corrections; its nadir figure for tau 1 (0.039546) is 1.1 %
  // above the converged 0.03909 (a plain photon Monte Carlo of 4e7 photons, written aside for this
  // check, gave 0.03911 +- 0.00003), so only the off-nadir ones are held, to 2e-3.
  for (const auto& c : kHenyeyGreenstein) {
    const SlabSolution s = solve(c, 32);
    const double a = c.flup / kPi;
    std::printf("DISORT %s (HG 0.75, tau %g): A %.6f [%.6f]  R(1) %.6f [%.6f]  R(0.5) %.6f [%.6f]  R(0.1) %.6f [%.6f]\n", c.name,
                c.tau, s.plane_albedo(1.0), a, s.reflection(1.0, 1.0), c.r1, s.reflection(0.5, 1.0), c.r05, s.reflection(0.1, 1.0),
                c.r01);
    EXPECT_LT(rel(s.plane_albedo(1.0), a), 5e-5) << c.name;
    EXPECT_LT(rel(s.reflection(0.5, 1.0), c.r05), 2e-3) << c.name;
    EXPECT_LT(rel(s.reflection(0.1, 1.0), c.r01), 2e-3) << c.name;
  }
}

// E_n(x) for the Lambda iteration: E1 by its series or continued fraction (Abramowitz & Stegun
// 5.1.11, 5.1.22), then E_{n+1} = (exp(-x) - x E_n) / n.
double expint_e1(double x) {
  if (x < 1.0) {
    double s = -0.57721566490153286 - std::log(x), term = 1.0;
    for (int k = 1; k < 60; ++k) {
      term *= -x / k;
      s -= term / k;
    }
    return s;
  }
  double b = x + 1.0, c = 1e300, d = 1.0 / b, h = d;
  for (int i = 1; i < 300; ++i) {
    const double an = -static_cast<double>(i) * i;
    b += 2.0;
    d = 1.0 / (an * d + b);
    c = b + an / c;
    const double del = c * d;
    h *= del;
    if (std::abs(del - 1.0) < 1e-16) break;
  }
  return h * std::exp(-x);
}
double expint_e3(double x) {
  if (x == 0.0) return 0.5;
  const double e2 = std::exp(-x) - x * expint_e1(x);
  return 0.5 * (std::exp(-x) - x * e2);
}

TEST(SlabSolver, AgreesWithLambdaIterationOfTheIntegralEquation) {
  // A second method for isotropic scattering: the source function S(t) = (omega / 4) exp(-t / mu0) +
  // (omega / 2) int E1(|t - t'|) S(t') dt' (F = 1), on cells where S is constant (the E1 kernel
  // integrated over the cells exactly, as E3 differences), iterated to convergence; R(mu, mu0) =
  // int S exp(-t / mu) dt / mu / mu0. DISORT's problem 1b: tau 0.03125, omega 1, mu0 0.1.
  const double tau = 0.03125, mu0 = 0.1, omega = 1.0;
  const int m = 400;
  const double h = tau / m;
  std::vector<double> s0(m), s(m), next(m), kern(m);
  for (int i = 0; i < m; ++i) s0[i] = 0.25 * omega * mu0 * (std::exp(-i * h / mu0) - std::exp(-(i + 1) * h / mu0)) / h;
  for (int k = 0; k < m; ++k) {
    const double v = k == 0 ? 2.0 * (h - (0.5 - expint_e3(h))) : expint_e3((k - 1) * h) - 2.0 * expint_e3(k * h) + expint_e3((k + 1) * h);
    kern[k] = 0.5 * omega * v / h;
  }
  s = s0;
  for (int it = 0; it < 200; ++it) {
    double change = 0.0;
    for (int i = 0; i < m; ++i) {
      double v = s0[i];
      for (int j = 0; j < m; ++j) v += kern[std::abs(i - j)] * s[j];
      next[i] = v;
      change = std::max(change, std::abs(v - s[i]));
    }
    s.swap(next);
    if (change < 1e-15) break;
  }
  SlabProblem p;
  p.tau = tau;
  p.phase = isotropic_phase();
  p.mu_extra = {1.0, 0.5, 0.1};
  const SlabSolution sol = solve_slab(p);  // 32 streams
  for (double mu : {1.0, 0.5, 0.1}) {
    double r = 0.0;
    for (int i = 0; i < m; ++i) r += s[i] * (std::exp(-i * h / mu) - std::exp(-(i + 1) * h / mu));
    r /= mu0;
    std::printf("Lambda iteration R(%.1f, 0.1) %.7f   doubling %.7f\n", mu, r, sol.reflection(mu, mu0));
    EXPECT_LT(rel(sol.reflection(mu, mu0), r), 2e-6) << mu;
  }
}

TEST(SlabSolver, SingleScatteringLimit) {
  // At tau 1e-6 multiple scattering is a correction of order tau: at nadir R(1, mu0) is single
  // scattering, (1/4) P(-mu0) (1 - exp(-tau (1 + 1/mu0))) / (1 + mu0) with P = 4 pi p. With delta-M
  // and TMS on (the Mie peak is truncated) it must hold as well as without.
  for (const PhaseFunction& ph : {henyey_greenstein_phase(0.85), approximate_mie_phase(20.0)}) {
    for (double theta : {0.0, 30.0, 60.0, 75.0}) {
      const double mu0 = std::cos(theta * kPi / 180.0), tau = 1e-6;
      SlabProblem p;
      p.tau = tau;
      p.phase = ph;
      p.mu_extra = {1.0, mu0};
      const SlabSolution s = solve_slab(p);
      const double ss = 0.25 * 4.0 * kPi * ph.value(-mu0) * -std::expm1(-tau * (1.0 + 1.0 / mu0)) / (1.0 + mu0);
      EXPECT_LT(rel(s.reflection(1.0, mu0), ss), 1e-5) << theta;
    }
  }
}

TEST(SlabSolver, ThickIsotropicSlabTransmitsAsTheDiffusionAsymptote) {
  // Conservative isotropic scattering, diffuse incidence: the transmitted flux tends to
  // 4 / (3 (tau + 2 q)) with q the Hopf constant 0.7104461 (the extrapolation length of the Milne
  // problem; Chandrasekhar 1960, Radiative Transfer, ch. IV), up to terms exponentially small in tau.
  const double q = 0.7104460896;
  std::vector<double> x, w;
  gauss_legendre(16, 0.0, 1.0, x, w);
  for (double tau : {32.0, 128.0, 1024.0}) {
    SlabProblem p;
    p.tau = tau;
    p.phase = isotropic_phase();
    p.mu_extra = x;
    const SlabSolution s = solve_slab(p);
    double t = 0.0, a = 0.0;
    for (std::size_t i = 0; i < x.size(); ++i) {
      t += 2.0 * w[i] * x[i] * s.total_transmission(x[i]);
      a += 2.0 * w[i] * x[i] * s.plane_albedo(x[i]);
    }
    const double asym = 4.0 / (3.0 * (tau + 2.0 * q));
    std::printf("tau %6.0f: diffuse transmission %.9f, 4/(3(tau + 2q)) %.9f, relative %.1e, A + T - 1 %.1e\n", tau, t, asym,
                t / asym - 1.0, a + t - 1.0);
    EXPECT_LT(rel(t, asym), 1e-6) << tau;
  }
}

TEST(SlabSolver, SemiInfiniteIsotropicReflectionIsChandrasekharsHFunction) {
  // Conservative isotropic scattering: R_inf(1, 1) = H(1)^2 / 8, H(1) = 2.90781 (Chandrasekhar 1960,
  // the H-function of conservative isotropic scattering). A finite slab approaches it as c / (tau +
  // 2 q); two thick slabs extrapolate to tau -> infinity.
  const double q = 0.7104460896;
  auto r11 = [](double tau) {
    SlabProblem p;
    p.tau = tau;
    p.phase = isotropic_phase();
    p.mu_extra = {1.0};
    return solve_slab(p).reflection(1.0, 1.0);
  };
  const double t1 = 512.0, t2 = 2048.0, r1 = r11(t1), r2 = r11(t2);
  const double r_inf = (r2 * (t2 + 2 * q) - r1 * (t1 + 2 * q)) / (t2 - t1);
  const double h1 = 2.90781;
  std::printf("R(1,1): tau 512 %.7f, 2048 %.7f, extrapolated %.7f; H(1)^2 / 8 = %.7f\n", r1, r2, r_inf, h1 * h1 / 8.0);
  EXPECT_LT(rel(r_inf, h1 * h1 / 8.0), 1e-5);
}

// The sweep.
const double kTaus[] = {1, 2, 5, 10, 20, 50, 100};
const double kZeniths[] = {0, 30, 60, 75};

SlabProblem sweep_problem(double tau, const PhaseFunction& ph) {
  SlabProblem p;
  p.tau = tau;
  p.phase = ph;
  p.mu_extra = {1.0};
  for (double z : kZeniths) p.mu_extra.push_back(std::cos(z * kPi / 180.0));
  return p;
}

TEST(SlabSolver, ConservativeSlabsNeitherGainNorLoseEnergy) {
  // The "never": on a conservative slab reflected plus transmitted never exceeds the incident.
  // Here they equal it, to rounding, on every case of the sweep and with either phase.
  double worst = 0.0, most = 0.0;
  for (const PhaseFunction& ph : {henyey_greenstein_phase(0.85), approximate_mie_phase(20.0)}) {
    for (double tau : kTaus) {
      const SlabSolution s = solve_slab(sweep_problem(tau, ph));
      for (double z : kZeniths) {
        const double mu0 = std::cos(z * kPi / 180.0);
        const double a = s.plane_albedo(mu0), t = s.total_transmission(mu0);
        EXPECT_GE(a, 0.0);
        EXPECT_GE(t, 0.0);
        EXPECT_LE(a + t, 1.0 + 1e-12) << tau << " " << z;
        worst = std::max(worst, std::abs(a + t - 1.0));
        most = std::max(most, a + t);
      }
    }
  }
  std::printf("over the sweep: |A + T - 1| <= %.1e, largest A + T = 1 %+.1e\n", worst, most - 1.0);
  EXPECT_LT(worst, 1e-9);
}

TEST(SlabSolver, ConvergesInTheNumberOfStreamsOnTheSweep) {
  // The solver's stated uncertainty: the change from N to 2N streams per hemisphere. HG 0.85 at 32
  // against 64; the Mie phase (forward peak truncated by delta-M, f = 0.25 at 64 and 0.13 at 128
  // streams) at 64 against 128. Printed: the reference values the Monte Carlo is held to.
  struct Case {
    const char* name;
    PhaseFunction p;
    int n;
    double radiance_tol, albedo_tol;  // relative, what docs/physics.md states
  };
  const Case cases[] = {{"HG 0.85", henyey_greenstein_phase(0.85), 32, 1e-5, 1e-6},
                        {"Mie 20 um", approximate_mie_phase(20.0), 64, 1e-2, 1e-5}};
  for (const auto& c : cases) {
    double worst_i = 0.0, worst_a = 0.0;
    for (double tau : kTaus) {
      SlabOptions o1, o2;
      o1.streams = c.n;
      o2.streams = 2 * c.n;
      const SlabProblem p = sweep_problem(tau, c.p);
      const SlabSolution a = solve_slab(p, o1), b = solve_slab(p, o2);
      std::printf("%s tau %5.0f:", c.name, tau);
      for (double z : kZeniths) {
        const double mu0 = std::cos(z * kPi / 180.0);
        std::printf("  %2.0f: I/E %.5f A %.5f", z, b.nadir_radiance(mu0), b.plane_albedo(mu0));
        worst_i = std::max(worst_i, rel(a.nadir_radiance(mu0), b.nadir_radiance(mu0)));
        worst_a = std::max(worst_a, rel(a.plane_albedo(mu0), b.plane_albedo(mu0)));
      }
      std::printf("\n");
    }
    std::printf("%s: %d -> %d streams changes the nadir radiance by <= %.1e, the plane albedo by <= %.1e (relative)\n", c.name, c.n,
                2 * c.n, worst_i, worst_a);
    EXPECT_LT(worst_i, c.radiance_tol) << c.name;
    EXPECT_LT(worst_a, c.albedo_tol) << c.name;
  }
}

// The reflection at an azimuth, summed over every Fourier mode, averages over the azimuth to the
// azimuthal mean the m = 0 solution gives (its single scattering corrected at the azimuth by the
// phase function itself, the mean's by a quadrature over the azimuth).
TEST(SlabSolver, AzimuthalModesAverageToTheMean) {
  for (double tau : {0.5, 5.0}) {
    SlabProblem p;
    p.tau = tau;
    p.phase = henyey_greenstein_phase(0.85);
    const double mu0 = std::cos(60.0 * kPi / 180.0);
    p.mu_extra = {mu0, 1.0, std::cos(45.0 * kPi / 180.0), std::cos(80.0 * kPi / 180.0)};
    SlabOptions o;
    o.azimuth_modes = 0;
    const SlabSolution s = solve_slab(p, o);
    std::vector<double> x, w;
    gauss_legendre(256, 0.0, kPi, x, w);
    for (double mu : {1.0, std::cos(45.0 * kPi / 180.0), std::cos(80.0 * kPi / 180.0)}) {
      double mean = 0.0;
      for (std::size_t k = 0; k < x.size(); ++k) mean += w[k] * s.reflection(mu, mu0, x[k]) / kPi;
      EXPECT_LT(rel(mean, s.reflection(mu, mu0)), 1e-4) << tau << " " << mu;
    }
  }
}

// The reflected radiance of a conservative Henyey-Greenstein slab over a black ground by a Monte
// Carlo written for this test (plane-parallel, photons from the sun's beam, the local estimate
// toward the view at every collision), per unit irradiance normal to the beam: I / E = (mu0 / N)
// sum p(Theta) exp(-tau / mu_v) / mu_v. Its standard error from the photons' spread.
struct McRadiance {
  double mean = 0.0, se = 0.0;
};
McRadiance planar_monte_carlo(double tau_total, double g, double mu0, double mu_v, double dphi, int photons, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  const double s0 = std::sqrt(1.0 - mu0 * mu0), sv = std::sqrt(1.0 - mu_v * mu_v);
  // The view's direction of travel (up); the beam's travels down along +x.
  const double vx = sv * std::cos(dphi), vy = sv * std::sin(dphi), vz = mu_v;
  auto hg = [g](double c) { return (1.0 - g * g) / (4.0 * kPi * std::pow(1.0 + g * g - 2.0 * g * c, 1.5)); };
  double sum = 0.0, sum2 = 0.0;
  for (int n = 0; n < photons; ++n) {
    double dx = s0, dy = 0.0, dz = -mu0, depth = 0.0, contrib = 0.0;
    for (int bounce = 0; bounce < 100000; ++bounce) {
      depth += -std::log(1.0 - u01(rng)) * -dz;  // optical path times the cosine below the horizontal
      if (depth <= 0.0 || depth >= tau_total) break;
      contrib += hg(dx * vx + dy * vy + dz * vz) * std::exp(-depth / mu_v) / mu_v;
      // A new direction: HG's cosine about the old one, a uniform azimuth.
      const double xi = u01(rng);
      const double t = (1.0 - g * g) / (1.0 - g + 2.0 * g * xi);
      const double c = std::clamp((1.0 + g * g - t * t) / (2.0 * g), -1.0, 1.0), sn = std::sqrt(std::max(0.0, 1.0 - c * c));
      const double ph = 2.0 * kPi * u01(rng), cp = std::cos(ph), sp = std::sin(ph);
      // An orthonormal frame about (dx, dy, dz).
      double ax = 0.0, ay = 0.0, az = 0.0;
      if (std::abs(dz) < 0.9) {
        const double l = std::sqrt(dx * dx + dy * dy);
        ax = -dy / l, ay = dx / l;
      } else {
        const double l = std::sqrt(dy * dy + dz * dz);
        ay = -dz / l, az = dy / l;
      }
      const double bx = dy * az - dz * ay, by = dz * ax - dx * az, bz = dx * ay - dy * ax;
      const double nx = c * dx + sn * (cp * ax + sp * bx), ny = c * dy + sn * (cp * ay + sp * by), nz = c * dz + sn * (cp * az + sp * bz);
      const double l = std::sqrt(nx * nx + ny * ny + nz * nz);
      dx = nx / l, dy = ny / l, dz = nz / l;
    }
    sum += contrib;
    sum2 += contrib * contrib;
  }
  const double mean = sum / photons, var = std::max(0.0, sum2 / photons - mean * mean);
  return {mu0 * mean, mu0 * std::sqrt(var / photons)};
}

// Off nadir the reflection depends on the azimuth (toward the sun's azimuth the forward-scattered
// light is several times that sent back toward the sun): every Fourier mode of the solver against
// the Monte Carlo above, within four standard errors and 1 % (the quadrature's error).
TEST(SlabSolver, ReflectionAtAnAzimuthMatchesAPlaneParallelMonteCarlo) {
  const double g = 0.85, tau = 5.0, mu0 = std::cos(60.0 * kPi / 180.0);
  SlabProblem p;
  p.tau = tau;
  p.phase = henyey_greenstein_phase(g);
  p.mu_extra = {mu0, std::cos(45.0 * kPi / 180.0), std::cos(70.0 * kPi / 180.0)};
  SlabOptions o;
  o.azimuth_modes = 0;
  const SlabSolution s = solve_slab(p, o);
  std::uint64_t seed = 11;
  for (double view : {45.0, 70.0}) {
    const double mu_v = std::cos(view * kPi / 180.0);
    double toward = 0.0, away = 0.0;
    for (double az : {0.0, 90.0, 180.0}) {
      const double dphi = az * kPi / 180.0;
      const McRadiance mc = planar_monte_carlo(tau, g, mu0, mu_v, dphi, 200000, seed++);
      const double ad = s.radiance(mu_v, mu0, dphi);
      std::printf("view %g, azimuth %g: adding-doubling I/E %.5f, Monte Carlo %.5f +- %.5f\n", view, az, ad, mc.mean, mc.se);
      EXPECT_LT(std::abs(ad - mc.mean), 4.0 * mc.se + 0.01 * ad) << view << " " << az;
      if (az == 0.0) toward = ad;
      if (az == 180.0) away = ad;
    }
    EXPECT_GT(toward, 1.5 * away) << view;  // the azimuth matters here: the check has something to see
  }
}

}  // namespace
