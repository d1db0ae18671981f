// The GPU path tracer: the kernel's path (shaders/kernel/path.glsl), the one the CPU Monte Carlo
// reference runs in double, traced once per pixel per dispatch for sample u_sample, and added to
// per-pixel sums (radiance and its square, luminance and its square) from which the host takes the
// mean and its standard error (app/render/raymarcher.cpp, GpuRaymarcher::trace_paths).
// Mesa's llvmpipe ends every loop of an invocation after 65 535 iterations in all, silently: a
// sample whose walk came near that budget (u_loop_budget) is counted in the stats as suspect, so an
// image says when a path may have been cut.
#include "../common/physics.glsl"
#include "../kernel/bindings.glsl"
#include "../kernel/march_stats.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

uniform uint u_sample;            // the sample index of this dispatch, for every pixel
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
// truncated, roulette, peak samples, majorant exceeded, samples near the loop budget.
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

void main() {
  ivec2 px = ivec2(gl_GlobalInvocationID.xy) + ivec2(0, u_row_offset);
  if (px.x >= u_size.x || px.y >= u_size.y) return;
  uint idx = uint(px.y) * uint(u_size.x) + uint(px.x);
  // A counter-based stream per (seed, pixel, sample), as the CPU's PathRng is (another hash).
  uint rng = pcg_hash(u_seed * 0x9E3779B9u ^ pcg_hash(idx * 0x85EBCA6Bu + 0x632BE5ABu) ^ pcg_hash(u_sample * 0xC2B2AE35u + 0x27D4EB2Fu));
  MarchRay ray = march_ray(px);
  TrackCounts c = track_counts();
  PathCounts pc = path_counts();
  PathResult r = trace_path(ray.origin, ray.d, rng, c, pc);
  vec3 v = vec3(r.radiance);
  // A sample that is not finite is counted and left out rather than spoiling the pixel.
  bool finite = !(any(isnan(v)) || any(isinf(v)));
  float l = finite ? dot(v, vec3(0.2126, 0.7152, 0.0722)) : 0.0;
  if (!finite) v = vec3(0.0);
  u_sums[2u * idx] += vec4(v, l);
  u_sums[2u * idx + 1u] += vec4(v * v, l * l);
  // The loop iterations this sample took, as llvmpipe counts them: every tentative collision and
  // lookup, and a few loop tests per vertex.
  uint iterations = c.null_collisions + c.lookups + 8u * uint(r.scatterings) + 16u;
  add_stat(0, 1u);
  add_stat(1, uint(r.scatterings));
  add_stat(2, c.null_collisions);
  add_stat(3, c.lookups);
  add_stat(4, pc.truncated);
  add_stat(5, pc.roulette_killed);
  add_stat(6, pc.peak_samples);
  add_stat(7, c.exceeded);
  add_stat(8, u_loop_budget && iterations > 50000u ? 1u : 0u);
  add_stat(9, finite ? 0u : 1u);
}
