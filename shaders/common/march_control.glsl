// March control shared by the CPU reference and the GPU: where a point falls among the extinction
// pyramid's bricks, a safe distance to leave a brick (for empty-space skipping), how many substeps
// a view step takes (steps adapted to optical depth) and when the sun march may stop. Both marchers
// call these, so a CPU image marches the same samples as the GPU one.

// A regional grid's side fades to nothing over one cell beyond it (volume_coords). That border
// belongs to the edge bricks (index clamped to the edge node, whose value bounds the fade), and
// beyond it indices move in by one cell, so the bricks outside the grid end where the border begins
// and no jump passes over it. The map never stretches distances, so a jump bound in index units
// stays a bound.
CV_FN real march_border_index(real g, real count) {
  if (g < real(0)) return g < real(-1) ? g + real(1) : real(0);
  if (g > count - real(1)) return g > count ? g - real(1) : count - real(1);
  return g;
}

// A point's fractional grid index (longitude, latitude, altitude), NOT clamped to the grid the way
// volume_coords clamps it: points outside the grid and its border get indices outside
// [0, count - 1] (march_border_index), and their bricks count as empty. West of a regional grid
// reads as negative longitude indices (the nearer side of the gap). Latitude clamps where
// volume_coords clamps it (grids reaching the poles), and altitude within 1/100 of a level of the
// grid's ends, where rounding of a sample on the shell's boundary still reads the edge level.
CV_FN real3 march_grid_index(real lat_deg, real lon_deg, real alt_m, real3 start, real3 step, real3 count, bool wraps,
                             bool global_lat) {
  real east = mod(lon_deg - start.x, real(360));  // degrees east of the first column, in [0, 360)
  real gx = east / step.x;
  if (wraps) {
    if (gx >= count.x) gx -= count.x;  // as volume_coords: past the last column is the first
  } else {
    real span = (count.x - real(1)) * step.x;
    if (east > span + real(0.5) * (real(360) - span)) gx = (east - real(360)) / step.x;
    gx = march_border_index(gx, count.x);
  }
  real gy = (lat_deg - start.y) / step.y;
  gy = global_lat ? clamp(gy, real(0), count.y - real(1)) : march_border_index(gy, count.y);
  real gz = (alt_m - start.z) / step.z;
  if (gz > real(-0.01) && gz < count.z - real(1) + real(0.01)) gz = clamp(gz, real(0), count.z - real(1));
  return real3(gx, gy, gz);
}

// The brick holding index g at a level whose bricks span `nodes` grid nodes per side.
CV_FN real3 march_brick(real3 g, real nodes) { return floor(g / nodes); }

// Whether brick b lies inside the pyramid level's brick counts nb (else: no data, empty).
CV_FN bool march_brick_inside(real3 b, real3 nb) {
  return b.x >= real(0) && b.y >= real(0) && b.z >= real(0) && b.x < nb.x && b.y < nb.y && b.z < nb.z;
}

// Distance (m) along a straight ray from radius r_m, at cosine mu_up to the local vertical, to where
// it leaves the spherical layer [r_bot_m, r_top_m] (r(s)^2 = r^2 + 2 r mu s + s^2), in the forms
// without cancellation; rounding beyond them is absorbed by the bricks' one-node dilation.
CV_FN real layer_exit_m(real r_m, real mu_up, real r_bot_m, real r_top_m) {
  real c_top = max(real(0), (r_top_m - r_m) * (r_top_m + r_m));  // r_top^2 - r^2
  real rm = r_m * mu_up;
  real s_top = rm >= real(0) ? c_top / (rm + sqrt(rm * rm + c_top)) : -rm + sqrt(rm * rm + c_top);
  if (rm >= real(0)) return s_top;  // rising: r(s) grows, the floor is never reached
  real c_bot = max(real(0), (r_m - r_bot_m) * (r_m + r_bot_m));  // r^2 - r_bot^2
  real disc = rm * rm - c_bot;
  if (disc < real(0)) return s_top;  // passes above the floor
  return min(s_top, c_bot / (-rm + sqrt(disc)));
}

// A lower bound on the distance (m) a straight ray from the point (lat_deg, radius r_m, index g,
// direction at cosine mu_up to the vertical) travels before it can leave brick b (index box
// [b, b + 1) x nodes): exactly through the altitude faces; the great-circle angle changes by at
// most distance / r_min (r_min: the radius of the box's floor), latitude by at most that angle,
// and longitude by at most angle / cos(lat) with lat the largest |latitude| of the box. Bricks on
// the edge rows of a grid reaching the poles reach the poles (volume_coords clamps there), where
// the longitude bound is 0: such bricks never skip.
CV_FN real march_brick_exit_m(real lat_deg, real r_m, real mu_up, real3 g, real3 b, real nodes, real3 nb, real3 start,
                              real3 step, bool global_lat, real r0_m) {
  const real kDegToRad = real(0.017453292519943295);
  real3 lo = b * nodes;
  real3 hi = lo + real3(nodes);
  real lat_lo = start.y + lo.y * step.y;
  real lat_hi = start.y + hi.y * step.y;
  if (global_lat && b.y <= real(0)) lat_lo = real(-90);
  if (global_lat && b.y >= nb.y - real(1)) lat_hi = real(90);
  lat_lo = clamp(lat_lo, real(-90), real(90));
  lat_hi = clamp(lat_hi, real(-90), real(90));
  real r_bot_m = max(r0_m + start.z + lo.z * step.z, real(0.5) * r0_m);
  real d_alt_m = layer_exit_m(r_m, mu_up, r_bot_m, r0_m + start.z + hi.z * step.z);
  // Off a grid reaching the poles, latitude indices may be moved in by the border (see
  // march_border_index): the distance in index units bounds the real one, and the brick's real
  // latitudes may reach a step further.
  real d_lat_deg = global_lat ? min(lat_deg - lat_lo, lat_hi - lat_deg) : min(g.y - lo.y, hi.y - g.y) * step.y;
  if (!global_lat) {
    lat_lo = max(lat_lo - step.y, real(-90));
    lat_hi = min(lat_hi + step.y, real(90));
  }
  // Longitude east of the first column; the circle closes at 360 (the last brick may be partial).
  real d_lon_deg = min(g.x - lo.x, hi.x - g.x) * step.x;
  d_lon_deg = min(d_lon_deg, real(360) - g.x * step.x);
  real cos_max = cos(max(abs(lat_lo), abs(lat_hi)) * kDegToRad);
  real angle_rad = min(d_lat_deg, d_lon_deg * cos_max) * kDegToRad;
  return max(real(0), min(d_alt_m, angle_rad * r_bot_m));
}

