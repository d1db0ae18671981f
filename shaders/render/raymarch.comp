// The GPU driver of the march kernel (shaders/kernel/march.glsl): the kernel's parameters as one
// uniform block, its textures and counters, and the dispatch passes. A frame takes several
// dispatches: pass 0 advances the march of every ray over the view steps [u_step_begin,
// u_step_begin + u_step_count) and keeps its state in u_state_*; pass 1 composites the air and the
// ground and writes u_out (rgb radiance, a = view transmittance, 0 on the globe) and u_cloud_depth
// (the distance from the camera at which the view transmittance fell to 0.5; 3e38: never).
// The reason is Mesa's llvmpipe: all loops of one invocation share a budget of 65 535 iterations,
// after which every loop runs its body once and stops, silently; the host
// (app/render/raymarcher.cpp) sizes u_step_count so that one dispatch stays inside it.
#include "../common/physics.glsl"
#include "../kernel/bindings.glsl"
#include "../kernel/march_stats.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

// The kernel's parameters (core/kernel/march_params.hpp packs them, std140).
#define CV_PARAM(T, name) T name;
#define CV_PARAM_ARRAY(T, name, N) T name[N];
layout(std140, binding = CV_UBO_MARCH) uniform MarchParams {
#include "../kernel/march_params.glsl"
};
#undef CV_PARAM
#undef CV_PARAM_ARRAY

// The dispatch's own state.
layout(rgba32f, binding = CV_IMAGE_OUT) writeonly uniform image2D u_out;
layout(rgba32f, binding = CV_IMAGE_STATE_L) uniform image2D u_state_l;          // radiance so far, view transmittance
layout(rgba32f, binding = CV_IMAGE_STATE_DEPTH) uniform image2D u_state_depth;  // depth_w, depth_t, 1 once ended, next step
layout(r32f, binding = CV_IMAGE_STATE_HALF) uniform image2D u_state_half;        // where transmittance fell to 0.5
layout(r32f, binding = CV_IMAGE_CLOUD_DEPTH) writeonly uniform image2D u_cloud_depth;  // pass 1 writes it there
uniform int u_pass;        // 0: march a range of steps; 1: air and ground, then u_out
uniform int u_step_begin;  // pass 0: the first view step (counted over both shell segments)
uniform int u_step_count;  // pass 0: how many
uniform int u_row_offset;  // first image row of this dispatch (long renders go in tiles of rows)

// The prepared volume and the other textures, fetched texel by texel (interpolated in the kernel).
layout(binding = CV_TEX_LIQUID) uniform sampler3D u_liquid;  // grid-mean extinction, 1/m (cf x in-cloud)
layout(binding = CV_TEX_ICE) uniform sampler3D u_ice;
layout(binding = CV_TEX_COLUMN_TAU) uniform sampler2D u_column_tau;  // vertical optical depth per column
layout(binding = CV_TEX_JITTER_MASK) uniform sampler2D u_jitter_mask;  // blue-noise rank / n^2, tiled
layout(binding = CV_TEX_GROUND) uniform sampler2D u_ground;  // linear albedo, equirectangular
layout(binding = CV_TEX_NOISE_LOW) uniform sampler3D u_noise_low;    // Perlin-Worley, periodic, [0, 1]
layout(binding = CV_TEX_NOISE_HIGH) uniform sampler3D u_noise_high;  // Worley fBm, periodic, [0, 1]
layout(binding = CV_TEX_DEPTH) uniform sampler2D u_depth;    // distance (m) from the camera to opaque geometry
layout(binding = CV_TEX_OPAQUE) uniform sampler2D u_opaque;  // that geometry's radiance
// The extinction pyramid: (min, max) per brick, levels one after the other, x fastest.
layout(std430, binding = CV_SSBO_PYRAMID) readonly buffer Pyramid { vec2 u_min_max[]; };
// Per-frame counters (MarchStats), each as (low, high) 32-bit words.
layout(std430, binding = CV_SSBO_STATS) buffer Stats { uint u_stats[]; };
uint g_stats[CV_STAT_COUNT] = uint[CV_STAT_COUNT](0u, 0u, 0u, 0u, 0u, 0u, 0u, 0u);

// Program variants (kernel::MarchVariant::defines): llvmpipe runs both sides of a branch under masks,
// so code switched off by a uniform would still cost every iteration. Without defines (a bare
// compile): the defaults of MarchSettings.
#ifndef CV_SKIP_EMPTY
#define CV_SKIP_EMPTY 1
#endif
#ifndef CV_ADAPTIVE
#define CV_ADAPTIVE 0
#endif
#ifndef CV_ATMOSPHERE
#define CV_ATMOSPHERE 1
#endif
#ifndef CV_GLOBE
#define CV_GLOBE 1
#endif
#ifndef CV_NOISE
#define CV_NOISE 0
#endif
const bool kSkipEmpty = CV_SKIP_EMPTY != 0;
const bool kAdaptive = CV_ADAPTIVE != 0;
const bool kAtmosphere = CV_ATMOSPHERE != 0;
const bool kGlobe = CV_GLOBE != 0;
const bool kNoise = CV_NOISE != 0;

#include "../kernel/march.glsl"

// Adds this invocation's counts to the frame's, carrying into the high words.
void flush_stats() {
  for (int k = 0; k < CV_STAT_COUNT; ++k) {
    if (g_stats[k] == 0u) continue;
    uint old = atomicAdd(u_stats[2 * k], g_stats[k]);
    if (old > 0xFFFFFFFFu - g_stats[k]) atomicAdd(u_stats[2 * k + 1], 1u);
  }
}

void main() {
  ivec2 px = ivec2(gl_GlobalInvocationID.xy) + ivec2(0, u_row_offset);
  if (px.x >= u_size.x || px.y >= u_size.y) return;
  MarchRay r = march_ray(px);
  bool first = u_pass == 0 && u_step_begin == 0;
  vec4 state_l = first ? vec4(0.0, 0.0, 0.0, 1.0) : imageLoad(u_state_l, px);
  vec4 state_depth = first ? vec4(0.0) : imageLoad(u_state_depth, px);
  MarchState s;
  s.radiance = state_l.rgb;
  s.t_view = state_l.a;
  s.depth_w = state_depth.x;
  s.depth_t = state_depth.y;
  s.ended = state_depth.z > 0.0;
  s.next_step = int(state_depth.w);
  s.t_half = first ? 3.0e38 : imageLoad(u_state_half, px).r;
  if (u_pass == 0) {
    march_advance(r, px, u_step_begin, u_step_count, s);
    flush_stats();
    imageStore(u_state_l, px, vec4(s.radiance, s.t_view));
    imageStore(u_state_depth, px, vec4(s.depth_w, s.depth_t, s.ended ? 1.0 : 0.0, float(s.next_step)));
    imageStore(u_state_half, px, vec4(s.t_half));
    return;
  }
  imageStore(u_out, px, march_finish(r, px, s));
  imageStore(u_cloud_depth, px, vec4(s.t_half));
}
