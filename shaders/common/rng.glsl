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
