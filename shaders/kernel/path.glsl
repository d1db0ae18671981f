// Volumetric path tracing through the kernel's medium: the Monte Carlo reference's path, written
// once for the CPU reference (core/reference/monte_carlo.cpp, in double) and the GPU path tracer
// (shaders/render/pathtrace.comp, in float). A path starts on a pixel's view ray and scatters in
// cloud (delta tracking, tracking.glsl) and off a Lambertian ground of constant albedo, with
// next-event estimation toward the sun (ratio tracking) at every vertex, new directions drawn from
// the phase function of the component that scattered, multiple importance sampling of the droplets'
// forward peak toward the sun, and Russian roulette on the throughput (docs/physics.md, "Monte Carlo
// reference" and "A reference that converges").
// Needs march.glsl and tracking.glsl, and from the including side: track_bits(rng) (32 random
// bits, for the Mie sampler's own stream), u_path_max_bounces, u_path_roulette_after and
// u_path_peak_mis.

#define CV_PATH_FAR real(3.0e38)
// How a path ended.
#define CV_PATH_SPACE 0
#define CV_PATH_GROUND 1
#define CV_PATH_TRUNCATED 2
#define CV_PATH_ROULETTE 3

// A path's outcome, per unit sun irradiance times the sun's irradiance: what reached the camera,
// the throughput it carried when it ended, what the ground absorbed, how it ended, its vertices.
struct PathResult {
  real3 radiance;
  real3 weight;
  real3 absorbed;
  int end;
  int scatterings;
};

// A path's counters, beside the tracking's (TrackCounts).
struct PathCounts {
  uint roulette_killed;
  uint truncated;
  uint peak_samples;
};

CV_FN PathCounts path_counts() {
  PathCounts c;
  c.roulette_killed = 0u;
  c.truncated = 0u;
  c.peak_samples = 0u;
  return c;
}

// The parts of the ray p + t d (t >= 0) inside the cloud layer, cut at the ground; their count
// (<= 2), and in t_ground the distance to the ground (CV_PATH_FAR: never).
CV_FN int path_shell_parts(real3 p, real3 d, CV_OUT(real4) seg, CV_OUT(real) t_ground) {
  real r = length(p);
  real alt = r - u_r0;
  real3 up = p / r;
  real mu = dot(d, up);
  real nu = length(cross(d, up));
  t_ground = CV_PATH_FAR;
  seg = real4(real(0.0));
  // A rising ray from the ground or above never meets it: a point placed on the ground may round
  // below it, and must not then find the ground at t = 0.
  bool rising = mu >= real(0.0) && alt > real(-1.0);
  real g0;
  real g1;
  if (!rising && ray_sphere_rel_nu(u_r0, alt, mu, nu, real(0.0), g0, g1) && g1 > real(0.0)) t_ground = max(g0, real(0.0));
  if (u_cloudless) return 0;
  real4 s;
  int n = ray_shell_rel_nu(u_r0, alt, mu, nu, u_layer.x, u_layer.y, s);
  int kept = 0;
  for (int k = 0; k < 2; ++k) {
    if (k >= n) break;
    real a = k == 0 ? s.x : s.z;
    real b = min(k == 0 ? s.y : s.w, t_ground);
    if (b > a) {
      if (kept == 0) {
        seg.x = a;
        seg.y = b;
      } else {
        seg.z = a;
        seg.w = b;
      }
      kept += 1;
    }
  }
  return kept;
}

// Distance to the first real collision from p along d (CV_PATH_FAR when the ray leaves the cloud),
// and the distance to the ground.
CV_FN real path_free_path(real3 p, real3 d, CV_INOUT(TrackRng) rng, CV_INOUT(TrackCounts) c, CV_OUT(real) t_ground) {
  real4 seg;
  int n = path_shell_parts(p, d, seg, t_ground);
  return delta_track(p, d, seg, n, rng, c);
}

// Transmittance of the cloud from p along d by ratio tracking; 0 when the ray meets the Earth.
CV_FN real path_transmittance(real3 p, real3 d, CV_INOUT(TrackRng) rng, CV_INOUT(TrackCounts) c) {
  real4 seg;
  real t_ground;
  int n = path_shell_parts(p, d, seg, t_ground);
  if (t_ground < CV_PATH_FAR) return real(0.0);  // the Earth's shadow
  return ratio_track(p, d, seg, n, rng, c);
}

// The phase function of a point holding liquid sl and ice si at scattering cosine mu: the mix by
// extinction share, which is also the density of the direction a path draws there.
CV_FN real path_phase(real sl, real si, real mu, MieParams mie, real liquid_g) {
  real sigma = sl + si;
  if (!(sigma > real(0.0))) return phase_isotropic();
  real liquid = u_liquid_phase_hg ? phase_hg(mu, liquid_g) : phase_mie(mu, mie);
  return (sl * liquid + si * phase_hg(mu, u_ice_g)) / sigma;
}

// Russian roulette on the throughput from u_path_roulette_after vertices on: false when it ends
// the path (r.end set); a survivor's throughput is divided by its survival probability.
CV_FN bool path_roulette(CV_INOUT(PathResult) r, CV_INOUT(real3) beta, CV_INOUT(TrackRng) rng, CV_INOUT(PathCounts) pc) {
  if (r.scatterings < u_path_roulette_after) return true;
  real q = min(real(1.0), max(beta.x, max(beta.y, beta.z)));
  if (q >= real(1.0)) return true;
  if (track_uniform(rng) >= q) {
    r.end = CV_PATH_ROULETTE;
    pc.roulette_killed += 1u;
    return false;
  }
  beta /= q;
  return true;
}

