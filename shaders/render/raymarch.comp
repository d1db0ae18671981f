// The volumetric raymarcher on the spherical shell, in the form of the CPU reference
// (core/reference/raymarcher.cpp): shell intersection from the camera's altitude, the segment
// integral per step, a secondary march toward the sun with the Earth's shadow, and the octave sum
// with the approximate Mie phase for liquid and Henyey-Greenstein for ice; the sun's light reaches
// each sample through the atmosphere, with an ambient sky term. Both marches jump over empty bricks
// of the extinction pyramid and view steps through thick cloud are divided
// (shaders/common/march_control.glsl), as in the reference. Sky and globe are composited around the
// clouds in sky_ground.glsl. Output: rgb radiance, a = view transmittance (0 on the globe);
// per-frame counters in the Stats buffer.
//
// A frame takes several dispatches: pass 0 marches the view steps [u_step_begin, u_step_begin +
// u_step_count) of every ray (counted over both shell segments) and keeps the march's state in
// u_state_l and u_state_depth; pass 1 adds the air and the ground and writes u_out. The reason is
// Mesa's llvmpipe: all loops of one invocation share a budget of 65 535 iterations
// (LP_MAX_TGSI_LOOP_ITERATIONS in gallivm), after which every loop, the march's own included, runs
// its body once and stops, silently. A ray along the horizon spent it all in one dispatch
// (docs/physics.md, "GPU parity"); the host (app/render/raymarcher.cpp) sizes u_step_count so that
// one dispatch stays inside it.
#include "../common/physics.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 0) writeonly uniform image2D u_out;
layout(rgba32f, binding = 6) uniform image2D u_state_l;      // radiance so far, view transmittance
layout(rgba32f, binding = 7) uniform image2D u_state_depth;  // depth_w, depth_t, 1 once ended, next step
uniform int u_pass;        // 0: march a range of steps; 1: air and ground, then u_out
uniform int u_step_begin;  // pass 0: the first view step (counted over both shell segments)
uniform int u_step_count;  // pass 0: how many
layout(binding = 1) uniform sampler3D u_liquid;  // grid-mean extinction, 1/m (cf x in-cloud)
layout(binding = 2) uniform sampler3D u_ice;

uniform ivec2 u_size;
uniform int u_row_offset;     // first image row of this dispatch (long renders go in tiles of rows)
uniform vec3 u_cam_ecef;      // metres (float: 0.5 m near the Earth, +-32 m at 4e8 m; far rays re-anchor)
uniform float u_cam_alt;      // metres, from double on the CPU
uniform vec3 u_cam_up;        // local vertical at the camera
uniform vec3 u_forward;
uniform vec3 u_right;
uniform vec3 u_upv;
uniform float u_tan_half;     // of the horizontal field of view
uniform vec3 u_to_sun;
uniform vec3 u_irradiance;
uniform float u_r0;           // the sphere's radius
uniform vec3 u_grid_start;    // (lon deg, lat deg, alt m)
uniform vec3 u_grid_step;
uniform vec3 u_grid_count;
uniform bool u_wraps;
uniform bool u_global_lat;
uniform float u_view_step;
uniform vec2 u_layer;         // altitudes (m) between which the data holds cloud (core::cloud_layer)
uniform bool u_cloudless;     // no cloud anywhere: nothing to march
uniform bool u_sun_down;      // the whole cloud layer is in the Earth's shadow (core::layer_in_earth_shadow)
uniform int u_sun_steps;
uniform float u_sigma_max;      // the volume's largest extinction, 1/m (core::largest_extinction)
uniform float u_sun_step_tau;   // optical depth a sun step may hold at u_sigma_max (sun_march_steps)
uniform float u_sun_step_max;   // the longest a sun step may be, m (core::sun_step_limit_m)
uniform int u_octaves;
uniform vec3 u_octave_abc;
uniform bool u_octave_gate;   // weight octave i >= 1 by w^i from the column's optical depth (octaves.glsl)
// Vertical optical depth per grid column (core/volume/column_depth), fetched texel by texel.
layout(binding = 7) uniform sampler2D u_column_tau;
uniform float u_droplet_um;
uniform bool u_liquid_phase_hg;  // Henyey-Greenstein with the Mie fit's mean cosine instead of the fit
uniform float u_ice_g;
uniform int u_frame;  // -1: step middles; else the accumulation frame whose jitter places the samples
uniform bool u_blue_noise;  // the jitter from the blue-noise mask (blue_noise_jitter), else the hash
// The blue-noise mask (core/noise/blue_noise), rank / n^2 per texel, tiled over the image.
layout(binding = 6) uniform sampler2D u_jitter_mask;
uniform float u_ambient;      // strength of the isotropic sky light on clouds
uniform int u_sky_steps;      // steps of a sky in-scatter integral
uniform int u_atmo_sun_steps; // steps of an atmospheric transmittance toward the sun
uniform vec3 u_ground_albedo; // when there is no ground texture
uniform ivec2 u_ground_size;  // of the albedo texture; (0, 0): constant albedo
layout(binding = 5) uniform sampler2D u_ground;  // linear albedo, equirectangular

