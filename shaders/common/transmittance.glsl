// Transmittance and the energy-conserving segment integral (Hillaire 2016).

CV_FN real transmittance(real optical_depth) { return exp(-optical_depth); }

// E(x) = (1 - exp(-x)) / x for x = sigma_t dt >= 0. The naive quotient is 0/0 at x = 0 and loses
// every digit below x ~ 1e-7 in float32, so below 0.1 we use its Taylor series (the first omitted
// term, x^6/5040, is below 3e-10 there); above, 1 - exp(-x) has lost at most one decimal digit.
CV_FN real segment_factor(real x) {
  if (x < real(0.1)) {
    return real(1) - x * (real(0.5) - x * (real(1.0 / 6.0) - x * (real(1.0 / 24.0) -
           x * (real(1.0 / 120.0) - x * real(1.0 / 720.0)))));
  }
  return (real(1) - exp(-x)) / x;
}

// Radiance added over a step of length dt_m with constant extinction sigma_t_per_m and constant
// in-scattered radiance s: integral_0^dt s exp(-sigma_t t) dt = s dt E(sigma_t dt). For
// sigma_t dt >> 1 it tends to s / sigma_t: only the first 1/sigma_t of the step contributes.
CV_FN real segment_integral(real s, real sigma_t_per_m, real dt_m) {
  return s * dt_m * segment_factor(sigma_t_per_m * dt_m);
}

CV_FN real3 segment_integral(real3 s, real sigma_t_per_m, real dt_m) {
  return s * (dt_m * segment_factor(sigma_t_per_m * dt_m));
}
