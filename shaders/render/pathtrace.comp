// The GPU path tracer: the kernel's path (shaders/kernel/path.glsl), the one the CPU Monte Carlo
// reference runs in double, traced once per pixel per dispatch for sample u_sample, and added to
// per-pixel sums (radiance and its square, luminance and its square) from which the host takes the
// mean and its standard error (app/render/raymarcher.cpp, GpuRaymarcher::trace_paths).
// Mesa's llvmpipe ends every loop of an invocation after 65 535 iterations in all, silently: there
// (u_loop_budget) a path stops between vertices once its walk has taken 15 000 iterations, keeps
// its state in u_state, and resumes in the next dispatch; the host dispatches until no path is in
// flight. A dispatch whose walk still came near the budget (one vertex of more than ~45 000
// iterations) is counted in the stats as suspect, so an image says when a path may have been cut.
// The droplets' peak around the sun is split off as on the CPU (CV_PATH_SPLIT): each pixel keeps a
// stack of u_path_branch_slots branches in u_branches, traced after its path, last made first, in
// the same dispatches; a vertex that finds the stack full takes the one-sample technique instead
// (path.glsl).
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
uniform int u_path_branch_slots;  // branches a pixel's stack holds (0: no splitting)

// Per pixel: (r, g, b, luminance) sums, then their squares, in float (the host adds each batch to
// double sums before float runs out of digits).
layout(std430, binding = CV_SSBO_PATH_SUMS) buffer PathSums { vec4 u_sums[]; };
// Counters, each as (low, high) 32-bit words: paths, scatterings, null collisions, shadow lookups,
// truncated, roulette, peak samples, majorant exceeded, dispatches near the loop budget, samples not
// finite, paths still in flight after this dispatch, vertices that found the branch stack full.
layout(std430, binding = CV_SSBO_PATH_STATS) buffer PathStats { uint u_path_stats[]; };
// Per pixel, u_path_branch_slots branches of ten floats: position, direction, throughput, vertices.
layout(std430, binding = CV_SSBO_PATH_BRANCHES) buffer PathBranches { float u_branches[]; };

#include "../kernel/gpu_inputs.glsl"
#include "../kernel/march.glsl"

#define TrackRng uint
real track_uniform(inout uint rng) { return rng_next(rng); }
uint track_bits(inout uint rng) {
  rng = pcg_hash(rng);
  return rng;
}

#define CV_PATH_SPLIT 1
#include "../kernel/tracking.glsl"
#include "../kernel/path.glsl"

uint g_pixel;         // this invocation's pixel
int g_branches;       // the branches on its stack
uint g_without_room;  // vertices that would have split but found the stack full

bool path_room() {
  if (g_branches < u_path_branch_slots) return true;
  g_without_room += 1u;
  return false;
}

void path_split(PathState b) {
  uint o = (g_pixel * uint(u_path_branch_slots) + uint(g_branches)) * 10u;
  u_branches[o] = b.p.x;
  u_branches[o + 1u] = b.p.y;
  u_branches[o + 2u] = b.p.z;
  u_branches[o + 3u] = b.d.x;
  u_branches[o + 4u] = b.d.y;
  u_branches[o + 5u] = b.d.z;
  u_branches[o + 6u] = b.beta.x;
  u_branches[o + 7u] = b.beta.y;
  u_branches[o + 8u] = b.beta.z;
  u_branches[o + 9u] = float(b.scatterings);
  g_branches += 1;
}

bool path_pop(out PathState b) {
  if (g_branches <= 0) return false;
  g_branches -= 1;
  uint o = (g_pixel * uint(u_path_branch_slots) + uint(g_branches)) * 10u;
  b = path_begin(vec3(u_branches[o], u_branches[o + 1u], u_branches[o + 2u]),
                 vec3(u_branches[o + 3u], u_branches[o + 4u], u_branches[o + 5u]));
  b.beta = vec3(u_branches[o + 6u], u_branches[o + 7u], u_branches[o + 8u]);
  b.scatterings = int(u_branches[o + 9u]);
  return true;
}

