// Phase functions, each normalised to 1 over the sphere (units 1/sr). mu is the cosine of the
// angle between the propagation directions before and after scattering: mu = 1 is forward.

CV_FN real phase_isotropic() { return CV_INV_4PI; }

// 1 + g^2 - 2 g mu, written as c^2 + 2 |g| (1 - sign(g) mu) with c = 1 - |g|, so it keeps its
// relative accuracy in the forward peak (|g| and sign(g) mu both near 1), where the plain form cancels.
CV_FN real hg_denominator(real mu, real g, real c) {
  real m = g < real(0) ? -mu : mu;
  return c * c + real(2) * abs(g) * (real(1) - m);
}

// Henyey-Greenstein with the complement c = 1 - |g| supplied by a caller that knows it to more
// digits than 1 - |g| would give (the peak scales as 1/c^2, so a float g near 1 alone loses them).
CV_FN real phase_hg_c(real mu, real g, real c) {
  real d = hg_denominator(mu, g, c);
  return CV_INV_4PI * c * (real(2) - c) / (d * sqrt(d));
}

// Henyey-Greenstein; mean cosine g.
CV_FN real phase_hg(real mu, real g) { return phase_hg_c(mu, g, real(1) - abs(g)); }

// Cornette-Shanks (1992); mean cosine 3 g (4 + g^2) / (5 (2 + g^2)).
CV_FN real phase_cornette_shanks(real mu, real g) {
  real c = real(1) - abs(g);
  real d = hg_denominator(mu, g, c);
  return real(3) / (real(8) * CV_PI) * c * (real(2) - c) * (real(1) + mu * mu) /
         ((real(2) + g * g) * d * sqrt(d));
}

// Schlick's rational approximation of HG with parameter k in (-1, 1).
CV_FN real phase_schlick(real mu, real k) {
  real d = real(1) - k * mu;
  return CV_INV_4PI * (real(1) - k * k) / (d * d);
}

// The usual mapping from an HG asymmetry g to Schlick's k (k ~ 1.55 g - 0.55 g^3). It passes 1 for
// g above ~0.92, where Schlick's function would turn negative, so k is held inside (-1, 1).
CV_FN real schlick_k_from_g(real g) {
  return clamp(real(1.55) * g - real(0.55) * g * g * g, real(-0.999), real(0.999));
}

// Rayleigh scattering (unpolarised); mean cosine 0.
CV_FN real phase_rayleigh(real mu) { return real(3) / (real(16) * CV_PI) * (real(1) + mu * mu); }

// Draine (2003): HG(g) (1 + alpha mu^2) / (1 + alpha (1 + 2 g^2) / 3), alpha >= 0.
CV_FN real phase_draine(real mu, real g, real alpha) {
  return phase_hg(mu, g) * (real(1) + alpha * mu * mu) /
         (real(1) + alpha * (real(1) + real(2) * g * g) / real(3));
}

// Mean cosine of the Draine phase function.
CV_FN real draine_mean_cosine(real g, real alpha) {
  return g * (real(1) + alpha * (real(3) + real(2) * g * g) / real(5)) /
         (real(1) + alpha * (real(1) + real(2) * g * g) / real(3));
}

// Two Henyey-Greenstein lobes: w HG(g1) + (1 - w) HG(g2); mean cosine w g1 + (1 - w) g2.
CV_FN real phase_dual_hg(real mu, real g1, real g2, real w) {
  return w * phase_hg(mu, g1) + (real(1) - w) * phase_hg(mu, g2);
}
