// Majorant-driven tracking through the kernel's medium, for the Monte Carlo reference (today in C++,
// core/reference/monte_carlo.cpp) and a GPU path tracer later: delta tracking finds a ray's first
// real collision and ratio tracking its transmittance, both unbiased, with null collisions against a
// majorant that is the volume's largest extinction or, on request, the pyramid's brick bound.
// Needs march.glsl (medium_at_point, space_at) and, from the including side, u_track_majorant (1/m),
// u_track_bricks (bool) and a random stream TrackRng with track_uniform(rng) in [0, 1).

// Below this many metres the pyramid's extent is not trusted to make progress (a query on a brick
// face); the volume's majorant covers that metre instead, which keeps the estimate unbiased.
#define CV_TRACK_MIN_BRICK_EXTENT_M real(1.0)
// Ratio tracking plays roulette below this transmittance: deep in thick cloud a sun ray would
// otherwise look up the medium for hundreds of optical depths to multiply tiny factors.
#define CV_TRACK_ROULETTE_BELOW real(1e-2)

// A lookup exceeds its majorant when the medium is above it by more than rounding: float's trilinear
// fetch can land a few ulps above the largest node it interpolates.
#define CV_TRACK_EXCEED_TOL real(1e-5)

// -log(1 - u): an exponential draw from a uniform one, accurate for small u.
CV_FN real exponential_draw(real u) {
#ifdef CV_GLSL
  return -log(real(1.0) - u);
#else
  return -std::log1p(-u);
#endif
}

// The majorant valid from t on along the ray p + s d (s < t_end), and the distance up to which it holds.
CV_FN void track_majorant(real3 p, real3 d, real t, real t_end, CV_OUT(real) sigma_max, CV_OUT(real) t_valid) {
  sigma_max = u_track_majorant;
  t_valid = t_end;
  if (!u_track_bricks) return;
  real3 q = p + t * d;
  real extent;
  real smax;
  bool empty = space_at(q, length(q) - u_r0, d, extent, smax);
  if (!(extent >= CV_TRACK_MIN_BRICK_EXTENT_M && extent < real(3.0e38))) {
    t_valid = min(t + CV_TRACK_MIN_BRICK_EXTENT_M, t_end);
    return;
  }
  sigma_max = empty ? real(0.0) : smax;
  t_valid = min(t + extent, t_end);
}

// A tracking walk's counters: tentative collisions rejected (delta tracking), medium lookups (ratio
// tracking), lookups where the medium exceeded the majorant (0 unless a majorant is wrong), and the
// loop iterations the walk took (llvmpipe ends every loop of an invocation after 65 535 in all:
// the GPU path tracer compares this count with that budget).
struct TrackCounts {
  uint null_collisions;
  uint lookups;
  uint exceeded;
  uint iterations;
};

CV_FN TrackCounts track_counts() {
  TrackCounts c;
  c.null_collisions = 0u;
  c.lookups = 0u;
  c.exceeded = 0u;
  c.iterations = 0u;
  return c;
}

// The next tentative collision of a walk from distance t within [t, b): true with its distance
// (t updated) and the majorant there; false when the walk has left [t, b).
CV_FN bool next_tentative(real3 p, real3 d, CV_INOUT(real) t, real b, CV_INOUT(TrackRng) rng, CV_OUT(real) majorant,
                          CV_INOUT(TrackCounts) c) {
  majorant = real(0.0);
  while (t < b) {
    c.iterations += 1u;
    real lim;
    track_majorant(p, d, t, b, majorant, lim);
    if (!(majorant > real(0.0))) {
      t = lim;
      continue;
    }
    // The exponential distribution is memoryless: a draw past the majorant's range restarts there.
    real s = exponential_draw(track_uniform(rng)) / majorant;
    if (t + s >= lim) {
      t = lim;
      continue;
    }
    t += s;
    return true;
  }
  return false;
}

// The medium's extinction at a tentative collision x, counted as a loop iteration and, where it
// exceeds the majorant maj beyond rounding, as a wrong majorant.
CV_FN real tentative_sigma(real3 x, real maj, CV_INOUT(TrackCounts) c) {
  c.iterations += 1u;
  real sl;
  real si;
  medium_at_point(x, sl, si);
  real sigma = sl + si;
  c.exceeded += sigma > maj * (real(1.0) + CV_TRACK_EXCEED_TOL) ? 1u : 0u;
  return sigma;
}

// Delta tracking along the ray's parts in the cloud shell, seg[0..2n) (distances from p): the
// distance to the first real collision (a tentative one is real with probability sigma /
// majorant), or 3e38 when the ray leaves them.
CV_FN real delta_track(real3 p, real3 d, real4 seg, int n, CV_INOUT(TrackRng) rng, CV_INOUT(TrackCounts) c) {
  for (int k = 0; k < n; ++k) {
    real t = k == 0 ? seg.x : seg.z;
    real b = k == 0 ? seg.y : seg.w;
    real maj;
    c.iterations += 2u;  // this loop's test and next_tentative's last one
    while (next_tentative(p, d, t, b, rng, maj, c)) {
      real sigma = tentative_sigma(p + t * d, maj, c);
      if (track_uniform(rng) * maj < sigma) return t;
      c.null_collisions += 1u;
    }
  }
  return real(3.0e38);
}

// Ratio tracking along the same parts: the transmittance, each tentative collision keeping the
// fraction 1 - sigma / majorant, with roulette below CV_TRACK_ROULETTE_BELOW (a survivor carries
// the threshold: the expectation is unchanged). 0 when the roulette ends it.
CV_FN real ratio_track(real3 p, real3 d, real4 seg, int n, CV_INOUT(TrackRng) rng, CV_INOUT(TrackCounts) c) {
  real tr = real(1.0);
  for (int k = 0; k < n; ++k) {
    real t = k == 0 ? seg.x : seg.z;
    real b = k == 0 ? seg.y : seg.w;
    real maj;
    c.iterations += 2u;  // this loop's test and next_tentative's last one
    while (next_tentative(p, d, t, b, rng, maj, c)) {
      real sigma = tentative_sigma(p + t * d, maj, c);
      c.lookups += 1u;
      tr *= max(real(0.0), real(1.0) - sigma / maj);
      if (tr < CV_TRACK_ROULETTE_BELOW) {
        if (track_uniform(rng) * CV_TRACK_ROULETTE_BELOW >= tr) return real(0.0);
        tr = CV_TRACK_ROULETTE_BELOW;
      }
    }
  }
  return tr;
}
