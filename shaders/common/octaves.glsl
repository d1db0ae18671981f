// Multiple-scattering approximation by octaves (Wrenninge et al. 2013; Hillaire 2016; Ford & Sung
// 2024): sum over i < n of b^i sigma_s p(mu; c^i g) exp(-a^i tau_sun). Octave i stands for light
// that has scattered more often: its extinction toward the sun is scaled by a^i, its contribution
// by b^i and its anisotropy by c^i. Returns the in-scattered radiance per unit sun radiance (1/m/sr).
//
// The gate (docs/physics.md, "Octave gate"): octave i >= 1 is weighted by w^i as well, with
// w = octave_gate_weight(tau_col) from the optical depth of the cloud column the sample is in. Light
// scattered n times scales as tau^n in an optically thin medium, so in thin cirrus the higher
// octaves fade, while deep in thick cloud w -> 1 and the classic sum is unchanged. The sum stops at
// the first octave whose weight b^i w^i is below tol (relative to the first octave's 1): thin cloud
// then pays for fewer octaves. w = 1, tol = 0 is the classic sum.

// Below this (relative to the first octave) an octave's weight b^i w^i ends the gated sum.
const real CV_OCTAVE_GATE_TOL = real(1e-3);

// The gate's weight from the vertical optical depth of the column (liquid + ice), in [0, 1).
CV_FN real octave_gate_weight(real tau_col) { return real(1) - exp(-max(tau_col, real(0))); }

// How many octaves the gated sums evaluate (the first whose weight b^i w^i is below tol ends them):
// what the statistics count, so the output says how many the gate left out.
CV_FN int octave_terms(int n, real b, real w, real tol) {
  int k = 0;
  real bi = real(1);
  for (int i = 0; i < n; ++i) {
    if (bi < tol) break;
    bi *= b * w;
    ++k;
  }
  return k;
}

CV_FN real ms_octaves_hg_gated(real sigma_s_per_m, real mu, real g, real tau_sun, int n, real a, real b, real c, real w,
                               real tol) {
  real sum = real(0);
  real ai = real(1);
  real bi = real(1);
  real ci = real(1);
  real bw = b * w;
  for (int i = 0; i < n; ++i) {
    if (bi < tol) break;
    sum += bi * phase_hg(mu, ci * g) * exp(-ai * tau_sun);
    ai *= a;
    bi *= bw;
    ci *= c;
  }
  return sigma_s_per_m * sum;
}

// The same with the approximate Mie phase: both lobes' asymmetries are scaled by c^i.
CV_FN real ms_octaves_mie_gated(real sigma_s_per_m, real mu, MieParams p, real tau_sun, int n, real a, real b, real c,
                                real w, real tol) {
  real sum = real(0);
  real ai = real(1);
  real bi = real(1);
  real ci = real(1);
  real bw = b * w;
  for (int i = 0; i < n; ++i) {
    if (bi < tol) break;
    sum += bi * phase_mie(mu, mie_scale_g(p, ci)) * exp(-ai * tau_sun);
    ai *= a;
    bi *= bw;
    ci *= c;
  }
  return sigma_s_per_m * sum;
}

// The classic sums, without the gate.
CV_FN real ms_octaves_hg(real sigma_s_per_m, real mu, real g, real tau_sun, int n, real a, real b, real c) {
  return ms_octaves_hg_gated(sigma_s_per_m, mu, g, tau_sun, n, a, b, c, real(1), real(0));
}
CV_FN real ms_octaves_mie(real sigma_s_per_m, real mu, MieParams p, real tau_sun, int n, real a, real b, real c) {
  return ms_octaves_mie_gated(sigma_s_per_m, mu, p, tau_sun, n, a, b, c, real(1), real(0));
}
