// An adding-doubling solver for a homogeneous plane-parallel slab, written for the tests as an
// independent check of the Monte Carlo reference (issue 11). It shares no code with the project: no
// header from core/ or shaders/ is included, and its phase functions (Henyey-Greenstein, Draine, the
// approximate Mie blend of Jendersie & d'Eon 2023) are written here again from the published
// formulas. docs/physics.md ("Plane-parallel slab check") states the method and its validation.
//
// Conventions (van de Hulst 1980, "Multiple Light Scattering"): a parallel beam of flux pi F per
// unit area normal to it falls on the top at mu0 = cos(zenith angle). The reflected radiance is
// I(mu) = mu0 F R(mu, mu0) and the diffusely transmitted one mu0 F T(mu, mu0); the plane albedo is
// A(mu0) = 2 int_0^1 R(mu, mu0) mu dmu. With the irradiance E = pi F normal to the beam, the
// radiance per unit irradiance is I / E = mu0 R / pi. By default only the azimuthal mean (Fourier
// term m = 0) is computed: it is all a plane albedo needs, and at nadir (mu = 1) the radiance does not
// depend on azimuth, so it is the whole radiance there. SlabOptions::azimuth_modes asks for the other
// modes too, for the reflection at any azimuth (oblique views).
#pragma once

#include <functional>
#include <vector>

namespace slabcheck {

// A phase function: its value per steradian at the scattering cosine, and its Legendre moments
// chi_l = 2 pi int p(mu) P_l(mu) dmu (chi_0 = 1, chi_1 = the mean cosine), 0..l_max.
struct PhaseFunction {
  std::function<double(double)> value;
  std::function<std::vector<double>(int l_max)> moments;
};

PhaseFunction isotropic_phase();
PhaseFunction henyey_greenstein_phase(double g);
// Draine (2003): HG(g) (1 + alpha mu^2) / (1 + alpha (1 + 2 g^2) / 3).
PhaseFunction draine_phase(double g, double alpha);

// Jendersie & d'Eon (2023), "An Approximate Mie Scattering Function for Fog and Cloud Rendering"
// (SIGGRAPH 2023 talk): (1 - w_D) HG(g_HG) + w_D Draine(g_D, alpha), with the parameters fitted over
// the droplet diameter. Only the branch for 5 <= d <= 50 um is written (clouds; d = 2 r_eff);
// outside it the function throws.
struct MieFit {
  double g_hg, one_minus_g_hg, g_d, alpha, w_d;
};
MieFit approximate_mie_fit(double diameter_um);
PhaseFunction approximate_mie_phase(double diameter_um);

// Legendre moments by quadrature of `value` over the sphere (panels packed geometrically toward the
// forward direction, so peaks down to 1 - mu ~ 1e-9 are resolved): a check of `moments`.
std::vector<double> moments_by_quadrature(const std::function<double(double)>& value, int l_max);

struct SlabProblem {
  double tau = 1.0;    // optical thickness
  double omega = 1.0;  // single-scattering albedo
  PhaseFunction phase;
  // Directions (cosines in (0, 1]) at which R and T are wanted, as outgoing or incident ones: added
  // to the quadrature as nodes of zero weight, so they take no part in the integrals.
  std::vector<double> mu_extra;
};

struct SlabOptions {
  int streams = 32;            // Gauss-Legendre nodes per hemisphere (double Gauss)
  bool delta_m = true;         // Wiscombe (1977): truncate the forward peak at 2 * streams moments
  bool tms = true;             // Nakajima & Tanaka (1988): exact single scattering in R at mu_extra
  double thin_layer = 1.0e-13;  // the doubling starts from single scattering in a layer at most this thick
  // Fourier modes in azimuth solved: 1 = the azimuthal mean alone (all a plane albedo or a nadir
  // radiance needs); 0 or more than 2 * streams = every mode the truncated phase has (2 * streams),
  // for the reflection at any azimuth.
  int azimuth_modes = 1;
};

class SlabSolution {
 public:
  // Reflection and diffuse transmission functions (m = 0) at two of the problem's mu_extra.
  double reflection(double mu, double mu0) const;
  // The reflection function at an azimuth (needs SlabOptions::azimuth_modes other than 1): dphi is the
  // angle between the horizontal parts of the reflected light's direction of travel and the sun's
  // beam's, so dphi = 0 is light that travels on in the sun's azimuth (a camera looking toward the
  // sun) and dphi = pi light sent back toward the sun. I / E = mu0 R / pi as above.
  double reflection(double mu, double mu0, double dphi) const;
  double radiance(double mu, double mu0, double dphi) const { return mu0 * reflection(mu, mu0, dphi) / 3.14159265358979323846; }
  double diffuse_transmission(double mu, double mu0) const;
  // Reflected and transmitted (direct + diffuse) flux over the incident, mu0 one of mu_extra.
  double plane_albedo(double mu0) const;
  double total_transmission(double mu0) const;
  // I / E at nadir, mu0 one of mu_extra and 1 among them too.
  double nadir_radiance(double mu0) const { return mu0 * reflection(1.0, mu0) / 3.14159265358979323846; }
  // The spherical albedo s = 2 int_0^1 A(mu) mu dmu (the plane albedo over the quadrature's nodes):
  // the share of isotropic light the slab reflects, from above or, homogeneous, from below.
  double spherical_albedo() const;
  // I / E at nadir with a Lambertian ground of albedo `ground` under the slab, by the adding of a
  // Lambertian surface (van de Hulst 1980; Liou 2002, section 6.3): the ground takes
  // mu0 T(mu0) / (1 - ground s) of the irradiance (the slab sends part of what the ground
  // reflects back down), and its radiance reaches the top at nadir through T(1), T the total
  // (direct and diffuse) transmission: nadir_radiance(mu0) + (ground / pi) mu0 T(mu0) T(1) / (1 - ground s).
  double nadir_radiance_over_ground(double mu0, double ground) const;

  // What was solved, for the reports.
  double truncated_fraction = 0.0;  // delta-M's f
  double scaled_tau = 0.0;
  int doublings = 0;

 private:
  friend SlabSolution solve_slab(const SlabProblem& p, const SlabOptions& o);
  int index(double mu) const;
  std::vector<double> mu_, weight_;  // nodes, and 2 w mu (0 for the extra nodes)
  std::vector<double> r_, t_;        // n x n, row = outgoing, column = incident
  std::vector<double> r_ss_fix_;     // TMS correction added to R (extra rows and columns only)
  std::vector<double> direct_;       // exp(-tau* / mu) per node
  // Per Fourier mode m: R_m and the truncated phase's reflection kernel (for TMS at an azimuth).
  std::vector<std::vector<double>> r_modes_, p_refl_modes_;
  std::vector<double> p_refl0_;
  double omega_ = 1.0, f_ = 0.0, omega_s_ = 1.0;
  bool tms_ = true;
  std::function<double(double)> phase_value_;
};

SlabSolution solve_slab(const SlabProblem& p, const SlabOptions& o = {});

// Gauss-Legendre nodes and weights on (a, b).
void gauss_legendre(int n, double a, double b, std::vector<double>& x, std::vector<double>& w);

// Delta-Eddington plane albedo of a conservative slab (Joseph, Wiscombe & Weinman 1976), for context.
double delta_eddington_albedo(double tau, double g, double mu0);

}  // namespace slabcheck
