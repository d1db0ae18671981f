// Geodesy on the spherical Earth the renderer draws: latitude/longitude (radians) and altitude
// (metres above radius r_m) to and from Earth-centred Cartesian coordinates, and local frames.
// The ellipsoid (where it matters, e.g. importing projected grids) lives in core/geo (GeographicLib).

CV_FN real3 sphere_to_ecef(real lat_rad, real lon_rad, real alt_m, real r_m) {
  real rr = r_m + alt_m;
  real cl = cos(lat_rad);
  return real3(rr * cl * cos(lon_rad), rr * cl * sin(lon_rad), rr * sin(lat_rad));
}

// Returns (lat_rad, lon_rad, alt_m). Altitude loses float32 digits far from the surface; GPU code
// takes altitudes from the CPU (double) instead of calling this.
CV_FN real3 ecef_to_sphere(real3 p, real r_m) {
  real rho = length(real2(p.x, p.y));
  return real3(atan(p.z, rho), atan(p.y, p.x), length(p) - r_m);
}

// East, north and up unit vectors at (lat, lon).
CV_FN void enu_frame(real lat_rad, real lon_rad, CV_OUT(real3) east, CV_OUT(real3) north, CV_OUT(real3) up) {
  real sl = sin(lat_rad);
  real cl = cos(lat_rad);
  real so = sin(lon_rad);
  real co = cos(lon_rad);
  east = real3(-so, co, real(0));
  north = real3(-sl * co, -sl * so, cl);
  up = real3(cl * co, cl * so, sl);
}

// Geopotential (m^2/s^2) to geometric height above the sphere: z = Phi R / (g0 R - Phi).
CV_FN real geopotential_to_height_m(real phi_m2_per_s2, real r_m) {
  return phi_m2_per_s2 * r_m / (CV_G0_M_PER_S2 * r_m - phi_m2_per_s2);
}
