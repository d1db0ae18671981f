// Sub-grid erosion noise: where a point falls in the tileable noise textures, the texel pair and
// weight of wrapped trilinear interpolation, and the erosion of the grid-mean extinction. The CPU
// reference and the GPU raymarcher both use these (through shaders/kernel/march.glsl), so they erode
// the same field.

// The high-frequency tile's coordinates from the low-frequency tile's: it repeats 4 times per
// low-frequency tile (an integer, so both patterns tile together; a power of two, so the scaling
// is exact in float).
CV_FN real3 noise_high_coords(real3 t_low) { return fract(t_low * real(4)); }

// Extinction is normalised as the opacity across an eighth of the low-frequency tile (about the
// size of its smallest features), so "thin" and "thick" are judged at the scale of the noise.
CV_FN real noise_feature_m(real period_m) { return period_m * real(0.125); }

// Coordinates in [0, 1) of a point in a tile of period_m metres. rel_m is the point relative to an
// anchor chosen near the data, anchor_frac the anchor's own position in tiles (fract(anchor /
// period), computed in double on the CPU): a float position at 6.4e6 m keeps 0.5 m, and dividing it
// whole by the period would lose more digits than subtracting a nearby anchor first.
CV_FN real3 noise_tile_coords(real3 rel_m, real3 anchor_frac, real period_m) {
  return fract(anchor_frac + rel_m / period_m);
}

// Wrapped linear interpolation along one axis of an n-texel periodic texture: texel i sits at
// coordinate i / n, so coordinate c in [0, 1] lies between texels i0 and i1 = i0 + 1 (mod n).
CV_FN void noise_texel_pair(real c, int n, CV_OUT(int) i0, CV_OUT(int) i1, CV_OUT(real) w) {
  real x = c * real(n);
  real fl = floor(x);
  w = x - fl;
  i0 = int(fl) % n;
  if (i0 < 0) i0 += n;
  i1 = (i0 + 1) % n;
}

// The erosion threshold in [0, amount]: low Perlin-Worley (the low-frequency tile) erodes most,
// billowy Worley detail (the high-frequency tile) less. Both noises are in [0, 1].
CV_FN real erosion_threshold(real n_low, real n_high, real amount) {
  return clamp(amount, real(0), real(1)) * (real(0.75) * (real(1) - n_low) + real(0.25) * (real(1) - n_high));
}

// Erodes a grid-mean extinction (1/m): with d the opacity of one noise feature (feature_m metres)
// of this extinction, in [0, 1), the eroded opacity is remap(d, threshold, 1, 0, 1) = (d - t)/(1 - t)
// (Schneider & Vos 2015), which is never above d for d <= 1. The extinction is scaled by the ratio
// of the two opacities, capped at 1: erosion only ever removes extinction, so a min/max bound built
// from the data stays valid, and thin cloud edges erode before optically thick cores.
CV_FN real erode_extinction(real sigma_per_m, real threshold, real feature_m) {
  // A threshold of 0 (no noise) returns the data exactly, not through a ratio that rounds.
  if (!(sigma_per_m > real(0)) || !(threshold > real(0))) return sigma_per_m;
  real x = sigma_per_m * feature_m;
  real d = x * segment_factor(x);  // 1 - exp(-x) without cancellation for thin media
  if (d <= threshold) return real(0);
  real keep = (d - threshold) / ((real(1) - threshold) * d);
  return sigma_per_m * min(keep, real(1));
}