// Compile-time switches (GpuRaymarcher builds a program per combination): llvmpipe runs both sides
// of a branch under masks, so code switched off by a uniform would still cost every iteration.
#ifndef CV_SKIP_EMPTY
#define CV_SKIP_EMPTY 1
#endif
#ifndef CV_ADAPTIVE
#define CV_ADAPTIVE 0
#endif
// The air (sun colour through it, sky in-scatter, ambient sky light) and the globe (the ground where
// a ray meets it): a scene without them runs a program without their code.
#ifndef CV_ATMOSPHERE
#define CV_ATMOSPHERE 1
#endif
#ifndef CV_GLOBE
#define CV_GLOBE 1
#endif
const bool kSkipEmpty = CV_SKIP_EMPTY != 0;
const bool kAdaptive = CV_ADAPTIVE != 0;
const bool kAtmosphere = CV_ATMOSPHERE != 0;
const bool kGlobe = CV_GLOBE != 0;
uniform float u_max_step_tau;     // optical depth a view substep may hold (adaptive steps)
uniform float u_min_t;            // view rays stop below this transmittance
uniform float u_sun_tau_limit;    // sun marches stop past this optical depth (sun_march_tau_limit)
uniform int u_levels;             // pyramid levels, 0: no pyramid
uniform ivec3 u_bricks[4];        // bricks per axis, finest level first
uniform int u_level_nodes[4];     // grid nodes per brick side
uniform int u_level_offset[4];    // first brick of each level in u_min_max

// The extinction pyramid (core/volume/extinction_pyramid): (min, max) per brick, levels one after
// the other, x fastest.
layout(std430, binding = 3) readonly buffer Pyramid { vec2 u_min_max[]; };
// Per-frame counters (core::MarchStats), each as (low, high) 32-bit words.
layout(std430, binding = 4) buffer Stats { uint u_stats[]; };
const int kStatViewSamples = 0;
const int kStatViewSkipped = 1;
const int kStatBricksJumped = 2;
const int kStatSunSamples = 3;
const int kStatSunSkipped = 4;
const int kStatRaysMissed = 5;
const int kStatOctaveTerms = 6;
const int kStatOctaveTermsFull = 7;
const int kStatCount = 8;
uint g_stats[kStatCount] = uint[kStatCount](0u, 0u, 0u, 0u, 0u, 0u, 0u, 0u);

const float kDeg = 0.017453292519943295;

// Trilinear over texel centres, exactly as core/volume/sampler.cpp: no data reads as 0, and so do
// the border nodes (index -1 or n) a regional grid fades into.
float node(sampler3D tex, int x, int y, int z) {
  ivec3 n = ivec3(u_grid_count);
  return x < 0 || x >= n.x || y < 0 || y >= n.y ? 0.0 : texelFetch(tex, ivec3(x, y, z), 0).r;
}

