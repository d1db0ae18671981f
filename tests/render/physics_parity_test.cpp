// GPU parity: a compute shader evaluates every physics function on a parameter grid (llvmpipe in
// CI, any GPU elsewhere) and the results must match the C++ float build of the same code.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "physics/physics.hpp"
#include "render/context.hpp"
#include "render/shader_loader.hpp"

#include "../../shaders/tests/physics_parity_ids.glsl"

namespace {
using namespace cv::render;
namespace f32 = cv::physics::f32;
using glm::uvec4;
using glm::vec3;
using glm::vec4;

struct Case {
  vec4 in0{0.0f};
  vec4 in1{0.0f};
  uvec4 meta{0u};
};
struct Result {
  vec4 a{0.0f};
  vec4 b{0.0f};
  uvec4 u{0u};
};
// std430 layout of ParityCase / ParityResult in shaders/tests/physics_parity.comp.
static_assert(sizeof(Case) == 48 && offsetof(Case, in1) == 16 && offsetof(Case, meta) == 32);
static_assert(sizeof(Result) == 48 && offsetof(Result, b) == 16 && offsetof(Result, u) == 32);

// The C++ side of the shader's switch.
Result eval(const Case& c) {
  Result r;
  f32::uint rng = c.meta.y;
  float pdf = 0, t0 = 0, t1 = 0;
  vec3 e, n, up;
  vec4 seg;
  switch (c.meta.x) {
    case PARITY_ISOTROPIC: r.a.x = f32::phase_isotropic(); break;
    case PARITY_HG: r.a.x = f32::phase_hg(c.in0.x, c.in0.y); break;
    case PARITY_CORNETTE_SHANKS: r.a.x = f32::phase_cornette_shanks(c.in0.x, c.in0.y); break;
    case PARITY_SCHLICK: r.a.x = f32::phase_schlick(c.in0.x, f32::schlick_k_from_g(c.in0.y)); break;
    case PARITY_RAYLEIGH: r.a.x = f32::phase_rayleigh(c.in0.x); break;
    case PARITY_DRAINE: r.a.x = f32::phase_draine(c.in0.x, c.in0.y, c.in0.z); break;
    case PARITY_DUAL_HG: r.a.x = f32::phase_dual_hg(c.in0.x, c.in0.y, c.in0.z, c.in0.w); break;
    case PARITY_MIE_PARAMS: {
      const f32::MieParams p = f32::mie_params(c.in0.x);
      r.a = vec4(p.g_hg, p.g_d, p.alpha, p.w_d);
      r.b.x = p.c_hg;
      break;
    }
    case PARITY_MIE_PHASE: r.a.x = f32::phase_mie(c.in0.x, f32::mie_params(c.in0.y)); break;
    case PARITY_MIE_MEAN_COSINE: r.a.x = f32::mie_mean_cosine(f32::mie_params(c.in0.x)); break;
    case PARITY_HG_SAMPLE_MU: r.a.x = f32::hg_sample_mu(c.in0.x, c.in0.y); break;
    // Each sampler sets pdf, so it is read only after the call.
    case PARITY_SAMPLE_HG:
      r.a = vec4(f32::sample_hg(vec3(c.in0), c.in0.w, glm::vec2(c.in1), pdf), 0.0f);
      r.a.w = pdf;
      break;
    case PARITY_SAMPLE_DRAINE:
      r.a = vec4(f32::sample_draine(vec3(c.in0), c.in0.w, c.in1.x, rng, pdf), 0.0f);
      r.a.w = pdf;
      r.u.x = rng;
      break;
    case PARITY_SAMPLE_MIE:
      r.a = vec4(f32::sample_mie(vec3(c.in0), f32::mie_params(c.in0.w), rng, pdf), 0.0f);
      r.a.w = pdf;
      r.u.x = rng;
      break;
    case PARITY_SAMPLE_DUAL_HG:
      r.a = vec4(f32::sample_dual_hg(vec3(c.in0), c.in0.w, c.in1.x, c.in1.y, rng, pdf), 0.0f);
      r.a.w = pdf;
      r.u.x = rng;
      break;
    case PARITY_SEGMENT_FACTOR: r.a.x = f32::segment_factor(c.in0.x); break;
    case PARITY_SEGMENT_INTEGRAL: r.a.x = f32::segment_integral(c.in0.x, c.in0.y, c.in0.z); break;
    case PARITY_TRANSMITTANCE: r.a.x = f32::transmittance(c.in0.x); break;
    case PARITY_OCTAVES_HG:
      r.a.x = f32::ms_octaves_hg(c.in0.x, c.in0.y, c.in0.z, c.in0.w, int(c.meta.y), c.in1.x, c.in1.y, c.in1.z);
      break;
    case PARITY_OCTAVES_MIE:
      r.a.x = f32::ms_octaves_mie(c.in0.x, c.in0.y, f32::mie_params(c.in0.z), c.in0.w, int(c.meta.y), c.in1.x,
                                  c.in1.y, c.in1.z);
      break;
    case PARITY_RAY_SPHERE_REL:
      r.u.x = f32::ray_sphere_rel(c.in0.x, c.in0.y, c.in0.z, c.in0.w, t0, t1) ? 1u : 0u;
      r.a.x = t0;
      r.a.y = t1;
      break;
    case PARITY_RAY_SHELL_REL:
      r.u.x = static_cast<unsigned>(f32::ray_shell_rel(c.in0.x, c.in0.y, c.in0.z, c.in0.w, c.in1.x, seg));
      r.a = seg;
      break;
    case PARITY_RAY_SPHERE:
      r.u.x = f32::ray_sphere(vec3(c.in0), vec3(c.in1), c.in0.w, t0, t1) ? 1u : 0u;
      r.a.x = t0;
      r.a.y = t1;
      break;
    case PARITY_SPHERE_TO_ECEF: r.a = vec4(f32::sphere_to_ecef(c.in0.x, c.in0.y, c.in0.z, c.in0.w), 0); break;
    case PARITY_ECEF_TO_SPHERE: r.a = vec4(f32::ecef_to_sphere(vec3(c.in0), c.in0.w), 0); break;
    case PARITY_ENU_FRAME:
      f32::enu_frame(c.in0.x, c.in0.y, e, n, up);
      r.a = vec4(e, 0);
      r.b = vec4(n, 0);
      break;
    case PARITY_GEOPOTENTIAL: r.a.x = f32::geopotential_to_height_m(c.in0.x, c.in0.y); break;
    case PARITY_PCG_HASH: r.u.x = f32::pcg_hash(c.meta.y); break;
    case PARITY_TWO_PROD: {
      const auto p = f32::two_prod(c.in0.x, c.in0.y);
      r.a.x = p.x;
      r.a.y = p.y;
      break;
    }
    case PARITY_DIRECTION_AROUND: r.a = vec4(f32::direction_around(vec3(c.in0), c.in1.x, c.in1.y), 0); break;
    case PARITY_VOLUME_COORDS: {
      glm::vec3 f;
      const bool wraps = c.in0.w > 0.5f;
      r.u.x = f32::volume_coords(c.in0.x, c.in0.y, c.in0.z, vec3(160.0f, 25.0f, 0.0f), vec3(0.5f, 0.5f, 500.0f),
                                 wraps ? vec3(720.0f, 81.0f, 33.0f) : vec3(121.0f, 81.0f, 33.0f), wraps, false, f)
                  ? 1u : 0u;
      r.a = vec4(f, 0.0f);
      break;
    }
    case PARITY_STEP_JITTER: r.a.x = f32::step_jitter(static_cast<f32::uint>(c.in0.x), static_cast<f32::uint>(c.in0.y), c.meta.y); break;
    case PARITY_BLUE_NOISE_JITTER: r.a.x = f32::blue_noise_jitter(c.in0.x, c.meta.y); break;
    case PARITY_RAY_ALTITUDE: r.a.x = f32::ray_altitude(c.in0.x, c.in0.y, c.in0.z, c.in0.w); break;
    case PARITY_NOISE_TILE_COORDS: r.a = vec4(f32::noise_tile_coords(vec3(c.in0), vec3(c.in1), c.in0.w), 0); break;
    case PARITY_NOISE_TEXEL_PAIR: {
      int i0, i1;
      f32::noise_texel_pair(c.in0.x, static_cast<int>(c.meta.y), i0, i1, r.a.x);
      r.u.x = static_cast<unsigned>(i0);
      r.u.y = static_cast<unsigned>(i1);
      break;
    }
    case PARITY_EROSION:
      r.a.x = f32::erosion_threshold(c.in0.y, c.in0.z, c.in0.w);
      r.a.y = f32::erode_extinction(c.in0.x, r.a.x, c.in1.x) / c.in0.x;
      break;
    case PARITY_FRESNEL_WATER: r.a.x = f32::fresnel_water(c.in0.x); break;
    case PARITY_SEA_GLINT: r.a.x = f32::sea_glint_brdf(c.in0.x, c.in0.y, c.in0.z, c.in0.w); break;
    case PARITY_WATER_RADIANCE:
      r.a = vec4(f32::water_radiance(f32::CV_WATER_BODY, c.in0.x, c.in0.y, c.in0.z, c.in0.w, vec3(0.8f, 0.7f, 0.6f),
                                     vec3(0.02f, 0.03f, 0.05f)),
                 0.0f);
      break;
    default: r.u.w = 1u; break;
  }
  return r;
}

Case mk(unsigned id, vec4 in0, vec4 in1 = vec4(0.0f), unsigned arg = 0) { return {in0, in1, uvec4(id, arg, 0, 0)}; }

std::vector<Case> build_cases() {
  std::vector<Case> cs;
  const float gs[] = {-0.99f, -0.5f, -1e-3f, 0.0f, 1e-4f, 0.3f, 0.85f, 0.99f};
  for (int i = 0; i <= 40; ++i) {
    const float mu = -1.0f + i / 20.0f;
    cs.push_back(mk(PARITY_ISOTROPIC, vec4(mu, 0, 0, 0)));
    cs.push_back(mk(PARITY_RAYLEIGH, vec4(mu, 0, 0, 0)));
    for (float g : gs) {
      cs.push_back(mk(PARITY_HG, vec4(mu, g, 0, 0)));
      cs.push_back(mk(PARITY_CORNETTE_SHANKS, vec4(mu, g, 0, 0)));
      cs.push_back(mk(PARITY_SCHLICK, vec4(mu, g, 0, 0)));
      for (float alpha : {0.0f, 27.1f, 250.0f}) cs.push_back(mk(PARITY_DRAINE, vec4(mu, g, alpha, 0)));
      cs.push_back(mk(PARITY_DUAL_HG, vec4(mu, g, -0.3f, 0.7f)));
    }
  }
  for (int i = 0; i <= 60; ++i) {
    const float d = 0.01f * std::pow(5000.0f, i / 60.0f);
    cs.push_back(mk(PARITY_MIE_PARAMS, vec4(d, 0, 0, 0)));
    cs.push_back(mk(PARITY_MIE_MEAN_COSINE, vec4(d, 0, 0, 0)));
    for (float mu : {-1.0f, -0.2f, 0.5f, 0.99f, 1.0f}) cs.push_back(mk(PARITY_MIE_PHASE, vec4(mu, d, 0, 0)));
  }
  for (float d : {0.0999f, 0.1f, 0.1001f, 1.4999f, 1.5f, 1.5001f, 4.999f, 5.0f, 5.001f}) {
    cs.push_back(mk(PARITY_MIE_PARAMS, vec4(d, 0, 0, 0)));
  }
  const vec3 wi = glm::normalize(vec3(0.3f, -0.5f, 0.8f));
  for (float g : gs) {
    for (int i = 0; i <= 20; ++i) {
      const float u = i / 20.0f * 0.999f;
      cs.push_back(mk(PARITY_HG_SAMPLE_MU, vec4(g, u, 0, 0)));
      cs.push_back(mk(PARITY_SAMPLE_HG, vec4(wi, g), vec4(u, 1.0f - u, 0, 0)));
    }
  }
  for (unsigned seed = 1; seed <= 40; ++seed) {
    cs.push_back(mk(PARITY_SAMPLE_DRAINE, vec4(wi, 0.594f), vec4(27.1f, 0, 0, 0), seed));
    cs.push_back(mk(PARITY_SAMPLE_MIE, vec4(wi, seed % 2 ? 20.0f : 0.5f), vec4(0.0f), seed));
    cs.push_back(mk(PARITY_SAMPLE_DUAL_HG, vec4(wi, 0.85f), vec4(-0.3f, 0.7f, 0, 0), seed));
    cs.push_back(mk(PARITY_PCG_HASH, vec4(0.0f), vec4(0.0f), seed * 2654435761u));
  }
  for (float x : {0.0f, 1e-30f, 1e-12f, 1e-8f, 1e-4f, 1e-2f, 0.0999f, 0.1f, 1.0f, 10.0f, 100.0f, 1e4f, 1e6f}) {
    cs.push_back(mk(PARITY_SEGMENT_FACTOR, vec4(x, 0, 0, 0)));
    cs.push_back(mk(PARITY_TRANSMITTANCE, vec4(x, 0, 0, 0)));
    cs.push_back(mk(PARITY_SEGMENT_INTEGRAL, vec4(2.5f, x, 1.0f, 0)));
  }
  for (unsigned n : {1u, 2u, 8u}) {
    for (float tau : {0.0f, 1.0f, 50.0f}) {
      cs.push_back(mk(PARITY_OCTAVES_HG, vec4(0.05f, 0.3f, 0.85f, tau), vec4(0.5f, 0.5f, 0.5f, 0), n));
      cs.push_back(mk(PARITY_OCTAVES_MIE, vec4(0.05f, 0.3f, 20.0f, tau), vec4(0.5f, 0.5f, 0.5f, 0), n));
    }
  }
  const float r0 = 6371000.0f;
  for (float h : {0.1f, 10.0f, 1000.0f, 5000.0f, 25000.0f, 1e6f, 4e8f}) {
    for (int i = 0; i <= 60; ++i) {
      const float mu = static_cast<float>(-std::cos(3.14159265358979 * i / 60));
      for (float hs : {0.0f, 1000.0f, 20000.0f}) cs.push_back(mk(PARITY_RAY_SPHERE_REL, vec4(r0, h, mu, hs)));
      cs.push_back(mk(PARITY_RAY_SHELL_REL, vec4(r0, h, mu, 1000.0f), vec4(20000.0f, 0, 0, 0)));
    }
    // Within a few ulps of tangency to the ground and to the shell top.
    for (float hs : {0.0f, 20000.0f}) {
      if (h <= hs) continue;
      const double r = double(r0) + h, rs = double(r0) + hs;
      float mu = static_cast<float>(-std::sqrt(1.0 - (rs / r) * (rs / r)));
      for (int k = 0; k < 4; ++k) mu = std::nextafter(mu, -1.0f);
      for (int k = 0; k <= 8; ++k, mu = std::nextafter(mu, 1.0f)) {
        cs.push_back(mk(PARITY_RAY_SPHERE_REL, vec4(r0, h, mu, hs)));
      }
    }
  }
  for (int i = 0; i < 30; ++i) {
    const vec3 o(1000.0f * i - 15000.0f, 2000.0f, -3000.0f);
    const vec3 d = glm::normalize(vec3(0.5f, -0.1f * i, 0.3f));
    cs.push_back(mk(PARITY_RAY_SPHERE, vec4(o, 8000.0f), vec4(d, 0)));
  }
  for (float lat : {-1.5707963f, -0.7f, 0.0f, 0.3f, 1.5707963f}) {
    for (float lon : {-3.14159f, -1.0f, 0.0f, 2.0f}) {
      cs.push_back(mk(PARITY_SPHERE_TO_ECEF, vec4(lat, lon, 12000.0f, r0)));
      cs.push_back(mk(PARITY_ENU_FRAME, vec4(lat, lon, 0, 0)));
      cs.push_back(mk(PARITY_ECEF_TO_SPHERE, vec4(f32::sphere_to_ecef(lat, lon, 12000.0f, r0), r0)));
    }
  }
  for (float phi : {0.0f, 1e4f, 9.80665e4f, 4e5f}) cs.push_back(mk(PARITY_GEOPOTENTIAL, vec4(phi, r0, 0, 0)));
  for (float a : {6371000.0f, 0.3333333f, -12345.678f}) {
    for (float b : {0.9999999f, -7.0e-5f, 3.1415927f}) cs.push_back(mk(PARITY_TWO_PROD, vec4(a, b, 0, 0)));
  }
  // Grid coordinates on a regional grid (160..220E, 25..65N) and a global one, across the date line
  // and its edges, above and below; and the step jitter of a few pixels and frames.
  for (float lon : {-200.0f, -180.0f, -175.0f, 159.9f, 160.0f, 185.25f, 219.99f, 220.0f, 220.3f, 359.9f, 530.0f}) {
    for (float lat : {24.0f, 25.0f, 44.3f, 65.0f}) {
      for (float alt : {-1.0f, 0.0f, 7777.0f, 16000.0f, 16001.0f}) {
        for (float wraps : {0.0f, 1.0f}) cs.push_back(mk(PARITY_VOLUME_COORDS, vec4(lat, lon, alt, wraps)));
      }
    }
  }
  for (unsigned f = 0; f < 4; ++f) {
    for (float px : {0.0f, 17.0f, 1919.0f}) cs.push_back(mk(PARITY_STEP_JITTER, vec4(px, 3.0f * px + 1.0f, 0, 0), vec4(0.0f), f));
  }
  // Mask values (rank / 4096) from the ends and the middle, at frames up to the 32-bit wrap.
  for (unsigned f : {0u, 1u, 7u, 1000u, 4000000000u})
    for (float v : {0.0f, 1.0f / 4096.0f, 0.2998046875f, 0.5f, 4095.0f / 4096.0f})
      cs.push_back(mk(PARITY_BLUE_NOISE_JITTER, vec4(v, 0, 0, 0), vec4(0.0f), f));
  for (float h : {0.0f, 2500.0f, 4e8f})
    for (float mu : {-0.9f, -0.004f, 0.0f, 0.3f, 1.0f})
      for (float t : {0.0f, 150.0f, 4.0e5f}) cs.push_back(mk(PARITY_RAY_ALTITUDE, vec4(6371000.0f, h, mu, t)));
  // Erosion noise: tile coordinates of offsets up to 1e6 m (away from the wrap at 0/1, where a
  // last-bit difference would read as a whole tile), texel addressing across the seam, and the
  // erosion from thin to thick extinction.
  for (float x : {-987654.3f, -2500.0f, 0.0f, 123.456f, 7777.7f, 300001.0f}) {
    cs.push_back(mk(PARITY_NOISE_TILE_COORDS, vec4(x, 0.5f * x + 1000.0f, -x - 3000.0f, 20000.0f), vec4(0.3f, 0.71f, 0.05f, 0)));
  }
  for (float t : {0.0f, 0.2f, 0.5f / 64.0f, 0.49f, 63.5f / 64.0f, 0.9999f, 1.0f}) {
    for (unsigned n : {32u, 64u}) cs.push_back(mk(PARITY_NOISE_TEXEL_PAIR, vec4(t, 0, 0, 0), vec4(0.0f), n));
  }
  for (float sigma : {1e-7f, 1e-4f, 1e-3f, 2e-2f, 5.0f}) {
    for (float nl : {0.0f, 0.3f, 0.8f, 1.0f}) {
      for (float nh : {0.0f, 0.6f, 1.0f}) {
        for (float amount : {0.0f, 0.5f, 1.0f}) cs.push_back(mk(PARITY_EROSION, vec4(sigma, nl, nh, amount), vec4(2500.0f, 0, 0, 0)));
      }
    }
  }
  // Water: Fresnel from grazing to normal incidence; the glint and the water's radiance over sun
  // and view angles (grazing included), azimuths and the sea's roughness from calm to 30 m/s.
  for (int i = -2; i <= 50; ++i) cs.push_back(mk(PARITY_FRESNEL_WATER, vec4(i / 50.0f, 0, 0, 0)));
  for (float ts : {0.0f, 0.3f, 0.8f, 1.3f, 1.5707f}) {
    for (float tv : {0.0f, 0.2f, 0.6f, 1.2f, 1.5706f}) {
      for (float phi : {0.0f, 1.0f, 3.14159f}) {
        for (float mss : {0.003f, 0.0388f, 0.157f}) {
          const float nu = std::sin(ts) * std::sin(tv) * std::cos(phi) + std::cos(ts) * std::cos(tv);
          cs.push_back(mk(PARITY_SEA_GLINT, vec4(std::cos(ts), std::cos(tv), nu, mss)));
          cs.push_back(mk(PARITY_WATER_RADIANCE, vec4(std::cos(ts), std::cos(tv), nu, mss)));
        }
      }
    }
  }
  for (int i = 0; i <= 10; ++i) {
    cs.push_back(mk(PARITY_DIRECTION_AROUND, vec4(glm::normalize(vec3(0.1f * i - 0.5f, 0.2f, -0.9f)), 0),
                    vec4(-1.0f + 0.2f * i, 0.6f * i, 0, 0)));
  }
  return cs;
}

// The scale below which a difference counts as absolute rather than relative: 1 for unit vectors,
// cosines and angles, metres for distances, the Earth's radius for Earth-centred coordinates and for
// an altitude taken from them (|p| - R of float positions, which carry 0.5 m themselves).
float floor_for(unsigned id, int component) {
  if (id == PARITY_ECEF_TO_SPHERE && component == 2) return 6.4e6f;
  switch (id) {
    case PARITY_HG_SAMPLE_MU:
    case PARITY_SAMPLE_HG:
    case PARITY_SAMPLE_DRAINE:
    case PARITY_SAMPLE_MIE:
    case PARITY_SAMPLE_DUAL_HG:
    case PARITY_ENU_FRAME:
    case PARITY_DIRECTION_AROUND:
    case PARITY_ECEF_TO_SPHERE:
    case PARITY_VOLUME_COORDS:  // grid indices
    case PARITY_NOISE_TILE_COORDS:  // tile coordinates in [0, 1)
    case PARITY_NOISE_TEXEL_PAIR:  // interpolation weight
    case PARITY_EROSION: return 1.0f;  // threshold and fraction kept, both in [0, 1]
    case PARITY_RAY_SPHERE_REL:
    case PARITY_RAY_SHELL_REL:
    case PARITY_RAY_SPHERE:
    case PARITY_RAY_ALTITUDE: return 1.0f;  // metres
    case PARITY_SPHERE_TO_ECEF: return 6.4e6f;
    case PARITY_MIE_PARAMS: return 1e-3f;
    case PARITY_TWO_PROD: return 1e-30f;
    case PARITY_SEA_GLINT:        // 1/sr, up to ~100 at the peak of a calm sea
    case PARITY_WATER_RADIANCE: return 1e-3f;  // per unit irradiance
    default: return 1e-30f;
  }
}

const char* name_of(unsigned id) {
  static const char* names[] = {"isotropic", "hg", "cornette_shanks", "schlick", "rayleigh", "draine", "dual_hg",
                                "mie_params", "mie_phase", "mie_mean_cosine", "hg_sample_mu", "sample_hg",
                                "sample_draine", "sample_mie", "sample_dual_hg", "segment_factor",
                                "segment_integral", "transmittance", "octaves_hg", "octaves_mie", "ray_sphere_rel",
                                "ray_shell_rel", "ray_sphere", "sphere_to_ecef", "ecef_to_sphere", "enu_frame",
                                "geopotential", "pcg_hash", "two_prod", "direction_around", "volume_coords", "step_jitter",
                                "ray_altitude", "noise_tile_coords", "noise_texel_pair", "erosion",
                                "blue_noise_jitter", "fresnel_water", "sea_glint", "water_radiance"};
  return id < PARITY_FUNCTION_COUNT ? names[id] : "?";
}

TEST(GpuParity, EveryPhysicsFunctionMatchesTheCppBuild) {
  auto ctx = make_headless_context();
  ShaderLoader loader({CV_SHADER_DIR});
  GlProgram prog = load_compute(loader, std::string(CV_SHADER_DIR) + "/tests/physics_parity.comp");
  const std::vector<Case> cases = build_cases();
  std::vector<bool> seen(PARITY_FUNCTION_COUNT, false);
  for (const Case& c : cases) seen[c.meta.x] = true;
  for (unsigned id = 0; id < PARITY_FUNCTION_COUNT; ++id) EXPECT_TRUE(seen[id]) << name_of(id) << " has no case";

  GLuint bufs[2];
  glCreateBuffers(2, bufs);
  glNamedBufferStorage(bufs[0], static_cast<GLsizeiptr>(cases.size() * sizeof(Case)), cases.data(), 0);
  glNamedBufferStorage(bufs[1], static_cast<GLsizeiptr>(cases.size() * sizeof(Result)), nullptr,
                       GL_MAP_READ_BIT);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, bufs[0]);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, bufs[1]);
  glUseProgram(prog.id());
  glUniform1ui(glGetUniformLocation(prog.id(), "u_count"), static_cast<GLuint>(cases.size()));
  glDispatchCompute(static_cast<GLuint>((cases.size() + 63) / 64), 1, 1);
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  std::vector<Result> gpu(cases.size());
  glGetNamedBufferSubData(bufs[1], 0, static_cast<GLsizeiptr>(gpu.size() * sizeof(Result)), gpu.data());
  check_gl("running the physics parity shader");
  glDeleteBuffers(2, bufs);

  std::map<unsigned, double> worst;
  for (size_t i = 0; i < cases.size(); ++i) {
    const unsigned id = cases[i].meta.x;
    const Result cpu = eval(cases[i]);
    ASSERT_EQ(gpu[i].u.w, 0u) << "the shader does not know function " << name_of(id);
    EXPECT_EQ(gpu[i].u, cpu.u) << name_of(id) << " case " << i;  // flags, counts, rng states: exact
    for (int k = 0; k < 4; ++k) {
      const float fl = floor_for(id, k);
      for (const auto& [g, c] : {std::pair{gpu[i].a[k], cpu.a[k]}, std::pair{gpu[i].b[k], cpu.b[k]}}) {
        ASSERT_TRUE(std::isfinite(g)) << name_of(id) << " case " << i;
        const double err = std::abs(double(g) - double(c)) / std::max(std::abs(double(c)), double(fl));
        worst[id] = std::max(worst[id], err);
        EXPECT_LE(err, 1e-5) << name_of(id) << " case " << i << " component " << k << ": gpu " << g << " cpu " << c;
        // Latitude and longitude place every cloud sample: 3e-7 rad is 2 m on the ground.
        if (id == PARITY_ECEF_TO_SPHERE && k < 2) {
          EXPECT_LE(err, 3e-7) << "ecef_to_sphere case " << i << " component " << k;
        }
      }
    }
  }
  double overall = 0;
  unsigned overall_id = 0;
  std::printf("GPU (%s) vs C++ float, worst relative difference per function:\n", ctx->info().renderer.c_str());
  for (const auto& [id, w] : worst) {
    std::printf("  %-18s %.3g\n", name_of(id), w);
    if (w >= overall) overall = w, overall_id = id;
  }
  std::printf("worst overall: %.3g (%s), over %zu cases\n", overall, name_of(overall_id), cases.size());
}

}  // namespace
