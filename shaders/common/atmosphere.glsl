// The Earth's clear-sky atmosphere: Rayleigh and Mie scattering, ozone absorption, transmittance
// toward space and single-scattered sky radiance along a ray, all from camera-relative quantities
// (reference radius, altitude, cosine with the local up) so float32 keeps its digits.
//
// Figures: Bruneton (2017), "Precomputed Atmospheric Scattering: a New Implementation" (demo
// constants), and Hillaire (2020), "A Scalable and Production Ready Sky and Atmosphere Rendering
// Technique", table 1: Rayleigh scattering (5.802, 13.558, 33.1)e-6 /m at sea level with scale
// height 8 km; Mie scattering 3.996e-6 /m, extinction 4.40e-6 /m, scale height 1.2 km, g = 0.8
// (Cornette-Shanks); ozone absorption (0.650, 1.881, 0.085)e-6 /m at the peak of a tent profile
// that rises from 10 km to 1 at 25 km and falls to 0 at 40 km. The top of the atmosphere is
// Bruneton's 60 km (Rayleigh density there is exp(-7.5) = 5.5e-4 of sea level).

const real CV_ATMO_TOP_M = real(60000.0);
const real CV_RAYLEIGH_SCALE_HEIGHT_M = real(8000.0);
const real CV_MIE_SCALE_HEIGHT_M = real(1200.0);
const real CV_MIE_SCATTERING_PER_M = real(3.996e-6);
const real CV_MIE_EXTINCTION_PER_M = real(4.40e-6);
const real CV_MIE_G = real(0.8);
const real CV_OZONE_PEAK_M = real(25000.0);
const real CV_OZONE_HALF_WIDTH_M = real(15000.0);

CV_FN real3 rayleigh_scattering_per_m() { return real3(real(5.802e-6), real(13.558e-6), real(33.1e-6)); }
CV_FN real3 ozone_absorption_per_m() { return real3(real(0.650e-6), real(1.881e-6), real(0.085e-6)); }

// Densities relative to their reference (sea level, or the ozone peak): (Rayleigh, Mie, ozone).
// Below the ground (float round-off of a ground point) the sea-level value holds.
CV_FN real3 atmo_density(real alt_m) {
  real h = max(alt_m, real(0));
  real ozone = max(real(0), real(1) - abs(h - CV_OZONE_PEAK_M) / CV_OZONE_HALF_WIDTH_M);
  return real3(exp(-h / CV_RAYLEIGH_SCALE_HEIGHT_M), exp(-h / CV_MIE_SCALE_HEIGHT_M), ozone);
}

// Extinction (1/m, per RGB channel) of air with densities dens.
CV_FN real3 atmo_extinction_per_m(real3 dens) {
  return rayleigh_scattering_per_m() * dens.x + real3(CV_MIE_EXTINCTION_PER_M * dens.y) + ozone_absorption_per_m() * dens.z;
}

// The middle and length of step i of n over [a, b], the steps packed toward the end where the ray
// is lowest (the air densest): toward a when toward_a, else toward b. Cubic packing (t ~ u^3) puts
// about five of 16 steps in the lowest 2 km of a vertical ray (the Mie layer) and still spans the
// 1000 km of a horizontal one; quadratic packing left the Mie layer three.
CV_FN void atmo_step(real a, real b, int i, int n, bool toward_a, CV_OUT(real) t, CV_OUT(real) dt) {
  real len = b - a;
  real u = toward_a ? (real(i) + real(0.5)) / real(n) : (real(n - i) - real(0.5)) / real(n);
  real off = len * u * u * u;
  t = toward_a ? a + off : b - off;
  // The midpoint rule in u with the weight dt/du = 3 len u^2, scaled so the steps add up to the
  // whole length (the plain weights fall short by 1 / (4 n^2): a quarter for a single step).
  dt = real(3) * len * u * u / (real(n) - real(0.25) / real(n));
}

// Where a ray's altitude is lowest within [t0, t1]: r(t)^2 is least at t = -r mu.
CV_FN real atmo_lowest_t(real r0_m, real h_m, real mu, real t0, real t1) {
  return clamp(-(r0_m + h_m) * mu, t0, t1);
}

// How many of n steps go to the part [t0, tl] of [t0, t1] (the rest to [tl, t1]): in proportion to
// length, at least one for each part that is not empty.
CV_FN int atmo_first_steps(real t0, real tl, real t1, int n) {
  if (!(tl > t0)) return 0;
  if (!(t1 > tl)) return n;
  int k = int(real(n) * (tl - t0) / (t1 - t0) + real(0.5));
  return clamp(k, 1, max(1, n - 1));
}

// Optical depth (RGB) along the ray from t0_m to t1_m (midpoint rule, steps packed toward the
// lowest point of the ray, where nearly all of the air's mass lies for an exponential profile).
CV_FN real3 atmo_optical_depth(real r0_m, real h_m, real mu, real t0_m, real t1_m, int steps) {
  real3 tau = real3(real(0));
  if (!(t1_m > t0_m)) return tau;
  real tl = atmo_lowest_t(r0_m, h_m, mu, t0_m, t1_m);
  int n1 = atmo_first_steps(t0_m, tl, t1_m, steps);
  int n2 = steps - n1;
  for (int i = 0; i < n1; ++i) {
    real t;
    real dt;
    atmo_step(t0_m, tl, i, n1, false, t, dt);
    tau += atmo_extinction_per_m(atmo_density(ray_altitude(r0_m, h_m, mu, t))) * dt;
  }
  for (int i = 0; i < n2; ++i) {
    real t;
    real dt;
    atmo_step(tl, t1_m, i, n2, true, t, dt);
    tau += atmo_extinction_per_m(atmo_density(ray_altitude(r0_m, h_m, mu, t))) * dt;
  }
  return tau;
}