void add_stat(int k, uint v) {
  if (v == 0u) return;
  uint old = atomicAdd(u_path_stats[2 * k], v);
  if (old > 0xFFFFFFFFu - v) atomicAdd(u_path_stats[2 * k + 1], 1u);
}

// The path's state between dispatches, per pixel (PathState packed in five vec4, the branch count
// in its flags).
layout(std430, binding = CV_SSBO_PATH_STATE) buffer PathStateBuffer { vec4 u_state[]; };

void store_state(uint idx, PathState s, uint rng) {
  float flags = float(s.end + (s.done ? 4 : 0) + (s.prev_peak ? 8 : 0) + 16 * g_branches);
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
  g_branches = flags >> 4;
  s.beta = c.xyz;
  s.prev_sl = c.w;
  s.radiance = e.xyz;
  s.prev_si = e.w;
  s.absorbed = vec3(0.0);  // not kept on the GPU
  s.prev_d = f.xyz;
  s.px = ivec2(0);  // a path in flight has met its first vertex: its pixel's inputs are behind it
  rng = floatBitsToUint(f.w);
  return s;
}

void main() {
  load_march_params();
  ivec2 px = ivec2(gl_GlobalInvocationID.xy) + ivec2(0, u_row_offset);
  if (px.x >= u_size.x || px.y >= u_size.y) return;
  uint idx = uint(px.y) * uint(u_size.x) + uint(px.x);
  g_pixel = idx;
  g_branches = 0;
  g_without_room = 0u;
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
    s.px = px;  // the overlays' depth, colour and translucent fragments of this pixel
    if (misses) {
      TrackCounts c0 = track_counts();
      path_view_misses(s, c0);
    }
  } else {
    s = load_state(idx, rng);
    if (s.done && g_branches == 0) return;
  }
  TrackCounts c = track_counts();
  PathCounts pc = path_counts();
  // Vertices while the walk stays well inside the loop budget (a vertex may take tens of thousands
  // of iterations in a towering cell); the rest in the next dispatch. A path that has ended hands
  // on to its last branch, with the light gathered so far.
  uint budget = u_loop_budget ? 15000u : 0xFFFFFFFFu;
  for (;;) {
    if (!s.done) path_advance(s, rng, c, pc, budget);
    if (!s.done || g_branches == 0 || c.iterations >= budget) break;
    vec3 gathered = s.radiance;
    path_pop(s);
    s.radiance = gathered;
  }
  if (s.done && g_branches == 0) {
    vec3 v = vec3(s.radiance);
    // A sample that is not finite is counted and left out rather than spoiling the pixel.
    bool finite = !(any(isnan(v)) || any(isinf(v)));
    float l = finite ? dot(v, vec3(0.2126, 0.7152, 0.0722)) : 0.0;
    if (!finite) v = vec3(0.0);
    u_sums[2u * idx] += vec4(v, l);
    u_sums[2u * idx + 1u] += vec4(v * v, l * l);
    add_stat(0, 1u);
    add_stat(9, finite ? 0u : 1u);
  } else {
    add_stat(10, 1u);  // still in flight: the host dispatches again
  }
  store_state(idx, s, rng);
  add_stat(1, pc.vertices);
  add_stat(2, c.null_collisions);
  add_stat(3, c.lookups);
  add_stat(4, pc.truncated);
  add_stat(5, pc.roulette_killed);
  add_stat(6, pc.peak_samples);
  add_stat(7, c.exceeded);
  add_stat(11, g_without_room);
  // The loop iterations of this dispatch, as llvmpipe counts them (TrackCounts.iterations, and a
  // few of the setup's); past 65 535 every loop would have run once and stopped. Above 60 000 the
  // walk is counted as suspect.
  add_stat(8, u_loop_budget && c.iterations + 16u > 60000u ? 1u : 0u);
}