// One path from p along unit d (the first segment is the view ray).
CV_FN PathResult trace_path(real3 p, real3 d, CV_INOUT(TrackRng) rng, CV_INOUT(TrackCounts) c, CV_INOUT(PathCounts) pc) {
  MieParams mie = mie_params(u_droplet_um);
  real liquid_g = mie_mean_cosine(mie);  // for u_liquid_phase_hg
  // The second technique for the direction into a vertex: the droplets' HG peak lobe around the
  // sun, drawn at every cloud vertex holding liquid (Henyey-Greenstein liquid has no peak).
  bool peak = u_path_peak_mis && !u_liquid_phase_hg;
  PathResult r;
  r.radiance = real3(0.0);
  r.weight = real3(1.0);
  r.absorbed = real3(0.0);
  r.end = CV_PATH_SPACE;
  r.scatterings = 0;
  real3 beta = real3(1.0);
  // The vertex the current direction was drawn at, when the peak technique could have drawn it too.
  bool prev_peak = false;
  real prev_sl = real(0.0);
  real prev_si = real(0.0);
  real3 prev_d = real3(0.0);
  for (;;) {
    real t_ground;
    real t = path_free_path(p, d, rng, c, t_ground);
    if (t < CV_PATH_FAR) {
      p += t * d;
      real sl;
      real si;
      medium_at_point(p, sl, si);
      real sigma = sl + si;
      r.scatterings += 1;
      // Next-event estimation: the sun is a delta light, reachable only this way. The scattering
      // cosine is between the sunlight's propagation (-to_sun) and the light's toward the camera
      // (-d). Balance heuristic against the peak technique, which could have drawn d at the vertex before.
      real w = real(1.0);
      if (prev_peak) {
        real p_prev = path_phase(prev_sl, prev_si, dot(prev_d, d), mie, liquid_g);
        w = p_prev / (p_prev + phase_hg_c(dot(d, u_to_sun), mie.g_hg, mie.c_hg));
      }
      r.radiance += beta * u_irradiance * (w * path_phase(sl, si, dot(d, u_to_sun), mie, liquid_g) * path_transmittance(p, u_to_sun, rng, c));
      if (r.scatterings >= u_path_max_bounces) {
        r.end = CV_PATH_TRUNCATED;
        pc.truncated += 1u;
        break;
      }
      if (!path_roulette(r, beta, rng, pc)) break;
      // The peak technique: a direction wq ~ q around the sun, the free path along it, the sun's
      // light at the vertex it reaches, weighted q / (p + q) (the path's own technique is weighted above).
      prev_peak = peak && sl > real(0.0);
      if (prev_peak) {
        pc.peak_samples += 1u;
        real q;
        real u1 = track_uniform(rng);
        real u2 = track_uniform(rng);
        real3 wq = sample_hg(u_to_sun, mie.g_hg, real2(u1, u2), q);
        q = phase_hg_c(dot(wq, u_to_sun), mie.g_hg, mie.c_hg);  // c_hg kept apart: the sampler's pdf loses digits near g = 1
        real p_here = path_phase(sl, si, dot(d, wq), mie, liquid_g);
        real tg2;
        real tq = path_free_path(p, wq, rng, c, tg2);
        if (tq < CV_PATH_FAR && p_here > real(0.0)) {
          real3 x = p + tq * wq;
          real sl2;
          real si2;
          medium_at_point(x, sl2, si2);
          r.radiance += beta * u_irradiance *
                        (p_here / (p_here + q) * path_phase(sl2, si2, dot(wq, u_to_sun), mie, liquid_g) * path_transmittance(x, u_to_sun, rng, c));
        }
        prev_sl = sl;
        prev_si = si;
        prev_d = d;
      }
      // Clouds do not absorb (albedo 1): the new direction is drawn from the phase function of the
      // component that scattered, chosen by its share of the extinction; beta is unchanged.
      real pdf;
      if (track_uniform(rng) * sigma < sl || !(sigma > real(0.0))) {
        if (u_liquid_phase_hg) {
          real v1 = track_uniform(rng);
          real v2 = track_uniform(rng);
          d = sample_hg(d, liquid_g, real2(v1, v2), pdf);
        } else {
          uint state = track_bits(rng);
          d = sample_mie(d, mie, state, pdf);
        }
      } else {
        real v1 = track_uniform(rng);
        real v2 = track_uniform(rng);
        d = sample_hg(d, u_ice_g, real2(v1, v2), pdf);
      }
    } else if (kGlobe && t_ground < CV_PATH_FAR) {
      // A Lambertian ground of constant albedo: lit by the sun through the clouds, reflecting a
      // cosine-distributed new direction with throughput times albedo.
      p = normalize(p + t_ground * d) * u_r0;
      real3 n = p / u_r0;
      r.scatterings += 1;
      real mu_s = dot(n, u_to_sun);
      if (mu_s > real(0.0)) {
        real tr = path_transmittance(p, u_to_sun, rng, c);
        r.radiance += beta * u_irradiance * ground_radiance(u_ground_albedo, mu_s, real3(tr), real3(0.0));
      }
      r.absorbed += beta * (real3(1.0) - u_ground_albedo);
      beta *= u_ground_albedo;
      if (r.scatterings >= u_path_max_bounces) {
        r.end = CV_PATH_TRUNCATED;
        pc.truncated += 1u;
        break;
      }
      if (!path_roulette(r, beta, rng, pc)) break;
      prev_peak = false;  // a cosine draw from the ground: no other technique makes it
      real v1 = track_uniform(rng);
      real v2 = track_uniform(rng);
      d = direction_around(n, sqrt(v1), CV_TWO_PI * v2);
    } else {
      r.end = t_ground < CV_PATH_FAR ? CV_PATH_GROUND : CV_PATH_SPACE;
      break;
    }
  }
  r.weight = beta;
  return r;
}
