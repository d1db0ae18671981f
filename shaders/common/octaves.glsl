// Multiple-scattering approximation by octaves (Wrenninge et al. 2013; Hillaire 2016; Ford & Sung
// 2024): sum over i < n of b^i sigma_s p(mu; c^i g) exp(-a^i tau_sun). Octave i stands for light
// that has scattered more often: its extinction toward the sun is scaled by a^i, its contribution
// by b^i and its anisotropy by c^i. Returns the in-scattered radiance per unit sun radiance (1/m/sr).

CV_FN real ms_octaves_hg(real sigma_s_per_m, real mu, real g, real tau_sun, int n, real a, real b, real c) {
  real sum = real(0);
  real ai = real(1);
  real bi = real(1);
  real ci = real(1);
  for (int i = 0; i < n; ++i) {
    sum += bi * phase_hg(mu, ci * g) * exp(-ai * tau_sun);
    ai *= a;
    bi *= b;
    ci *= c;
  }
  return sigma_s_per_m * sum;
}

// The same with the approximate Mie phase: both lobes' asymmetries are scaled by c^i.
CV_FN real ms_octaves_mie(real sigma_s_per_m, real mu, MieParams p, real tau_sun, int n, real a, real b, real c) {
  real sum = real(0);
  real ai = real(1);
  real bi = real(1);
  real ci = real(1);
  for (int i = 0; i < n; ++i) {
    sum += bi * phase_mie(mu, mie_scale_g(p, ci)) * exp(-ai * tau_sun);
    ai *= a;
    bi *= b;
    ci *= c;
  }
  return sigma_s_per_m * sum;
}