float fetch(sampler3D tex, vec3 f) {
  ivec3 n = ivec3(u_grid_count);
  float wx;
  float wy;
  float wz;
  int x0 = volume_fetch_index(f.x, n.x, wx);
  int y0 = volume_fetch_index(f.y, n.y, wy);
  int z0 = volume_fetch_index(f.z, n.z, wz);
  int x1 = u_wraps ? (x0 + 1) % n.x : x0 + 1;
  int y1 = y0 + 1;
  int z1 = min(z0 + 1, n.z - 1);
  float c00 = mix(node(tex, x0, y0, z0), node(tex, x1, y0, z0), wx);
  float c10 = mix(node(tex, x0, y1, z0), node(tex, x1, y1, z0), wx);
  float c01 = mix(node(tex, x0, y0, z1), node(tex, x1, y0, z1), wx);
  float c11 = mix(node(tex, x0, y1, z1), node(tex, x1, y1, z1), wx);
  return mix(mix(c00, c10, wy), mix(c01, c11, wy), wz);
}

#ifdef CV_FEATURE_NOISE_DETAIL
// Sub-grid erosion (shaders/common/erosion.glsl), compiled in only when the amount is above 0.
layout(binding = 3) uniform sampler3D u_noise_low;   // Perlin-Worley, periodic, [0, 1]
layout(binding = 4) uniform sampler3D u_noise_high;  // Worley fBm, periodic, [0, 1]
uniform vec3 u_noise_anchor;       // metres, Earth-centred, a float-exact point near the data
uniform vec3 u_noise_anchor_frac;  // the anchor's position in tiles, from double on the CPU
uniform float u_noise_period;      // metres, the low-frequency tile
uniform float u_noise_amount;

// Trilinear with wrap-around, as NoiseTexture::sample in core/noise (x, then y, then z).
float fetch_noise(sampler3D tex, vec3 t) {
  int n = textureSize(tex, 0).x;
  ivec3 i0;
  ivec3 i1;
  vec3 w;
  noise_texel_pair(t.x, n, i0.x, i1.x, w.x);
  noise_texel_pair(t.y, n, i0.y, i1.y, w.y);
  noise_texel_pair(t.z, n, i0.z, i1.z, w.z);
  float c00 = mix(texelFetch(tex, ivec3(i0.x, i0.y, i0.z), 0).r, texelFetch(tex, ivec3(i1.x, i0.y, i0.z), 0).r, w.x);
  float c10 = mix(texelFetch(tex, ivec3(i0.x, i1.y, i0.z), 0).r, texelFetch(tex, ivec3(i1.x, i1.y, i0.z), 0).r, w.x);
  float c01 = mix(texelFetch(tex, ivec3(i0.x, i0.y, i1.z), 0).r, texelFetch(tex, ivec3(i1.x, i0.y, i1.z), 0).r, w.x);
  float c11 = mix(texelFetch(tex, ivec3(i0.x, i1.y, i1.z), 0).r, texelFetch(tex, ivec3(i1.x, i1.y, i1.z), 0).r, w.x);
  return mix(mix(c00, c10, w.y), mix(c01, c11, w.y), w.z);
}

// Erodes both extinctions at p, as Erosion::apply in core/reference/raymarcher.cpp does.
void erode_at(vec3 p, inout float sl, inout float si) {
  vec3 t = noise_tile_coords(p - u_noise_anchor, u_noise_anchor_frac, u_noise_period);
  float e = erosion_threshold(fetch_noise(u_noise_low, t), fetch_noise(u_noise_high, noise_high_coords(t)), u_noise_amount);
  float feature_m = noise_feature_m(u_noise_period);
  sl = erode_extinction(sl, e, feature_m);
  si = erode_extinction(si, e, feature_m);
}
#endif

