// The GPU path tracer: the kernel's path (shaders/kernel/path.glsl), the one the CPU Monte Carlo
// reference runs in double, traced once per pixel per dispatch for sample u_sample, and added to
// per-pixel sums (radiance and its square, luminance and its square) from which the host takes the
// mean and its standard error (app/render/raymarcher.cpp, GpuRaymarcher::trace_paths).
// Mesa's llvmpipe ends every loop of an invocation after 65 535 iterations in all, silently: there
// (u_loop_budget) a path stops between vertices once its walk has taken 15 000 iterations, keeps
// its state in u_state, and resumes in the next dispatch; the host dispatches until no path is in
// flight. A dispatch whose walk still came near the budget (one vertex of more than ~45 000
// iterations) is counted in the stats as suspect, so an image says when a path may have been cut.
#include "../common/physics.glsl"
#include "../kernel/bindings.glsl"
#include "../kernel/march_stats.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

uniform int u_pass;               // 0: start sample u_sample in every pixel; 1: resume the paths in flight
uniform uint u_sample;            // the sample index of pass 0, for every pixel
uniform uint u_seed;              // the image's seed
uniform int u_row_offset;         // first image row of this dispatch
uniform float u_track_majorant;   // 1/m: the volume's largest extinction
uniform bool u_track_bricks;      // the pyramid's brick bounds as majorants instead
uniform int u_path_max_bounces;
uniform int u_path_roulette_after;
uniform bool u_path_peak_mis;
uniform bool u_loop_budget;       // the driver ends loops after 65 535 iterations (llvmpipe)

// Per pixel: (r, g, b, luminance) sums, then their squares, in float (the host adds each batch to
// double sums before float runs out of digits).
layout(std430, binding = CV_SSBO_PATH_SUMS) buffer PathSums { vec4 u_sums[]; };
// Counters, each as (low, high) 32-bit words: paths, scatterings, null collisions, shadow lookups,
// truncated, roulette, peak samples, majorant exceeded, dispatches near the loop budget, samples not
// finite, paths still in flight after this dispatch.
layout(std430, binding = CV_SSBO_PATH_STATS) buffer PathStats { uint u_path_stats[]; };

#include "../kernel/gpu_inputs.glsl"
#include "../kernel/march.glsl"

#define TrackRng uint
real track_uniform(inout uint rng) { return rng_next(rng); }
uint track_bits(inout uint rng) {
  rng = pcg_hash(rng);
  return rng;
}

#include "../kernel/tracking.glsl"
#include "../kernel/path.glsl"

void add_stat(int k, uint v) {
  if (v == 0u) return;
  uint old = atomicAdd(u_path_stats[2 * k], v);
  if (old > 0xFFFFFFFFu - v) atomicAdd(u_path_stats[2 * k + 1], 1u);
}

// The path's state between dispatches, per pixel (PathState packed in five vec4).
layout(std430, binding = CV_SSBO_PATH_STATE) buffer PathStateBuffer { vec4 u_state[]; };

void store_state(uint idx, PathState s, uint rng) {
  float flags = float(s.end + (s.done ? 4 : 0) + (s.prev_peak ? 8 : 0));
  u_state[5u * idx] = vec4(s.p, float(s.scatterings));
  u_state[5u * idx + 1u] = vec4(s.d, flags);
  u_state[5u * idx + 2u] = vec4(s.beta, s.prev_sl);
  u_state[5u * idx + 3u] = vec4(s.radiance, s.prev_si);
  u_state[5u * idx + 4u] = vec4(s.prev_d, uintBitsToFloat(rng));
}

PathState load_state(uint idx, out uint rng) {
  PathState s;
  vec4 a = u_state[5u * idx];
  vec4 b = u_state[5u * idx + 1u];
  vec4 c = u_state[5u * idx + 2u];
  vec4 e = u_state[5u * idx + 3u];
  vec4 f = u_state[5u * idx + 4u];
  int flags = int(b.w);
  s.p = a.xyz;
  s.scatterings = int(a.w);
  s.d = b.xyz;
  s.end = flags & 3;
  s.done = (flags & 4) != 0;
  s.prev_peak = (flags & 8) != 0;
  s.beta = c.xyz;
  s.prev_sl = c.w;
  s.radiance = e.xyz;
  s.prev_si = e.w;
  s.absorbed = vec3(0.0);  // not kept on the GPU
  s.prev_d = f.xyz;
  rng = floatBitsToUint(f.w);
  return s;
}

void main() {
  load_march_params();
  ivec2 px = ivec2(gl_GlobalInvocationID.xy) + ivec2(0, u_row_offset);
  if (px.x >= u_size.x || px.y >= u_size.y) return;
  uint idx = uint(px.y) * uint(u_size.x) + uint(px.x);
  PathState s;
  uint rng;
  if (u_pass == 0) {  // a new sample: the pixel's view ray and its own random stream
    // A counter-based stream per (seed, pixel, sample), as the CPU's PathRng is (another hash).
    rng = pcg_hash(u_seed * 0x9E3779B9u ^ pcg_hash(idx * 0x85EBCA6Bu + 0x632BE5ABu) ^ pcg_hash(u_sample * 0xC2B2AE35u + 0x27D4EB2Fu));
    // With anti-aliasing, each sample's ray passes through a uniform point of its pixel (a box
    // filter: what the march's accumulated frames tend to); else through the centre.
    vec2 j = vec2(0.0);
    if (u_anti_alias) j = (vec2(rng_next(rng), rng_next(rng)) - 0.5) / float(u_pixel_block);
    vec3 d = pixel_direction_jittered(px, j);
    bool misses;
    vec3 o = path_camera_origin(d, misses);
    s = path_begin(o, d);
    s.done = misses;
    if (misses) {
      TrackCounts c0 = track_counts();
      s.radiance = path_miss(d, c0);
    }
  } else {
    s = load_state(idx, rng);
    if (s.done) return;
  }
  TrackCounts c = track_counts();
  PathCounts pc = path_counts();
  // Vertices while the walk stays well inside the loop budget (a vertex may take tens of thousands
  // of iterations in a towering cell); the rest in the next dispatch.
  path_advance(s, rng, c, pc, u_loop_budget ? 15000u : 0xFFFFFFFFu);
  if (s.done) {
    vec3 v = vec3(s.radiance);
    // A sample that is not finite is counted and left out rather than spoiling the pixel.
    bool finite = !(any(isnan(v)) || any(isinf(v)));
    float l = finite ? dot(v, vec3(0.2126, 0.7152, 0.0722)) : 0.0;
    if (!finite) v = vec3(0.0);
    u_sums[2u * idx] += vec4(v, l);
    u_sums[2u * idx + 1u] += vec4(v * v, l * l);
    add_stat(0, 1u);
    add_stat(1, uint(s.scatterings));
    add_stat(9, finite ? 0u : 1u);
  } else {
    add_stat(10, 1u);  // still in flight: the host dispatches again
  }
  store_state(idx, s, rng);
  add_stat(2, c.null_collisions);
  add_stat(3, c.lookups);
  add_stat(4, pc.truncated);
  add_stat(5, pc.roulette_killed);
  add_stat(6, pc.peak_samples);
  add_stat(7, c.exceeded);
  // The loop iterations of this dispatch, as llvmpipe counts them (TrackCounts.iterations, and a
  // few of the setup's); past 65 535 every loop would have run once and stopped. Above 60 000 the
  // walk is counted as suspect.
  add_stat(8, u_loop_budget && c.iterations + 16u > 60000u ? 1u : 0u);
}
