// The diffuse radiance inside a homogeneous plane-parallel slab, by discrete ordinates, with its
// angular moments at any depth (docs/physics.md, "The slab's diffuse radiance by discrete
// ordinates"). A step toward the source of higher angular order that the deck's error asks for
// ("What is left on the deck is one-dimensional"): the scaled problem of a smaller truncation (the
// phase cut flat at the level that leaves a share f = g^8 above it) solved with every Fourier mode
// the moments need, so that the diffuse light scattered toward any direction,
//
//   J(mu, phi) = omega sum_m cos(m phi) sum_{l >= m} (2 l + 1) / 2 chi_l Lambda_l^m(mu) psi_lm(tau),
//
// follows from the moments psi_lm(tau) = int Lambda_l^m(mu') I^m(tau, mu') dmu' (to any degree; the
// march's tables keep degree 15 in the azimuthal mean and 7 for m = 1..7: 44 numbers,
// shaders/kernel/ms_slab.glsl).
//
// Conventions: tau is the optical depth from the top, down; mu the cosine of a direction of travel to
// the downward vertical (mu > 0 travels down, into the slab); phi the azimuth of the direction of
// travel from the sun's beam's (phi = 0: travelling on in the beam's azimuth). The beam falls on the
// top at mu0 with irradiance 1 normal to it; I(tau, mu, phi) = sum_m I^m(tau, mu) cos(m phi) is the
// diffuse radiance per unit of that irradiance. The ground below is black. The phase is given by
// its Legendre moments chi_l = 2 pi int p P_l dmu (chi_0 = 1, chi_1 the mean cosine), so
// p(cos theta) = sum_l (2 l + 1) / (4 pi) chi_l P_l(cos theta), and Lambda_l^m = sqrt((l - m)! /
// (l + m)!) P_l^m are the normalised associated Legendre functions.
#pragma once

#include <functional>
#include <utility>
#include <vector>

namespace cv::core {

// Lambda_l^m(mu) for l = m .. l_max (index l - m), by the normalised three-term recurrence.
std::vector<double> ms_slab_legendre(int m, int l_max, double mu);

// The Legendre moments chi_0 .. chi_l_max of a phase function (per steradian, of the scattering
// cosine) cut flat at `cut` and renormalised: min(p, cut) / (1 - f), f the share above the cut. The
// cut's cone is found from the forward direction (p must fall below `cut` once and stay below it
// toward the back); the part below the cut is integrated by Gauss-Legendre panels, the flat part in
// closed form. *share_cut receives f when given.
std::vector<double> ms_clipped_moments(const std::function<double(double)>& phase, double cut, int l_max,
                                       double* share_cut = nullptr);

// The Legendre moments chi_0 .. chi_l_max of a phase function over the sphere, by the trapezoid on
// cosines packed geometrically toward the forward direction (1 - mu from 1e-12 to 2), so a droplet's
// forward lobe narrower than a degree is resolved.
std::vector<double> ms_phase_moments(const std::function<double(double)>& phase, int l_max);

// The share f the higher-order source truncates from a phase (docs/physics.md, "The higher-order
// source"): delta-M's with eight moments, f = chi_8; for a droplets' Mie fit whose narrow HG lobe
// (weight spike_weight, kept apart by the beam's table) would not fit within it, enough to hold the
// lobe: f = max(chi_8, spike_weight / 0.98). Henyey-Greenstein: g^8.
double ms_slab_share(const std::function<double(double)>& phase, double spike_weight = 0.0);

class MsSlabField;

// The eigen-solutions of one homogeneous medium (phase moments, single-scattering albedo) for
// `streams` Gauss nodes per hemisphere and Fourier modes 0 .. modes - 1: made once, shared by every
// optical depth and sun. The phase's moments beyond 2 streams - 2 are dropped (the quadrature cannot
// hold them, and with them the conservative slab's diffusion solution would not be exact).
class MsSlab {
 public:
  MsSlab(std::vector<double> chi, double omega, int streams = 16, int modes = 8);

  // The slab of optical depth tau (>= 0) under a sun at cosine mu0 (0 < mu0 <= 1).
  MsSlabField solve(double tau, double mu0) const;
  // The slab lit from below by isotropic radiance 1 going up at its bottom (a Lambertian ground's
  // light), nothing from above: the azimuthal mean alone.
  MsSlabField solve_lit_from_below(double tau) const;

  int streams() const { return n_; }
  int modes() const { return static_cast<int>(modes_.size()); }
  const std::vector<double>& nodes() const { return mu_; }    // Gauss nodes on (0, 1)
  const std::vector<double>& weights() const { return w_; }  // their weights (sum 1)
  const std::vector<double>& chi() const { return chi_; }
  double omega() const { return omega_; }