// The column's vertical optical depth at p, bilinear with the 3-D fetch's horizontal rules
// (wrap, pole clamp, regional border 0), as core::ColumnDepth::at.
float column_tau(vec3 p) {
  vec3 g = ecef_to_sphere(p, u_r0);
  vec3 f;
  if (!volume_coords(g.x / kDeg, g.y / kDeg, u_grid_start.z, u_grid_start, u_grid_step, u_grid_count, u_wraps, u_global_lat, f)) return 0.0;
  ivec2 n = ivec2(u_grid_count.xy);
  float wx;
  float wy;
  int x0 = volume_fetch_index(f.x, n.x, wx);
  int y0 = volume_fetch_index(f.y, n.y, wy);
  int x1 = u_wraps ? (x0 + 1) % n.x : x0 + 1;
  int y1 = y0 + 1;
  float c00 = x0 < 0 || x0 >= n.x || y0 < 0 || y0 >= n.y ? 0.0 : texelFetch(u_column_tau, ivec2(x0, y0), 0).r;
  float c10 = x1 < 0 || x1 >= n.x || y0 < 0 || y0 >= n.y ? 0.0 : texelFetch(u_column_tau, ivec2(x1, y0), 0).r;
  float c01 = x0 < 0 || x0 >= n.x || y1 < 0 || y1 >= n.y ? 0.0 : texelFetch(u_column_tau, ivec2(x0, y1), 0).r;
  float c11 = x1 < 0 || x1 >= n.x || y1 < 0 || y1 >= n.y ? 0.0 : texelFetch(u_column_tau, ivec2(x1, y1), 0).r;
  return mix(mix(c00, c10, wx), mix(c01, c11, wx), wy);
}

float node_sum(int x, int y, int z) { return node(u_liquid, x, y, z) + node(u_ice, x, y, z); }

// The largest extinction (1/m, liquid + ice) that trilinear sampling can return in the grid cell
// around p (altitude alt_m): the largest of the 8 nodes fetch reads there; 0 outside the grid.
float cell_max(vec3 p, float alt_m) {
  vec3 g = ecef_to_sphere(p, u_r0);
  vec3 f;
  if (!volume_coords(g.x / kDeg, g.y / kDeg, alt_m, u_grid_start, u_grid_step, u_grid_count, u_wraps, u_global_lat, f)) return 0.0;
  ivec3 n = ivec3(u_grid_count);
  float w;
  int x0 = volume_fetch_index(f.x, n.x, w);
  int y0 = volume_fetch_index(f.y, n.y, w);
  int z0 = volume_fetch_index(f.z, n.z, w);
  int x1 = u_wraps ? (x0 + 1) % n.x : x0 + 1;
  int y1 = y0 + 1;
  int z1 = min(z0 + 1, n.z - 1);
  // Written out, not looped: see space_at on llvmpipe's loop budget.
  float m = max(max(node_sum(x0, y0, z0), node_sum(x1, y0, z0)), max(node_sum(x0, y1, z0), node_sum(x1, y1, z0)));
  m = max(m, max(max(node_sum(x0, y0, z1), node_sum(x1, y0, z1)), max(node_sum(x0, y1, z1), node_sum(x1, y1, z1))));
  return m;
}

// The medium at Earth-centred point p whose altitude alt_m the caller knows better than |p| - r0
// (ray_altitude): latitude and longitude come from p.
void medium_at(vec3 p, float alt_m, out float sl, out float si) {
  sl = 0.0;
  si = 0.0;
  vec3 g = ecef_to_sphere(p, u_r0);
  vec3 f;
  if (!volume_coords(g.x / kDeg, g.y / kDeg, alt_m, u_grid_start, u_grid_step, u_grid_count, u_wraps, u_global_lat, f)) return;
  sl = fetch(u_liquid, f);
  si = fetch(u_ice, f);
#ifdef CV_FEATURE_NOISE_DETAIL
  if (sl + si > 0.0) erode_at(p, sl, si);
#endif
}

