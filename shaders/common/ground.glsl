// The ground of the globe: where a point falls in an equirectangular albedo image (the Natural
// Earth relief, longitude -180..180 left to right, latitude 90..-90 top to bottom), and the
// radiance a Lambertian ground reflects. The GPU and the CPU reference both use these.

// Bilinear lookup of texel centres for (lat, lon) in radians on a w x h image: returns
// (x0, y0, wx, wy); the other corner is x1 = (x0 + 1) mod w (longitude wraps) and
// y1 = min(y0 + 1, h - 1) (latitude clamps at the poles' rows).
CV_FN real4 equirect_texel(real lat_rad, real lon_rad, int w, int h) {
  real x = (lon_rad + CV_PI) / CV_TWO_PI * real(w) - real(0.5);
  real y = (real(0.5) * CV_PI - lat_rad) / CV_PI * real(h) - real(0.5);
  x = mod(x, real(w));  // in [0, w): the texel left of x and the one after wrap
  real x0 = min(floor(x), real(w - 1));
  y = clamp(y, real(0), real(h - 1));
  real y0 = min(floor(y), real(max(0, h - 2)));
  return real4(x0, y0, x - x0, min(y - y0, real(1)));
}

// Radiance (per unit sun irradiance) reflected by a Lambertian ground of albedo `albedo`, lit by
// the sun at cosine mu_s through transmittance t_sun (air and cloud) and by sky irradiance e_sky.
CV_FN real3 ground_radiance(real3 albedo, real mu_s, real3 t_sun, real3 e_sky) {
  return albedo / CV_PI * (t_sun * max(mu_s, real(0)) + e_sky);
}

// The share of an isotropic sky's irradiance that a conservative cloud column of vertical optical
// depth tau (its mean cosine g) passes to the ground, direct and diffuse: the spherical
// transmittance, in the two-stream's form 1 / (1 + gamma1 (1 - f) tau) with Eddington's
// coefficient gamma1 (1 - f) = (3 / 4)(1 - g). Against the adding-doubling solver's 1 - s (s the
// spherical albedo) for Henyey-Greenstein 0.75 and 0.85 and droplets of 10 and 20 um at optical
// depths 0.5-100 it is within +0.4..+4.6 %; the quadrature's sqrt(3) / 2 in place of 3 / 4 was
// -12.5..+2.2 % (`SlabCheckSky.TheSkysLightThroughACloudIsTheSlabsSphericalTransmittance`).
// In terms of x = (1 - g) tau, summed over a column's layers and phases (a conservative two-stream
// layer's 1 / t - 1 is proportional to it, so layers of different g add their x):
// 1 / (1 + (3 / 4) x).
CV_FN real sky_share_of_depth(real x) { return real(1.0) / (real(1.0) + real(0.75) * max(x, real(0.0))); }
CV_FN real sky_through_cloud(real tau, real g) { return sky_share_of_depth((real(1.0) - g) * max(tau, real(0.0))); }

// The share of an isotropic sky's irradiance at a conservative cloud column's top that reaches a
// ground of diffuse albedo `a` under it: the spherical transmittance t = sky_through_cloud(tau, g),
// and the light the ground sends back up, of which the cloud returns its spherical albedo from below
// (1 - t for any conservative layer, as t is the same from either side), again and again:
// t / (1 - a (1 - t)), the adding of a Lambertian surface. Under droplets (10 um) of optical depth 20
// that is 2.2 times the black ground's t over snow (0.8), 1.05 times over the sea (0.07). Against
// the solver's spherical albedo it is within +0.2..+4.4 %
// (`SlabCheckSky.TheSkysLightOnTheGroundUnderACloudIncludesWhatTheCloudReturns`).
CV_FN real3 sky_to_ground_of_depth(real x, real3 a) {
  real t = sky_share_of_depth(x);
  real s = real(1.0) - t;
  return real3(t) / (real3(1.0) - clamp(a, real3(0.0), real3(0.99)) * s);
}
CV_FN real3 sky_through_cloud_to_ground(real tau, real g, real3 a) {
  return sky_to_ground_of_depth((real(1.0) - g) * max(tau, real(0.0)), a);
}

// ---- Water: Fresnel reflection, the Cox-Munk sun glint and the light from the water body ----
// (docs/physics.md, "Ground albedo"). Cosines are with the local vertical; nu_sv is the cosine
// between the directions to the sun and to the viewer (both away from the surface).

