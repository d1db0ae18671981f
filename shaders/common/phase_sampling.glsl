// Importance sampling of the phase functions: each returns a direction distributed exactly as the
// phase function around the incoming propagation direction wi, and its pdf (1/sr), equal to eval.

// Inverse CDF of HG in mu. The textbook form (1 + g^2 - t^2) / (2 g) cancels for small |g|; with
// v = 1 - 2u it rearranges (docs/physics.md) to a quotient with no cancellation for any g:
// mu = ((v + g)(1 + g v) + g (1 - g^2) 2 u (1 - u)) / (1 + g v)^2.  u = 0 gives mu = 1.
CV_FN real hg_sample_mu(real g, real u) {
  real v = real(1) - real(2) * u;
  real gv = real(1) + g * v;
  real mu = ((v + g) * gv + real(2) * g * (real(1) - g * g) * u * (real(1) - u)) / (gv * gv);
  return clamp(mu, real(-1), real(1));
}

CV_FN real3 sample_hg(real3 wi, real g, real2 u, CV_OUT(real) pdf) {
  real mu = hg_sample_mu(g, u.x);
  pdf = phase_hg(mu, g);
  return direction_around(wi, mu, CV_TWO_PI * u.y);
}

// mu distributed as Draine(g, alpha): rejection from HG(g) with acceptance (1 + alpha mu^2) /
// (1 + alpha). The acceptance rate is at least 1/3 for every g and alpha >= 0, so 64 tries fail
// with probability below (2/3)^64 ~ 5e-12 (then the last HG draw is kept).
CV_FN real draine_sample_mu(real g, real alpha, CV_INOUT(uint) rng) {
  real mu = real(1);
  for (int i = 0; i < 64; ++i) {
    mu = hg_sample_mu(g, rng_next(rng));
    if (rng_next(rng) * (real(1) + alpha) <= real(1) + alpha * mu * mu) break;
  }
  return mu;
}

CV_FN real3 sample_draine(real3 wi, real g, real alpha, CV_INOUT(uint) rng, CV_OUT(real) pdf) {
  real mu = draine_sample_mu(g, alpha, rng);
  pdf = phase_draine(mu, g, alpha);
  return direction_around(wi, mu, CV_TWO_PI * rng_next(rng));
}

// The Mie blend: pick a lobe with its weight, sample it; the pdf is the whole blend.
CV_FN real3 sample_mie(real3 wi, MieParams p, CV_INOUT(uint) rng, CV_OUT(real) pdf) {
  real mu = rng_next(rng) < p.w_d ? draine_sample_mu(p.g_d, p.alpha, rng) : hg_sample_mu(p.g_hg, rng_next(rng));
  pdf = phase_mie(mu, p);
  return direction_around(wi, mu, CV_TWO_PI * rng_next(rng));
}

CV_FN real3 sample_dual_hg(real3 wi, real g1, real g2, real w, CV_INOUT(uint) rng, CV_OUT(real) pdf) {
  real g = rng_next(rng) < w ? g1 : g2;
  real mu = hg_sample_mu(g, rng_next(rng));
  pdf = phase_dual_hg(mu, g1, g2, w);
  return direction_around(wi, mu, CV_TWO_PI * rng_next(rng));
}