// One level of the pyramid at grid index g (see space_at): true when its brick there is empty, with
// the distance the ray may jump; else the brick's largest extinction, and the distance it holds.
bool level_empty(int l, vec3 g, float lat, float r, float mu_up, out float extent_m, out float brick_max) {
  vec3 nb = vec3(u_bricks[l]);
  float nodes = float(u_level_nodes[l]);
  vec3 b = march_brick(g, nodes);
  extent_m = march_brick_exit_m(lat, r, mu_up, g, b, nodes, nb, u_grid_start, u_grid_step, u_global_lat, u_r0);
  brick_max = 0.0;
  if (march_brick_inside(b, nb)) {
    ivec3 bi = ivec3(b);
    brick_max = u_min_max[u_level_offset[l] + (bi.z * u_bricks[l].y + bi.y) * u_bricks[l].x + bi.x].y;
  }
  return !(brick_max > 0.0);
}

// What a ray along dir learns about the space around p, at altitude alt_m
// (core::ExtinctionPyramid::at): true when
// empty, with the distance (m) it may jump; else the finest brick's largest extinction (1/m) and
// the distance over which that holds. The levels are visited without a loop: llvmpipe ends the
// loops of an invocation after 65535 iterations in all (LP_MAX_TGSI_LOOP_ITERATIONS, shared by
// every loop), and this runs inside both marches.
bool space_at(vec3 p, float alt_m, vec3 dir, out float extent_m, out float sigma_max) {
  extent_m = 0.0;
  sigma_max = 0.0;
  if (u_levels <= 0) return false;
  vec3 g3 = ecef_to_sphere(p, u_r0);
  float lat = g3.x / kDeg;
  float r = u_r0 + alt_m;
  float mu_up = dot(dir, p) / length(p);
  vec3 g = march_grid_index(lat, g3.y / kDeg, alt_m, u_grid_start, u_grid_step, u_grid_count, u_wraps, u_global_lat);
  float unused;
  if (u_levels > 3 && level_empty(3, g, lat, r, mu_up, extent_m, unused)) return true;
  if (u_levels > 2 && level_empty(2, g, lat, r, mu_up, extent_m, unused)) return true;
  if (u_levels > 1 && level_empty(1, g, lat, r, mu_up, extent_m, unused)) return true;
  return level_empty(0, g, lat, r, mu_up, extent_m, sigma_max);
}

// Optical depth of the clouds from p (at altitude alt_p, m) toward the sun, whose cosine and sine
// with the local up at p are mu_sun and nu_sun: sun_march_steps per shell segment, empty bricks jumped,
// stopped past u_sun_tau_limit. The shell's (at most two) segments and their steps run as one loop
// (see space_at on loop counts). The cloud samples and the ground's shadow both use it.
float cloud_sun_depth(vec3 p, float alt_p, float mu_sun, float nu_sun) {
  float hb = u_layer.x;
  float ht = u_layer.y;
  float tau_sun = 0.0;
  vec4 sseg;
  int sn = u_cloudless ? 0 : ray_shell_rel_nu(u_r0, alt_p, mu_sun, nu_sun, hb, ht, sseg);
  // Steps per segment as core/reference/raymarcher.cpp sun_depth: more where the segment is long
  // (a low sun), fewer where the volume is thin.
  int n0 = sn > 0 ? sun_march_steps(u_sigma_max, sseg.y - sseg.x, u_sun_step_tau, u_sun_steps, u_sun_step_max) : 0;
  int n1 = sn > 1 ? sun_march_steps(u_sigma_max, sseg.w - sseg.z, u_sun_step_tau, u_sun_steps, u_sun_step_max) : 0;
  int total = n0 + n1;
  float known_end = -1.0;  // what the pyramid said holds below this distance into the segment
  for (int k = 0; k < total;) {
    int q = k < n0 ? 0 : 1;
    int nq = q == 0 ? n0 : n1;
    int j = q == 0 ? k : k - n0;
    if (j == 0) known_end = -1.0;
    float s0 = q == 0 ? sseg.x : sseg.z;
    float s1 = q == 0 ? sseg.y : sseg.w;
    float ds = (s1 - s0) / float(nq);
    float t_rel = (float(j) + 0.5) * ds;
    vec3 ps = p + (s0 + t_rel) * u_to_sun;
    float alt_s = ray_altitude(u_r0, alt_p, mu_sun, s0 + t_rel);
    if (kSkipEmpty && !(t_rel < known_end)) {
      float extent;
      float smax;
      if (space_at(ps, alt_s, u_to_sun, extent, smax)) {
        int next = min(march_resume_index(j, extent, ds), nq);
        g_stats[kStatSunSkipped] += uint(next - j);
        g_stats[kStatBricksJumped] += next - j > 1 ? 1u : 0u;
        k += next - j;
        continue;
      }
      known_end = t_rel + extent;
    }
    float a;
    float b;
    medium_at(ps, alt_s, a, b);
    tau_sun += (a + b) * ds;
    g_stats[kStatSunSamples] += 1u;
    ++k;
    if (tau_sun > u_sun_tau_limit) {
      g_stats[kStatSunSkipped] += uint(total - k);
      break;
    }
  }
  return tau_sun;
}