// Refractive index of water in the visible (Hale & Querry 1973: 1.331 at 650 nm to 1.337 at 450 nm).
const real CV_WATER_N = real(1.333);
// Albedo of a flat water surface under isotropic light, the integral of fresnel_water(mu) 2 mu dmu
// over the hemisphere: 0.066 for n = 1.333 (a test integrates it).
const real CV_WATER_DIFFUSE_FRESNEL = real(0.0664);
// Reflectance of the water body (red, green, blue: 0.67, 0.55, 0.47 um), above the surface at nadir
// under an overhead sun: pi x the remote-sensing reflectance of clear open ocean (Case 1 water,
// chlorophyll ~0.1-0.3 mg/m3: Rrs ~0.0003, 0.002, 0.006 /sr; Morel & Maritorena 2001).
const real3 CV_WATER_BODY = real3(real(0.001), real(0.006), real(0.020));

// Fresnel reflectance of unpolarised light at the air-water interface, exact, for the cosine of the
// angle of incidence (clamped to 0..1): 0.0204 at normal incidence, 1 at grazing.
CV_FN real fresnel_water(real cos_i) {
  real c = clamp(cos_i, real(0.0), real(1.0));
  real n = CV_WATER_N;
  real ct = sqrt(max(real(1.0) - (real(1.0) - c * c) / (n * n), real(0.0)));  // > 0.66 for n = 1.333
  real rs = (c - n * ct) / (c + n * ct);
  real rp = (n * c - ct) / (n * c + ct);
  return real(0.5) * (rs * rs + rp * rp);
}

// Mean square slope of the sea surface for a wind speed (m/s, ~12.5 m up): Cox & Munk (1954), the
// clean-surface fit sigma^2 = 0.003 + 5.12e-3 U, measured for 1-14 m/s.
CV_FN real cox_munk_mss(real wind_m_s) { return real(0.003) + real(5.12e-3) * max(wind_m_s, real(0.0)); }

// Smith's Lambda for an isotropic Gaussian (Beckmann) slope distribution of mean square slope mss,
// seen at cosine mu: (exp(-a^2) / (a sqrt(pi)) - erfc(a)) / 2 with a = mu / (sqrt(mss) sin):
// G1 = 1 / (1 + Lambda) is the fraction of the surface seen (Walter et al. 2007, eq. 27). erfc from
// Abramowitz & Stegun 7.1.26 (absolute error 1.5e-7, so Lambda is off by < 1e-7).
CV_FN real smith_lambda_gauss(real mu, real mss) {
  real m = clamp(mu, real(1e-6), real(1.0));
  real a = m / sqrt(mss * max(real(1.0) - m * m, real(1e-12)));
  if (a > real(6.0)) return real(0.0);  // exp(-36): nothing is hidden
  real t = real(1.0) / (real(1.0) + real(0.3275911) * a);
  real erfc_scaled = t * (real(0.254829592) + t * (real(-0.284496736) + t * (real(1.421413741) +
                     t * (real(-1.453152027) + t * real(1.061405429)))));  // erfc(a) exp(a^2)
  return max(real(0.5) * exp(-a * a) * (real(1.0) / (a * real(1.7724538509055160)) - erfc_scaled), real(0.0));
}

// The sun glint of a wind-roughened sea (1/sr): the Cox-Munk slope distribution as a microfacet BRDF,
// F(cos to the facet) D(h) G / (4 mu_s mu_v), with D the isotropic Gaussian of mean square slope
// mss over the half vector h (exp(-tan^2 / mss) / (pi mss cos^4)) and G Smith's height-correlated
// shadowing and masking, 1 / (1 + Lambda(mu_s) + Lambda(mu_v)). With G, its integral f mu_v over the
// hemisphere is at most the largest Fresnel factor (< 1): no energy gain at grazing sun or view,
// where the plain Cox-Munk form diverges. 0 with the sun or the viewer below the horizon.
CV_FN real sea_glint_brdf(real mu_s, real mu_v, real nu_sv, real mss) {
  if (!(mu_s > real(0.0)) || !(mu_v > real(0.0))) return real(0.0);
  real ms = max(mu_s, real(1e-4));
  real mv = max(mu_v, real(1e-4));
  real hh = max(real(2.0) + real(2.0) * clamp(nu_sv, real(-1.0), real(1.0)), real(1e-12));  // |s + v|^2
  real mu_h = min((mu_s + mu_v) / sqrt(hh), real(1.0));         // cosine of the facet normal h
  real tan2 = (real(1.0) - mu_h * mu_h) / (mu_h * mu_h);
  if (tan2 > real(80.0) * mss) return real(0.0);  // exp(-80): no facet points that way
  real d = exp(-tan2 / mss) / (CV_PI * mss * mu_h * mu_h * mu_h * mu_h);
  real g = real(1.0) / (real(1.0) + smith_lambda_gauss(ms, mss) + smith_lambda_gauss(mv, mss));
  real cos_i = sqrt(real(0.25) * hh);  // s.h = |s + v| / 2
  return fresnel_water(cos_i) * d * g / (real(4.0) * ms * mv);
}

