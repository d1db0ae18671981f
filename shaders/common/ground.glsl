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