// One view sample at p (altitude alt_p, distance t along the ray) standing for a step of ds:
// in-scattered light (sun through the air, ambient sky light), attenuation, and where the light
// was taken out of the view (depth_w, depth_t: the cloud's mean depth for the sky around it).
void march_sample(vec3 p, float alt_p, float t, float ds, float mu, MieParams mie, inout vec3 radiance, inout float t_view,
                  inout float depth_w, inout float depth_t) {
  float sl;
  float si;
  medium_at(p, alt_p, sl, si);
  g_stats[kStatViewSamples] += 1u;
  float sigma = sl + si;
  if (sigma <= 0.0) return;
  vec3 up_p = normalize(p);
  float mu_sun = dot(u_to_sun, up_p);
  float nu_sun = length(cross(u_to_sun, up_p));
  float e0;
  float e1;
  bool lit = !u_sun_down && !(ray_sphere_rel_nu(u_r0, alt_p, mu_sun, nu_sun, 0.0, e0, e1) && e1 > 0.0);
  float tau_sun = lit ? cloud_sun_depth(p, alt_p, mu_sun, nu_sun) : 0.0;
  // Sunlight reaches the sample through the air (reddened when low), and the sky lights it too.
  vec3 sun_air = kAtmosphere && lit ? atmo_transmittance(u_r0, alt_p, mu_sun, nu_sun, u_atmo_sun_steps) : vec3(1.0);
  vec3 ambient = kAtmosphere ? u_ambient * sky_irradiance(sun_air, mu_sun) * (sigma / CV_TWO_PI) : vec3(0.0);
  // The octave sums, only where the sun shines (llvmpipe runs masked code: a ternary would not save them).
  float scatter = 0.0;
  if (lit) {
    // The octave gate (octaves.glsl): w from the column's optical depth; off, the classic sum.
    bool gate = u_octave_gate && u_octaves > 1;
    float w = gate ? octave_gate_weight(column_tau(p)) : 1.0;
    float tol = gate ? CV_OCTAVE_GATE_TOL : 0.0;
    vec3 abc = u_octave_abc;
    g_stats[kStatOctaveTerms] += uint(octave_terms(u_octaves, abc.y, w, tol));
    g_stats[kStatOctaveTermsFull] += uint(max(u_octaves, 0));
    float liquid = u_liquid_phase_hg ? ms_octaves_hg_gated(sl, mu, mie_mean_cosine(mie), tau_sun, u_octaves, abc.x, abc.y, abc.z, w, tol)
                                     : ms_octaves_mie_gated(sl, mu, mie, tau_sun, u_octaves, abc.x, abc.y, abc.z, w, tol);
    scatter = liquid + ms_octaves_hg_gated(si, mu, u_ice_g, tau_sun, u_octaves, abc.x, abc.y, abc.z, w, tol);
  }
  radiance += t_view * segment_integral(u_irradiance * (sun_air * scatter + ambient), sigma, ds);
  // The light the step takes out of the view, t_view (1 - exp(-sigma ds)), without the
  // cancellation of t_view - t_next: in float that is a multiple of 6e-8, which left faint cloud
  // with a mean depth tens of kilometres off the CPU's (as in the reference raymarcher).
  float taken = t_view * segment_integral(sigma, sigma, ds);
  depth_w += taken;
  depth_t += taken * t;
  t_view *= transmittance(sigma * ds);
}

