// Ray/sphere and ray/spherical-shell intersection on a spherical Earth, free of cancellation.
// Distances in metres. A miss returns false and leaves t0 > t1.

// Both roots of t^2 + 2 b t + c = 0 given sqrt of its discriminant: the far one as
// q = -(b + sign(b) sqrt(disc)) and the near one as c / q, never a difference of near-equal terms.
CV_FN void sphere_roots(real b, real c, real sqrt_disc, CV_OUT(real) t0, CV_OUT(real) t1) {
  real q = -(b + (b >= real(0) ? sqrt_disc : -sqrt_disc));
  if (q == real(0)) {  // ray tangent at its own origin
    t0 = real(0);
    t1 = real(0);
    return;
  }
  real ta = q;
  real tb = c / q;
  t0 = min(ta, tb);
  t1 = max(ta, tb);
}

// General form for a ray o + t d (|d| = 1) and a sphere of radius r_m about the origin
// (Ray Tracing Gems ch. 7): the discriminant comes from the squared distance of the centre to the
// ray line rather than from b^2 - c, and the near root is c / q, never a difference.
CV_FN bool ray_sphere(real3 o, real3 d, real r_m, CV_OUT(real) t0, CV_OUT(real) t1) {
  t0 = real(1);
  t1 = real(0);
  real b = dot(o, d);
  real l = length(o - b * d);
  real disc = (r_m - l) * (r_m + l);
  if (disc < real(0)) return false;
  real lo = length(o);
  sphere_roots(b, (lo - r_m) * (lo + r_m), sqrt(disc), t0, t1);
  return true;
}

// Camera-relative form for float32 on the GPU. The ray starts at altitude h_m above the reference
// radius r0_m and its direction has cosine mu with the local up; the sphere lies at altitude hs_m.
// Altitudes come from double on the CPU, so c = r^2 - rs^2 = (h - hs)(2 r0 + h + hs) keeps its
// digits at any camera height; b^2 - c is then formed in double-float (precise.glsl) so rays
// within an ulp of tangency, seen from 0.1 m or from 4e8 m, keep their distances and classification.
CV_FN bool ray_sphere_rel(real r0_m, real h_m, real mu, real hs_m, CV_OUT(real) t0, CV_OUT(real) t1) {
  t0 = real(1);
  t1 = real(0);
  real2 r = two_sum(r0_m, h_m);
  // b = r mu as a double-float
  real2 bp = two_prod(r.x, mu);
  real2 b = two_sum(bp.x, bp.y + r.y * mu);
  // b^2
  real2 bb = two_prod(b.x, b.x);
  precise real bb_lo = bb.y + real(2) * b.x * b.y;
  // c = (h - hs)(2 r0 + h + hs)
  real2 dh = two_sum(h_m, -hs_m);
  real2 e1 = two_sum(real(2) * r0_m, h_m);
  real2 e2 = two_sum(e1.x, hs_m);
  precise real e_lo = e1.y + e2.y;
  real2 cp = two_prod(dh.x, e2.x);
  precise real c_lo = cp.y + dh.x * e_lo + dh.y * e2.x;
  // disc = b^2 - c
  real2 dd = two_sum(bb.x, -cp.x);
  precise real disc = dd.x + (dd.y + (bb_lo - c_lo));
  if (disc < real(0)) return false;
  sphere_roots(b.x, cp.x + c_lo, sqrt(disc), t0, t1);
  return true;
}

