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

// The dispatch's own state.
layout(rgba32f, binding = CV_IMAGE_OUT) writeonly uniform image2D u_out;
layout(rgba32f, binding = CV_IMAGE_STATE_L) uniform image2D u_state_l;          // radiance so far, view transmittance
// depth_w, depth_t, t_half, and the next step (n) while the march goes on or -(n + 1) once it has ended;
// with translucent geometry n is next_step * 8 + the next translucent fragment
layout(rgba32f, binding = CV_IMAGE_STATE_DEPTH) uniform image2D u_state_depth;
// The two-stream march's second view transmittance (MarchState.t_ms) between dispatches.
layout(r32f, binding = CV_IMAGE_STATE_MS) uniform image2D u_state_ms;
layout(r32f, binding = CV_IMAGE_CLOUD_DEPTH) writeonly uniform image2D u_cloud_depth;  // pass 1 writes it there
uniform int u_pass;        // 0: march a range of steps; 1: air and ground, then u_out
uniform int u_step_begin;  // pass 0: the first view step (counted over both shell segments)
uniform int u_step_count;  // pass 0: how many
uniform int u_row_offset;  // first image row of this dispatch (long renders go in tiles of rows)

#include "../kernel/gpu_inputs.glsl"
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
  load_march_params();
  ivec2 px = ivec2(gl_GlobalInvocationID.xy) + ivec2(0, u_row_offset);
  if (px.x >= u_size.x || px.y >= u_size.y) return;
  bool first = u_pass == 0 && u_step_begin == 0;
  vec4 state_depth = first ? vec4(0.0, 0.0, 3.0e38, 0.0) : imageLoad(u_state_depth, px);
  bool ended = state_depth.w < 0.0;
  // A ray whose march has ended has nothing more to do until the last pass: its state stands.
  if (u_pass == 0 && ended) return;
  MarchRay r = march_ray(px);
  vec4 state_l = first ? vec4(0.0, 0.0, 0.0, 1.0) : imageLoad(u_state_l, px);
  MarchState s;
  s.radiance = state_l.rgb;
  s.t_view = state_l.a;
  s.t_ms = kTwoStream ? (first ? 1.0 : imageLoad(u_state_ms, px).r) : 1.0;
  s.depth_w = state_depth.x;
  s.depth_t = state_depth.y;
  s.t_half = state_depth.z;
  s.half_before = 1.0;  // march_advance settles t_half before it returns
  s.half_sigma = 0.0;
  s.half_ds = 0.0;
  s.t_first = 3.0e38;  // not kept between dispatches: only the CPU's probes read it
  s.ended = ended;
  int code = ended ? -1 - int(state_depth.w) : int(state_depth.w);
  s.next_step = kTranslucent ? code >> 3 : code;
  s.tl_next = kTranslucent ? code & 7 : 0;
  if (u_pass == 0) {
    march_advance(r, px, u_step_begin, u_step_count, s);
    flush_stats();
    imageStore(u_state_l, px, vec4(s.radiance, s.t_view));
    if (kTwoStream) imageStore(u_state_ms, px, vec4(s.t_ms));
    int out_code = kTranslucent ? s.next_step * 8 + s.tl_next : s.next_step;
    imageStore(u_state_depth, px, vec4(s.depth_w, s.depth_t, s.t_half, float(s.ended ? -1 - out_code : out_code)));
    return;
  }
  imageStore(u_out, px, march_finish(r, px, s));
  imageStore(u_cloud_depth, px, vec4(s.t_half));
}