// Adds this invocation's counts to the frame's, carrying into the high words.
// Where in its step a pixel's view samples lie (0..1), as core/reference/raymarcher.cpp step_offset.
float step_offset(ivec2 px) {
  if (u_frame < 0) return 0.5;
  if (!u_blue_noise) return step_jitter(uint(px.x), uint(px.y), uint(u_frame));
  ivec2 n = textureSize(u_jitter_mask, 0);
  return blue_noise_jitter(texelFetch(u_jitter_mask, px % n, 0).r, uint(u_frame));
}

void flush_stats() {
  for (int k = 0; k < kStatCount; ++k) {
    if (g_stats[k] == 0u) continue;
    uint old = atomicAdd(u_stats[2 * k], g_stats[k]);
    if (old > 0xFFFFFFFFu - g_stats[k]) atomicAdd(u_stats[2 * k + 1], 1u);
  }
}

#include "sky_ground.glsl"

void main() {
  ivec2 px = ivec2(gl_GlobalInvocationID.xy) + ivec2(0, u_row_offset);
  if (px.x >= u_size.x || px.y >= u_size.y) return;
  float x = (2.0 * (float(px.x) + 0.5) / float(u_size.x) - 1.0) * u_tan_half;
  float y = (1.0 - 2.0 * (float(px.y) + 0.5) / float(u_size.y)) * u_tan_half * float(u_size.y) / float(u_size.x);
  vec3 d = normalize(u_forward + x * u_right + y * u_upv);
  float hb = u_layer.x;
  float ht = u_layer.y;
  // A camera above the shell marches from where its ray enters the shell, placed on the exact
  // sphere: positions near the Earth keep their digits (at 4e8 m a float position is +-32 m), and
  // nu = |d x up| keeps near-nadir and near-tangent rays right where mu rounds to +-1.
  vec3 origin = u_cam_ecef;
  float h = u_cam_alt;
  vec3 up = u_cam_up;
  float mu_up = dot(d, up);
  float nu_up = length(cross(d, up));
  bool in_shell = true;  // false: the ray misses the cloud shell (the sky may still show)
  if (h > ht) {
    float e0;
    float e1;
    if (!ray_sphere_rel_nu(u_r0, h, mu_up, nu_up, ht, e0, e1) || e1 < 0.0) {
      in_shell = false;
    } else if (e0 > 0.0) {
      origin = normalize(origin + e0 * d) * (u_r0 + ht);
      h = ht;
      up = normalize(origin);
      mu_up = dot(d, up);
      nu_up = length(cross(d, up));
    }
  }
  vec4 seg;
  int n = in_shell && !u_cloudless ? ray_shell_rel_nu(u_r0, h, mu_up, nu_up, hb, ht, seg) : 0;
  float tg0;
  float tg1;
  float t_ground = ray_sphere_rel_nu(u_r0, h, mu_up, nu_up, 0.0, tg0, tg1) && tg1 > 0.0 ? max(tg0, 0.0) : 3.0e38;
  float mu = dot(d, u_to_sun);
  MieParams mie = mie_params(u_droplet_um);
  bool first = u_pass == 0 && u_step_begin == 0;
  vec4 state_l = first ? vec4(0.0, 0.0, 0.0, 1.0) : imageLoad(u_state_l, px);
  vec4 state_depth = first ? vec4(0.0) : imageLoad(u_state_depth, px);
  vec3 radiance = state_l.rgb;
  float t_view = state_l.a;
  float depth_w = state_depth.x;  // sum over steps of the light each takes out of the view: where the cloud is
  float depth_t = state_depth.y;
  // The first step this dispatch takes (counted over both segments): a jump of the previous
  // dispatch may have carried past the start of this one's range.
  int next_step = max(u_step_begin, int(state_depth.w));
  int range_end = u_step_begin + u_step_count;
  int base = 0;  // steps of the segments before segment k
  bool crossed = false;
  for (int k = 0; k < (u_pass == 0 && state_depth.z == 0.0 ? n : 0) && t_view > u_min_t; ++k) {
    float t_start = k == 0 ? seg.x : seg.z;
    float t_end = min(k == 0 ? seg.y : seg.w, t_ground);
    if (!(t_end > t_start)) continue;
    crossed = true;
    int steps = max(1, int(ceil((t_end - t_start) / u_view_step)));
    float dt = (t_end - t_start) / float(steps);
    float offset = step_offset(px);
    int i_end = min(range_end - base, steps);
    int i = max(next_step - base, 0);
    base += steps;
    if (i >= i_end) continue;
    // What the pyramid said about the brick ahead: valid for sample distances below known_end.
    float known_end = -1.0;
    float sigma_max = 0.0;
    // One loop iteration per sample, substeps included (see space_at on loop counts): sample j of
    // the substeps of step i.
    int j = 0;
    int substeps = 1;
    while (i < i_end && t_view > u_min_t) {
      if (j == 0) {
        float t_rel = (float(i) + offset) * dt;
        if ((kSkipEmpty || kAdaptive) && !(t_rel < known_end)) {
          float extent;
          float t_q = t_start + t_rel;
          bool empty = space_at(origin + t_q * d, ray_altitude(u_r0, h, mu_up, t_q), d, extent, sigma_max);
          if (empty && kSkipEmpty) {
            int next = march_resume_index(i, extent, dt);
            g_stats[kStatViewSkipped] += uint(min(next, steps) - i);
            g_stats[kStatBricksJumped] += next - i > 1 ? 1u : 0u;
            i = next;
            next_step = base - steps + min(next, steps);  // where the march goes on, maybe in a later dispatch
            continue;
          }
          known_end = t_rel + extent;
        }
        substeps = 1;
        if (kAdaptive && march_substeps(sigma_max, dt, u_max_step_tau) > 1) {
          // The brick's bound is loose (a brick spans 4 cells and more): bound the step by the
          // cells at its two ends instead, so only steps near thick cloud are divided.
          float ta = t_start + float(i) * dt;
          float tb = t_start + float(i + 1) * dt;
          float bound = max(cell_max(origin + ta * d, ray_altitude(u_r0, h, mu_up, ta)),
                            cell_max(origin + tb * d, ray_altitude(u_r0, h, mu_up, tb)));
          substeps = march_substeps(bound, dt, u_max_step_tau);
        }
      }
      float ds = dt / float(substeps);
      float t = t_start + (float(i) + (float(j) + offset) / float(substeps)) * dt;
      march_sample(origin + t * d, ray_altitude(u_r0, h, mu_up, t), t, ds, mu, mie, radiance, t_view, depth_w, depth_t);
      if (++j == substeps) {
        j = 0;
        ++i;
        next_step = base - steps + i;
      }
    }
  }
  if (u_pass == 0) {
    if (first) g_stats[kStatRaysMissed] += crossed ? 0u : 1u;
    flush_stats();
    bool ended = !(t_view > u_min_t) || state_depth.z > 0.0 || range_end >= base;
    imageStore(u_state_l, px, vec4(radiance, t_view));
    imageStore(u_state_depth, px, vec4(depth_w, depth_t, ended ? 1.0 : 0.0, float(next_step)));
    return;
  }
  if (kAtmosphere || kGlobe) {
    // The cloud stands, for the air around it, at the mean depth of the light it takes out.
    vec3 p_cloud = origin + (depth_w > 0.0 ? depth_t / depth_w : 0.0) * d;
    imageStore(u_out, px, sky_and_ground(d, radiance, t_view, depth_w > 1e-6, p_cloud));
  } else {
    imageStore(u_out, px, vec4(radiance, t_view));
  }
}
