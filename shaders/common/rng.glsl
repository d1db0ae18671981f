// A small counter-based random number generator (PCG hash) that gives bit-identical sequences on
// the GPU and in C++, so GPU and CPU samplers can be compared draw for draw.
CV_FN uint pcg_hash(uint v) {
  uint state = v * 747796405u + 2891336453u;
  uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
  return (word >> 22u) ^ word;
}

// Uniform in [0, 1) with 24 random bits (exact in float32); advances the state.
CV_FN real rng_next(CV_INOUT(uint) state) {
  state = pcg_hash(state);
  return real(state >> 8u) * real(5.9604644775390625e-8);
}

// The offset within a march step for pixel (px, py) in accumulation frame `frame`: a hash, so the
// GPU and the CPU reference march through the same points; frames decorrelate the offsets.
CV_FN real step_jitter(uint px, uint py, uint frame) {
  uint seed = pcg_hash(px * 1973u + py * 9277u + frame * 26699u + 1u);
  return real(seed >> 8u) * real(5.9604644775390625e-8);
}

// The offset within a march step from the blue-noise mask (core/noise/blue_noise): the pixel's
// mask value rotated by the golden ratio each frame, fract(mask + frame * 0.6180339887), so one
// pixel's offsets over frames form a low-discrepancy (R1) sequence while neighbouring pixels keep
// their blue-noise differences. The sum is taken in 24-bit fixed point (0.618034 * 2^24 rounded)
// with integer wrap-around: the GPU's float and the reference's double then give the same offset
// bit for bit at any frame, where a float sum frame * 0.618 would lose digits as frames grow.
// mask_value is rank / n^2 with n^2 <= 2^24, so mask_value * 2^24 is an exact integer.
CV_FN real blue_noise_jitter(real mask_value, uint frame) {
  uint fixed24 = uint(mask_value * real(16777216.0)) + frame * 10368890u;
  return real(fixed24 & 16777215u) * real(5.9604644775390625e-8);
}