// The same, given also nu = sin of the angle between the ray and the local up (>= 0). Callers
// compute nu as |d x up| and mu as d . up: each keeps ~1e-7 relative where it is the smaller one.
// Closer to vertical than to horizontal (a camera at 4e8 m sees the whole Earth within 1 degree of
// its nadir, where mu rounds to +-1), the discriminant is formed from nu as
// rs^2 - (r nu)^2 = (rs - r nu)(rs + r nu), its small factor in double-float; closer to horizontal,
// from mu as in ray_sphere_rel.
CV_FN bool ray_sphere_rel_nu(real r0_m, real h_m, real mu, real nu, real hs_m, CV_OUT(real) t0, CV_OUT(real) t1) {
  if (abs(mu) < nu) return ray_sphere_rel(r0_m, h_m, mu, hs_m, t0, t1);
  t0 = real(1);
  t1 = real(0);
  real2 r = two_sum(r0_m, h_m);
  real2 rs = two_sum(r0_m, hs_m);
  real2 rn = two_prod(r.x, nu);
  precise real rn_lo = rn.y + r.y * nu;
  real2 diff = two_sum(rs.x, -rn.x);
  precise real small = diff.x + (diff.y + (rs.y - rn_lo));
  precise real disc = small * (rs.x + rn.x);
  if (disc < real(0)) return false;
  // c = (h - hs)(2 r0 + h + hs), as in ray_sphere_rel.
  real2 dh = two_sum(h_m, -hs_m);
  real2 e1 = two_sum(real(2) * r0_m, h_m);
  real2 e2 = two_sum(e1.x, hs_m);
  precise real c = dh.x * e2.x + (dh.x * (e1.y + e2.y) + dh.y * e2.x);
  sphere_roots(r.x * mu, c, sqrt(disc), t0, t1);
  return true;
}

// The parts of a camera-relative ray with t >= 0 inside the shell between altitudes hb_m < ht_m:
// up to two segments, (seg.x, seg.y) and (seg.z, seg.w), in order. Returns how many (0, 1 or 2).
// Two happen when the ray dips into the shell, crosses below its base and comes out again.
CV_FN int shell_segments(bool outer_hit, real to0, real to1, bool inner_hit, real ti0, real ti1, CV_OUT(real4) seg);

CV_FN int ray_shell_rel(real r0_m, real h_m, real mu, real hb_m, real ht_m, CV_OUT(real4) seg) {
  real to0;
  real to1;
  real ti0;
  real ti1;
  bool outer = ray_sphere_rel(r0_m, h_m, mu, ht_m, to0, to1);
  bool inner = ray_sphere_rel(r0_m, h_m, mu, hb_m, ti0, ti1);
  return shell_segments(outer, to0, to1, inner, ti0, ti1, seg);
}

CV_FN int ray_shell_rel_nu(real r0_m, real h_m, real mu, real nu, real hb_m, real ht_m, CV_OUT(real4) seg) {
  real to0;
  real to1;
  real ti0;
  real ti1;
  bool outer = ray_sphere_rel_nu(r0_m, h_m, mu, nu, ht_m, to0, to1);
  bool inner = ray_sphere_rel_nu(r0_m, h_m, mu, nu, hb_m, ti0, ti1);
  return shell_segments(outer, to0, to1, inner, ti0, ti1, seg);
}

// Altitude at distance t_m along a ray that starts at altitude h_m with cosine mu to the local up,
// on a sphere of radius r0_m. |o + t d| - r0 loses the altitude in float32 (positions carry 0.5 m
// near the Earth, and a grazing sun ray's samples sit in the ramp between grid levels for hundreds
// of kilometres); the rise t (t + 2 (r0 + h) mu) / (|o + t d| + r0 + h) keeps it, because the
// radius enters only the denominator.
CV_FN real ray_altitude(real r0_m, real h_m, real mu, real t_m) {
  real rh = r0_m + h_m;
  real r_t = sqrt(max(rh * rh + t_m * (t_m + real(2) * rh * mu), real(0)));
  return h_m + t_m * (t_m + real(2) * rh * mu) / (r_t + rh);
}

// The shell's segments from the outer sphere's and the inner sphere's hits.
CV_FN int shell_segments(bool outer_hit, real to0, real to1, bool inner_hit, real ti0, real ti1, CV_OUT(real4) seg) {
  seg = real4(real(0));
  if (!outer_hit || to1 < real(0)) return 0;
  bool inner = inner_hit && ti1 >= real(0);
  real start = max(to0, real(0));
  if (!inner || ti0 == ti1) {
    seg = real4(start, to1, real(0), real(0));
    return 1;
  }
  if (ti0 > start) {
    seg = real4(start, ti0, max(ti1, real(0)), to1);
    return 2;
  }
  seg = real4(max(ti1, real(0)), to1, real(0), real(0));
  return 1;
}
