// Error-free transformations (Knuth's two-sum, Dekker's split and two-product) so float32 code can
// carry about 48 bits where cancellation demands it (the ray/sphere discriminant near tangency).
// Every intermediate is `precise` so GLSL compilers neither reassociate nor fuse; C++ builds with
// -ffp-contract=off for the same reason. CV_SPLITTER is 2^12+1 for float, 2^27+1 for double.

// a + b = s + e exactly.
CV_FN real2 two_sum(real a, real b) {
  precise real s = a + b;
  precise real bb = s - a;
  precise real e = (a - (s - bb)) + (b - bb);
  return real2(s, e);
}

// a = hi + lo with hi holding the upper half of the significand.
CV_FN real2 split_real(real a) {
  precise real t = CV_SPLITTER * a;
  precise real hi = t - (t - a);
  precise real lo = a - hi;
  return real2(hi, lo);
}

// a * b = p + e exactly (barring underflow).
CV_FN real2 two_prod(real a, real b) {
  precise real p = a * b;
  real2 as = split_real(a);
  real2 bs = split_real(b);
  precise real e = ((as.x * bs.x - p) + as.x * bs.y + as.y * bs.x) + as.y * bs.y;
  return real2(p, e);
}