  struct Mode {
    int m = 0;
    std::vector<double> k;            // eigenvalues (n), >= 0
    std::vector<double> gp, gm;       // eigenvectors (n x n, column j = solution j): down and up halves
    bool conservative_pair = false;   // solution 0 is the pair 1 and mu - (1 - chi_1) tau (m = 0, omega = 1)
    std::vector<double> lam_pos;      // Lambda_l^m(mu_i), l = m .. l_max, row-major (n x (l_max - m + 1))
    std::vector<double> d_same, d_opp;  // omega sum_l (2l + 1) / 2 chi_l Lambda_l^m(mu_i) Lambda_l^m(+-mu_j)
  };

 private:
  friend class MsSlabField;
  MsSlabField solve_any(double tau, double mu0, bool from_below) const;
  std::vector<double> chi_;
  double omega_;
  int n_;
  int l_max_;
  std::vector<double> mu_, w_;
  std::vector<Mode> modes_;
};

// One slab's solution: the diffuse radiance at the Gauss nodes at any depth, its moments and fluxes.
class MsSlabField {
 public:
  // I^m(tau, mu) at node i: i < streams the downward direction mu_i, i >= streams the upward one
  // -mu_(i - streams). t is clamped to the slab.
  double radiance(int m, int i, double t) const;
  // psi_lm(t) = int_-1^1 Lambda_l^m(mu) I^m(t, mu) dmu by the quadrature, for 0 <= m <= l <= l_max
  // (l_max <= 2 streams - 1), index l (l + 1) / 2 + m; modes not solved give zero.
  std::vector<double> moments(double t, int l_max) const;
  // The diffuse light scattered toward (mu, phi) per unit extinction at depth t, J above, from the
  // moments to l_max.
  double in_scatter(double t, double mu, double phi, int l_max) const;
  // Net downward flux (diffuse and direct) per unit irradiance normal to the beam: constant in t
  // on a conservative slab.
  double net_flux(double t) const;
  // The upward diffuse flux at depth t per unit irradiance normal to the beam.
  double up_flux(double t) const;
  // Upward diffuse flux at the top and downward diffuse flux at the bottom, over mu0.
  double reflected_flux() const;
  double transmitted_diffuse_flux() const;
  double tau() const { return tau_; }
  double mu0() const { return mu0_; }

 private:
  friend class MsSlab;
  const MsSlab* slab_ = nullptr;
  double tau_ = 0.0, mu0_ = 1.0;
  bool beam_ = true;  // lit by the sun's beam from above; else from below (solve_lit_from_below)
  struct ModeSolution {
    std::vector<double> a, b;   // coefficients of the solutions decaying from the top and from the bottom
    std::vector<double> zp, zm;  // the beam's particular solution, down and up halves
  };
  std::vector<ModeSolution> sol_;
};

// The slab table of one phase (shaders/kernel/ms_slab.glsl for its layout; docs/physics.md, "The
// higher-order source"): for a conservative homogeneous slab with the optical depth t above a point
// and b below it, under a sun at mu0, the moments psi_lm of the diffuse radiance of the problem
// truncated at the share f (ms_slab_share; the phase cut flat there, its moments chi'_l) by discrete
// ordinates, times (2l + 1) / 2 chi'_l, per unit irradiance; the diffuse flux going down; and the
// two-stream's I0 there for a phase of mean cosine g_two_stream (ms_slab_two_stream_i0). The march
// weighs it by its node's slab factor (the source's I0 over that I0, which carries the 3-D light). Made in parallel; about a third of a second per phase on two cores.
struct MsSlabTable {
  std::vector<float> values;  // CV_MS_SLAB_PHASE_SIZE
  std::vector<float> below;   // CV_MS_SLAB_BELOW_SIZE: the slab lit from below
  double f = 0.0;             // the share truncated
  double cut = 0.0;           // the phase's cut (1/sr) that leaves f above it
  std::vector<double> chi;    // the cut phase's moments to 2 streams - 2
};
// The mean diffuse radiance I0 that the delta-scaled two-stream (two_stream_column, its default
// closure) gives at a point of a conservative homogeneous slab over a black ground with the optical
// depth t above it and b below, under a sun at mu0, for a phase of mean cosine g.
double ms_slab_two_stream_i0(double t, double b, double mu0, double g);
// The same over a Lambertian ground of albedo `ground`: I0 there and the ground's radiance (its
// albedo times the flux that reaches it, over pi), per unit irradiance.
struct MsSlabTwoStream {
  double i0 = 0.0, ground_radiance = 0.0;
};
MsSlabTwoStream ms_slab_two_stream(double t, double b, double mu0, double g, double ground);

MsSlabTable ms_slab_table(const std::function<double(double)>& phase, double f, double g_two_stream, int streams = 16);

}  // namespace cv::core