// The index of the first sample at or past `ahead_m` from sample i, on the grid (i + offset) dt:
// skipping never moves the samples, so a skipped render equals the unskipped one. At least i + 1.
CV_FN int march_resume_index(int i, real ahead_m, real dt_m) {
  real k = ceil(ahead_m / dt_m);
  return i + int(max(real(1), min(k, real(1.0e9))));
}

// Substeps for a view step of dt_m through a brick whose extinction is at most sigma_max_per_m: so
// many that each keeps its optical depth within max_tau (at most 64: a step through a core of
// optical depth ~1000 per step is then sampled at ~16 per substep, as deep as light gets anyway).
CV_FN int march_substeps(real sigma_max_per_m, real dt_m, real max_tau) {
  if (!(max_tau > real(0))) return 1;
  real n = ceil(sigma_max_per_m * dt_m / max_tau);
  return int(clamp(n, real(1), real(64)));
}

// The most steps one shell segment of a sun march takes for the length limit below. 256 keeps one
// view step within llvmpipe's loop budget even with 64 adaptive substeps, each with a full sun march
// over two segments: 64 x (2 x 257 + the other loops' ~25) = ~34 500 of 64 511 iterations (512
// would not fit). At 256 a grazing sun segment through a 10 km layer (~360 km) still takes 1.4 km
// steps; loop_iterations_per_view_step (app/render/raymarcher.cpp) budgets for it.
const int CV_SUN_SEGMENT_STEPS_MAX = 256;

// The longest a sun step may be (m): setting_m where > 0, else the grid's horizontal cell size at
// radius r_m (the layer's floor): the smaller of the latitude spacing and the longitude spacing at
// the grid's highest |latitude|, whose cosine is floored at 0.5 (60 deg) so that a grid reaching
// the poles, whose cells shrink to nothing there, does not send every sun march to the cap. A
// cloud spans at least a cell (the data cannot hold less), so a step no longer than a cell cannot
// jump over one, which a fixed count of steps along a grazing 200 km segment does.
CV_FN real sun_step_limit_m(real setting_m, real3 start, real3 step, real3 count, real r_m) {
  if (setting_m > real(0)) return setting_m;
  const real kDegToRad = real(0.017453292519943295);
  real lat_far_deg = min(max(abs(start.y), abs(start.y + (count.y - real(1)) * step.y)), real(90));
  real lat_m = abs(step.y) * kDegToRad * r_m;
  real lon_m = abs(step.x) * kDegToRad * r_m * max(cos(lat_far_deg * kDegToRad), real(0.5));
  return max(min(lat_m, lon_m), real(1));
}

// Steps of a sun march over a shell segment of len_m on which no extinction exceeds sigma_max_per_m
// (the volume's largest): sun_steps, or more where steps of len_m / sun_steps would be longer than
// max_step_m (a grazing sun; at most CV_SUN_SEGMENT_STEPS_MAX; max_step_m <= 0: no length limit);
// then only as many as keep every step below max_step_tau of optical depth (thin cloud pays for a
// few steps where the towering cell needs them all; max_step_tau <= 0: no such rule). The
// transmittance errors are measured in docs/physics.md.
CV_FN int sun_march_steps(real sigma_max_per_m, real len_m, real max_step_tau, int sun_steps, real max_step_m) {
  int n = max(sun_steps, 1);
  if (max_step_m > real(0)) {
    real by_length = min(ceil(len_m / max_step_m), real(CV_SUN_SEGMENT_STEPS_MAX));
    n = max(n, int(by_length));
  }
  if (!(max_step_tau > real(0))) return n;
  real by_tau = ceil(sigma_max_per_m * len_m / max_step_tau);
  return int(clamp(by_tau, real(1), real(n)));
}

// The optical depth at which a sun march may stop: beyond it every octave's exp(-a^i tau_sun) is
// below min_transmittance (the weakest attenuation is the last octave's, a^(n-1) for a < 1), so the
// rest of the path changes the light by less than that fraction. min_transmittance <= 0: never
// (a huge limit). Computed once per frame: pow and log per sun step cost llvmpipe dearly.
CV_FN real sun_march_tau_limit(int octaves, real a, real min_transmittance) {
  if (!(min_transmittance > real(0))) return real(3.0e38);
  real scale = a < real(1) ? pow(a, real(max(octaves - 1, 0))) : real(1);
  return -log(min_transmittance) / max(scale, real(1e-30));
}