// Transmittance (RGB) of the atmosphere from a point at altitude h_m toward a direction with cosine
// mu (and sine nu, see ray_sphere_rel_nu) to the local up, out to space; 0 when the ray meets the
// ground. A point above the atmosphere gets 1 unless its ray enters the air.
CV_FN real3 atmo_transmittance(real r0_m, real h_m, real mu, real nu, int steps) {
  real g0;
  real g1;
  if (ray_sphere_rel_nu(r0_m, h_m, mu, nu, real(0), g0, g1) && g1 > real(0)) return real3(real(0));
  real a0;
  real a1;
  if (!ray_sphere_rel_nu(r0_m, h_m, mu, nu, CV_ATMO_TOP_M, a0, a1) || a1 <= real(0)) return real3(real(1));
  return exp(-atmo_optical_depth(r0_m, h_m, mu, max(a0, real(0)), a1, steps));
}

// One step of the sky integral: in-scattered radiance added over [t - dt/2, t + dt/2] behind the
// view optical depth tau (updated), per unit sun irradiance. See atmo_inscatter.
CV_FN real3 atmo_inscatter_step(real r0_m, real h_m, real mu, real mu_s, real nu_vs, real t, real dt, real p_r, real p_m,
                                int sun_steps, CV_INOUT(real3) tau) {
  real alt = ray_altitude(r0_m, h_m, mu, t);
  real3 dens = atmo_density(alt);
  real3 sigma_t = atmo_extinction_per_m(dens);
  // The sun's cosine with the local up at the sample: (r up + t d) . to_sun / r(t).
  real mu_st = clamp(((r0_m + h_m) * mu_s + t * nu_vs) / (r0_m + alt), real(-1), real(1));
  real nu_st = sqrt(max(real(0), real(1) - mu_st * mu_st));
  real3 t_sun = atmo_transmittance(r0_m, alt, mu_st, nu_st, sun_steps);
  real3 s = t_sun * (rayleigh_scattering_per_m() * (dens.x * p_r) + real3(CV_MIE_SCATTERING_PER_M * dens.y * p_m));
  real3 l = exp(-tau) * real3(segment_integral(s.x, sigma_t.x, dt), segment_integral(s.y, sigma_t.y, dt),
                              segment_integral(s.z, sigma_t.z, dt));
  tau += sigma_t * dt;
  return l;
}

// Single-scattered sky radiance along the view ray from t0_m to t1_m (camera-relative: the ray
// starts at altitude h_m, mu = cosine of the ray with the local up there, mu_s = cosine of the
// sun's direction with that up, nu_vs = cosine between the ray and the sun's direction), per unit
// sun irradiance. Each step adds (sigma_R P_R + sigma_M P_CS) T_sun over the step with the
// energy-conserving segment integral per channel. Returns the in-scattered radiance; trans gets
// the view transmittance over the segment. Two loops, one per side of the ray's lowest point. (A
// form with one loop choosing the side per step was once taken for an llvmpipe miscompile. Run on
// llvmpipe with its arguments read from a buffer, it is within 1.1e-6 of the C++ float build for
// 10 to 20 steps. The horizon error came from llvmpipe's loop budget: see raymarch.comp.)
CV_FN real3 atmo_inscatter(real r0_m, real h_m, real mu, real mu_s, real nu_vs, real t0_m, real t1_m, int steps,
                           int sun_steps, CV_OUT(real3) trans) {
  real3 radiance = real3(real(0));
  trans = real3(real(1));
  if (!(t1_m > t0_m)) return radiance;
  // Sunlight propagates along -to_sun and leaves along -d: the scattering cosine is d . to_sun.
  real p_r = phase_rayleigh(nu_vs);
  real p_m = phase_cornette_shanks(nu_vs, CV_MIE_G);
  real tl = atmo_lowest_t(r0_m, h_m, mu, t0_m, t1_m);
  int n1 = atmo_first_steps(t0_m, tl, t1_m, steps);
  int n2 = steps - n1;
  real3 tau = real3(real(0));
  for (int i = 0; i < n1; ++i) {
    real t;
    real dt;
    atmo_step(t0_m, tl, i, n1, false, t, dt);
    radiance += atmo_inscatter_step(r0_m, h_m, mu, mu_s, nu_vs, t, dt, p_r, p_m, sun_steps, tau);
  }
  for (int i = 0; i < n2; ++i) {
    real t;
    real dt;
    atmo_step(tl, t1_m, i, n2, true, t, dt);
    radiance += atmo_inscatter_step(r0_m, h_m, mu, mu_s, nu_vs, t, dt, p_r, p_m, sun_steps, tau);
  }
  trans = exp(-tau);
  return radiance;
}

// Isotropic sky irradiance (per unit sun irradiance, on a horizontal surface) at a point whose sun
// transmittance is t_sun and whose sun cosine is mu_s: of the sunlight the air above has taken out
// of the direct beam on its way down, half is taken to arrive as diffuse light from the sky
// (single scattering, Rayleigh symmetric; ozone absorption is counted with it, a few per cent at
// most). 0 at night, where t_sun is 0 and mu_s <= 0. See docs/physics.md.
CV_FN real3 sky_irradiance(real3 t_sun, real mu_s) {
  return real(0.5) * max(mu_s, real(0)) * (real3(real(1)) - t_sun);
}
