// Geodesy on the spherical Earth the renderer draws: latitude/longitude (radians) and altitude
// (metres above radius r_m) to and from Earth-centred Cartesian coordinates, and local frames.
// The ellipsoid (where it matters, e.g. importing projected grids) lives in core/geo (GeographicLib).

CV_FN real3 sphere_to_ecef(real lat_rad, real lon_rad, real alt_m, real r_m) {
  real rr = r_m + alt_m;
  real cl = cos(lat_rad);
  return real3(rr * cl * cos(lon_rad), rr * cl * sin(lon_rad), rr * sin(lat_rad));
}

// atan(y, x) in (-pi, pi], to about an ulp of the result. GPU atan need not be that close: Mesa's
// llvmpipe is off by up to 1.4e-6 rad, which put cloud samples 9 m from where the CPU puts them and
// made whole pixels differ by 0.4 % in transmittance. The ratio is reduced to |u| <= tan(pi/32)
// around the nearest multiple of pi/16 (atan t = c + atan((t - tan c) / (1 + t tan c))), where
// eight terms of the Taylor series leave less than 1e-18. The quadrant and the reduction add up to
// m pi/16 for an integer m, added last as m * hi + (m * lo + series) with hi short enough that
// m * hi is exact: one rounding at the end instead of one per constant.
CV_FN real atan2_accurate(real y, real x) {
  real ax = abs(x);
  real ay = abs(y);
  bool swap = ay > ax;
  real num = swap ? ax : ay;
  real den = swap ? ay : ax;
  real t = den > real(0) ? num / den : real(0);  // in [0, 1]
  int k = 0;  // the reduction's angle, k pi/16
  real tc = real(0);
  if (t > real(0.8206787908286602)) {
    k = 4;
    tc = real(1);
  } else if (t > real(0.5345111359507916)) {
    k = 3;
    tc = real(0.66817863791929891999);
  } else if (t > real(0.3033466836073424)) {
    k = 2;
    tc = real(0.41421356237309504880);
  } else if (t > real(0.09849140335716425)) {
    k = 1;
    tc = real(0.19891236737965800691);
  }
  real u = (t - tc) / (real(1) + t * tc);
  real u2 = u * u;
  real series = u * (real(1) + u2 * (real(-1.0 / 3.0) + u2 * (real(0.2) + u2 * (real(-1.0 / 7.0) +
                u2 * (real(1.0 / 9.0) + u2 * (real(-1.0 / 11.0) + u2 * (real(1.0 / 13.0) + u2 * real(-1.0 / 15.0))))))));
  // atan(|y|/|x|) in the first quadrant is k pi/16 + series; swapping reflects it about pi/4
  // (8 pi/16), a negative x about pi/2.
  int m = k;
  if (swap) {
    m = 8 - m;
    series = -series;
  }
  if (x < real(0)) {
    m = 16 - m;
    series = -series;
  }
  real a = real(m) * real(0.19635009765625) + (real(m) * real(-5.5680688792259608478854503e-7) + series);
  return y < real(0) ? -a : a;
}

// Returns (lat_rad, lon_rad, alt_m). Altitude loses float32 digits far from the surface; GPU code
// takes altitudes from the CPU (double) instead of calling this.
CV_FN real3 ecef_to_sphere(real3 p, real r_m) {
  real rho = length(real2(p.x, p.y));
  return real3(atan2_accurate(p.z, rho), atan2_accurate(p.y, p.x), length(p) - r_m);
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
