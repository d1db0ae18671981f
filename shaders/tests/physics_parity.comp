// Evaluates the physics core on a grid of cases so tests can compare the GPU with the C++ build of
// the same code (tests/render/physics_parity_test.cpp holds the case list and the C++ side).
#include "../common/physics.glsl"
#include "physics_parity_ids.glsl"

layout(local_size_x = 64) in;

struct ParityCase {
  vec4 in0;
  vec4 in1;
  uvec4 meta;  // x: function id, y: integer argument (octave count, rng seed)
};
struct ParityResult {
  vec4 a;
  vec4 b;
  uvec4 u;
};

layout(std430, binding = 0) readonly buffer Cases { ParityCase cases[]; };
layout(std430, binding = 1) writeonly buffer Results { ParityResult results[]; };

uniform uint u_count;

void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= u_count) return;
  ParityCase c = cases[i];
  ParityResult r;
  r.a = vec4(0.0);
  r.b = vec4(0.0);
  r.u = uvec4(0u);
  uint rng = c.meta.y;
  float pdf = 0.0;
  float t0 = 0.0;
  float t1 = 0.0;
  vec3 e;
  vec3 n;
  vec3 up;
  vec4 seg;
  switch (c.meta.x) {
    case PARITY_ISOTROPIC: r.a.x = phase_isotropic(); break;
    case PARITY_HG: r.a.x = phase_hg(c.in0.x, c.in0.y); break;
    case PARITY_CORNETTE_SHANKS: r.a.x = phase_cornette_shanks(c.in0.x, c.in0.y); break;
    case PARITY_SCHLICK: r.a.x = phase_schlick(c.in0.x, schlick_k_from_g(c.in0.y)); break;
    case PARITY_RAYLEIGH: r.a.x = phase_rayleigh(c.in0.x); break;
    case PARITY_DRAINE: r.a.x = phase_draine(c.in0.x, c.in0.y, c.in0.z); break;
    case PARITY_DUAL_HG: r.a.x = phase_dual_hg(c.in0.x, c.in0.y, c.in0.z, c.in0.w); break;
    case PARITY_MIE_PARAMS: {
      MieParams p = mie_params(c.in0.x);
      r.a = vec4(p.g_hg, p.g_d, p.alpha, p.w_d);
      r.b.x = p.c_hg;
      break;
    }
    case PARITY_MIE_PHASE: r.a.x = phase_mie(c.in0.x, mie_params(c.in0.y)); break;
    case PARITY_MIE_MEAN_COSINE: r.a.x = mie_mean_cosine(mie_params(c.in0.x)); break;
    case PARITY_HG_SAMPLE_MU: r.a.x = hg_sample_mu(c.in0.x, c.in0.y); break;
    case PARITY_SAMPLE_HG:
      r.a.xyz = sample_hg(c.in0.xyz, c.in0.w, c.in1.xy, pdf);
      r.a.w = pdf;
      break;
    case PARITY_SAMPLE_DRAINE:
      r.a.xyz = sample_draine(c.in0.xyz, c.in0.w, c.in1.x, rng, pdf);
      r.a.w = pdf;
      r.u.x = rng;
      break;
    case PARITY_SAMPLE_MIE:
      r.a.xyz = sample_mie(c.in0.xyz, mie_params(c.in0.w), rng, pdf);
      r.a.w = pdf;
      r.u.x = rng;
      break;
    case PARITY_SAMPLE_DUAL_HG:
      r.a.xyz = sample_dual_hg(c.in0.xyz, c.in0.w, c.in1.x, c.in1.y, rng, pdf);
      r.a.w = pdf;
      r.u.x = rng;
      break;
    case PARITY_SEGMENT_FACTOR: r.a.x = segment_factor(c.in0.x); break;
    case PARITY_SEGMENT_INTEGRAL: r.a.x = segment_integral(c.in0.x, c.in0.y, c.in0.z); break;
    case PARITY_TRANSMITTANCE: r.a.x = transmittance(c.in0.x); break;
    case PARITY_OCTAVES_HG:
      r.a.x = ms_octaves_hg(c.in0.x, c.in0.y, c.in0.z, c.in0.w, int(c.meta.y), c.in1.x, c.in1.y, c.in1.z); break;
    case PARITY_OCTAVES_MIE:
      r.a.x = ms_octaves_mie(c.in0.x, c.in0.y, mie_params(c.in0.z), c.in0.w, int(c.meta.y), c.in1.x, c.in1.y,
                             c.in1.z);
      break;
    case PARITY_RAY_SPHERE_REL:
      r.u.x = ray_sphere_rel(c.in0.x, c.in0.y, c.in0.z, c.in0.w, t0, t1) ? 1u : 0u;
      r.a.xy = vec2(t0, t1);
      break;
    case PARITY_RAY_SHELL_REL:
      r.u.x = uint(ray_shell_rel(c.in0.x, c.in0.y, c.in0.z, c.in0.w, c.in1.x, seg));
      r.a = seg;
      break;
    case PARITY_RAY_SPHERE:
      r.u.x = ray_sphere(c.in0.xyz, c.in1.xyz, c.in0.w, t0, t1) ? 1u : 0u;
      r.a.xy = vec2(t0, t1);
      break;
    case PARITY_SPHERE_TO_ECEF: r.a.xyz = sphere_to_ecef(c.in0.x, c.in0.y, c.in0.z, c.in0.w); break;
    case PARITY_ECEF_TO_SPHERE: r.a.xyz = ecef_to_sphere(c.in0.xyz, c.in0.w); break;
    case PARITY_ENU_FRAME:
      enu_frame(c.in0.x, c.in0.y, e, n, up);
      r.a.xyz = e;
      r.b.xyz = n;
      break;
    case PARITY_GEOPOTENTIAL: r.a.x = geopotential_to_height_m(c.in0.x, c.in0.y); break;
    case PARITY_PCG_HASH: r.u.x = pcg_hash(c.meta.y); break;
    case PARITY_TWO_PROD: r.a.xy = two_prod(c.in0.x, c.in0.y); break;
    case PARITY_DIRECTION_AROUND: r.a.xyz = direction_around(c.in0.xyz, c.in1.x, c.in1.y); break;
    case PARITY_VOLUME_COORDS: {
      // in0 = (lat, lon, alt, wraps); in1 = grid start x/y/z and count x packed below by the test.
      vec3 f;
      bool wraps = c.in0.w > 0.5;
      r.u.x = volume_coords(c.in0.x, c.in0.y, c.in0.z, vec3(160.0, 25.0, 0.0), vec3(0.5, 0.5, 500.0),
                            wraps ? vec3(720.0, 81.0, 33.0) : vec3(121.0, 81.0, 33.0), wraps, false, f) ? 1u : 0u;
      r.a.xyz = f;
      break;
    }
    case PARITY_STEP_JITTER: r.a.x = step_jitter(uint(c.in0.x), uint(c.in0.y), c.meta.y); break;
    case PARITY_BLUE_NOISE_JITTER: r.a.x = blue_noise_jitter(c.in0.x, c.meta.y); break;
    case PARITY_RAY_ALTITUDE: r.a.x = ray_altitude(c.in0.x, c.in0.y, c.in0.z, c.in0.w); break;
    case PARITY_NOISE_TILE_COORDS: r.a.xyz = noise_tile_coords(c.in0.xyz, c.in1.xyz, c.in0.w); break;
    case PARITY_NOISE_TEXEL_PAIR: {
      int i0;
      int i1;
      noise_texel_pair(c.in0.x, int(c.meta.y), i0, i1, r.a.x);
      r.u.xy = uvec2(i0, i1);
      break;
    }
    case PARITY_EROSION:
      // in0 = (sigma, n_low, n_high, amount), in1.x = feature metres: the threshold and the fraction kept.
      r.a.x = erosion_threshold(c.in0.y, c.in0.z, c.in0.w);
      r.a.y = erode_extinction(c.in0.x, r.a.x, c.in1.x) / c.in0.x;
      break;
    case PARITY_FRESNEL_WATER: r.a.x = fresnel_water(c.in0.x); break;
    case PARITY_SEA_GLINT: r.a.x = sea_glint_brdf(c.in0.x, c.in0.y, c.in0.z, c.in0.w); break;
    case PARITY_WATER_RADIANCE:
      // in0 = (mu_s, mu_v, nu_sv, mss); the sun's transmittance and the sky light fixed.
      r.a.xyz = water_radiance(CV_WATER_BODY, c.in0.x, c.in0.y, c.in0.z, c.in0.w, vec3(0.8, 0.7, 0.6), vec3(0.02, 0.03, 0.05));
      break;
    default: r.u.w = 1u; break;
  }
  results[i] = r;
}
