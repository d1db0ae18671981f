// The kernel's tracking (shaders/kernel/tracking.glsl) on the GPU, for tests/render/tracking_test:
// one estimate per invocation along one ray through the uploaded volume, each with its own random
// stream. Mode 0: ratio tracking's transmittance; mode 1: delta tracking, 1 when the ray leaves
// without a real collision (both estimate the transmittance).
#include "../common/physics.glsl"
#include "../kernel/bindings.glsl"
#include "../kernel/march_stats.glsl"

layout(local_size_x = 64) in;

#include "../kernel/gpu_inputs.glsl"
#include "../kernel/march.glsl"

uniform float u_track_majorant;  // 1/m
uniform bool u_track_bricks;
uniform vec3 u_origin;  // Earth-centred, m
uniform vec3 u_dir;
uniform vec4 u_seg;     // the ray's parts, distances from u_origin
uniform int u_parts;
uniform int u_mode;
uniform uint u_count;
layout(std430, binding = 5) writeonly buffer Estimates { float u_estimates[]; };

struct TrackRng {
  uint state;
};
real track_uniform(inout TrackRng r) { return rng_next(r.state); }

#include "../kernel/tracking.glsl"

void main() {
  load_march_params();
  uint i = gl_GlobalInvocationID.x;
  if (i >= u_count) return;
  TrackRng rng;
  rng.state = pcg_hash(i * 2654435761u + 12345u);
  TrackCounts c = track_counts();
  float e = u_mode == 0 ? ratio_track(u_origin, u_dir, u_seg, u_parts, rng, c)
                        : (delta_track(u_origin, u_dir, u_seg, u_parts, rng, c) >= 3.0e38 ? 1.0 : 0.0);
  u_estimates[i] = e;
}