// Radiance (per unit sun irradiance) leaving water toward the viewer: the sun's glint, the sky
// mirrored by the surface (an isotropic sky of radiance e_sky / pi, reflected by fresnel(mu_v)), and
// the light scattered back out of the water body (body: its reflectance per channel, above the
// surface at nadir under an overhead sun), let in and out through the surface. Arguments as
// ground_radiance, plus the view and sun-view cosines and the mean square slope.
CV_FN real3 water_radiance(real3 body, real mu_s, real mu_v, real nu_sv, real mss, real3 t_sun, real3 e_sky) {
  real f0 = fresnel_water(real(1.0));
  real glint = max(mu_s, real(0.0)) * sea_glint_brdf(mu_s, mu_v, nu_sv, mss);
  real out_v = (real(1.0) - fresnel_water(mu_v)) / (real(1.0) - f0);
  real in_s = max(mu_s, real(0.0)) * (real(1.0) - fresnel_water(mu_s)) / (real(1.0) - f0);
  real in_sky = (real(1.0) - CV_WATER_DIFFUSE_FRESNEL) / (real(1.0) - f0);
  return t_sun * glint + fresnel_water(mu_v) * e_sky / CV_PI +
         body / CV_PI * out_v * (t_sun * in_s + e_sky * in_sky);
}

// The water's BRDF (1/sr, per channel) between the direction the light comes from (cosine mu_i with
// the vertical) and the direction to the viewer (mu_o), nu the cosine between those two: the sun
// glint and the light of the water body let in and out through the surface. water_radiance's sun
// terms are t_sun mu_s water_brdf(body, mu_s, mu_v, nu_sv, mss); it is symmetric in mu_i and mu_o.
// The path tracer (shaders/kernel/path.glsl) weights a bounce off water by it.
CV_FN real3 water_brdf(real3 body, real mu_i, real mu_o, real nu, real mss) {
  if (!(mu_i > real(0.0)) || !(mu_o > real(0.0))) return real3(0.0);
  real f0 = fresnel_water(real(1.0));
  real in_f = (real(1.0) - fresnel_water(mu_i)) / (real(1.0) - f0);
  real out_f = (real(1.0) - fresnel_water(mu_o)) / (real(1.0) - f0);
  return real3(sea_glint_brdf(mu_i, mu_o, nu, mss)) + body / CV_PI * (in_f * out_f);
}

// The diffuse albedo of a ground point whose water fraction is `water` (0..1): Lambertian land of
// albedo `land`, and water's reflection of isotropic light (CV_WATER_DIFFUSE_FRESNEL) plus its body.
// The light a cloud above receives back from the ground under isotropic light from above; the
// two-stream column's ground (core::column_ground_albedo) is its mean over the three channels.
CV_FN real3 ground_diffuse_albedo(real3 land, real water) {
  real w = clamp(water, real(0.0), real(1.0));
  return (real(1.0) - w) * land + w * (real3(CV_WATER_DIFFUSE_FRESNEL) + CV_WATER_BODY);
}

// Radiance of a ground point whose water fraction is `water` (0..1): Lambertian land of albedo
// `land`, the rest water_radiance with the body reflectance `body`. No water: ground_radiance exactly.
CV_FN real3 ground_radiance_water(real3 land, real water, real3 body, real mu_s, real mu_v, real nu_sv, real mss, real3 t_sun,
                                  real3 e_sky) {
  real3 l = ground_radiance(land, mu_s, t_sun, e_sky);
  if (!(water > real(0.0))) return l;
  real w = min(water, real(1.0));
  return (real(1.0) - w) * l + w * water_radiance(body, mu_s, mu_v, nu_sv, mss, t_sun, e_sky);
}
