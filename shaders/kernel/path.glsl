// Volumetric path tracing through the kernel's medium: the Monte Carlo reference's path, written
// once for the CPU reference (core/reference/monte_carlo.cpp, in double) and the GPU path tracer
// (shaders/render/pathtrace.comp, in float). A path starts on a pixel's view ray and scatters in
// cloud (delta tracking, tracking.glsl) and off the ground (the march's ground_at: land albedo and
// water, or the constant albedo without a ground texture), with next-event estimation toward the
// sun (ratio tracking) at every vertex, new directions drawn from the phase function of the
// component that scattered, multiple importance sampling of the droplets' forward peak toward the
// sun (with CV_PATH_SPLIT: the direction drawn around the sun starts a branch, and the includer
// provides path_room(), path_split(PathState) and path_pop(PathState)), and Russian roulette on
// the throughput (docs/physics.md, "Monte Carlo reference" and "A reference that converges"). With
// the air on (kAtmosphere) the sunlight reaching a vertex is reddened by the air's transmittance,
// and a path that leaves into the sky takes the sky's single-scattered radiance in its direction:
// the sky as an environment light (docs/physics.md, "The path tracer's sky and ground"). The air
// between the camera and the first vertex adds its light and dims what lies behind it, as the
// march's sky in front of its cloud and ground does; between later vertices it neither dims nor
// adds light.
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
  real3 escaped;   // the throughput that left into space, the branches' included
  real3 grounded;  // the throughput that ended on the ground (a black one, or the globe off), the same
  int end;
  int scatterings;
  int scatterings_branches;
};

// A path's counters, beside the tracking's (TrackCounts).
struct PathCounts {
  uint roulette_killed;
  uint truncated;
  uint peak_samples;
  uint vertices;  // scatterings in cloud and bounces off the ground
};

CV_FN PathCounts path_counts() {
  PathCounts c;
  c.roulette_killed = 0u;
  c.truncated = 0u;
  c.peak_samples = 0u;
  c.vertices = 0u;
  return c;
}

// The top of the volume's grid (m): paths cross the whole grid's shell, as the Monte Carlo always has.
CV_FN real path_grid_top() { return u_grid_start.z + u_grid_step.z * (u_grid_count.z - real(1.0)); }

// Where a pixel's path starts along its view ray d: the camera or, for a camera above the grid,
// where the ray enters it, on the exact sphere (distant cameras keep the digits of the positions
// they sample). misses: the ray never meets the grid's shell (nor the Earth inside it).
CV_FN real3 path_camera_origin(real3 d, CV_OUT(bool) misses) {
  misses = false;
  real3 o = u_cam_ecef;
  real ht = path_grid_top();
  if (u_cam_alt > ht) {
    real e0;
    real e1;
    if (!ray_sphere_rel_nu(u_r0, u_cam_alt, dot(d, u_cam_up), length(cross(d, u_cam_up)), ht, e0, e1) || e1 < real(0.0)) {
      misses = true;
    } else if (e0 > real(0.0)) {
      o = normalize(o + e0 * d) * (u_r0 + ht);
    }
  }
  return o;
}

// The parts of the ray p + t d (t >= 0) inside the grid's shell, cut at the ground; their count
// (<= 2), and in t_ground the distance to the ground (CV_PATH_FAR: never).
CV_FN int path_shell_parts(real3 p, real3 d, CV_OUT(real4) seg, CV_OUT(real) t_ground) {
  real r = length(p);
  real alt = max(r - u_r0, real(0.0));  // a ground vertex a hair below the sphere: on it (path_sun_air)
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
  real4 s;
  int n = ray_shell_rel_nu(u_r0, alt, mu, nu, u_grid_start.z, u_grid_start.z + u_grid_step.z * (u_grid_count.z - real(1.0)), s);
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
  c.iterations += 4u;  // path_shell_parts' loop
  real4 seg;
  int n = path_shell_parts(p, d, seg, t_ground);
  return delta_track(p, d, seg, n, rng, c);
}

// The air's transmittance (RGB) of the sunlight reaching p (0 in the Earth's shadow); 1 without air.
CV_FN real3 path_sun_air(real3 p, CV_INOUT(TrackCounts) c) {
  if (!kAtmosphere) return real3(1.0);
  c.iterations += uint(u_atmo_sun_steps) + 2u;  // atmo_optical_depth's two loops
  real r = length(p);
  real3 up = p / r;
  // A ground vertex lies on the sphere; rounding may put it a hair below, where every ray would
  // meet the Earth at once: its altitude is held at 0.
  return atmo_transmittance(u_r0, max(r - u_r0, real(0.0)), dot(u_to_sun, up), length(cross(u_to_sun, up)), u_atmo_sun_steps);
}

// The sky's radiance (per unit sun irradiance) arriving at p from direction d: the air's single
// scattering from p along d out to the top of the atmosphere (atmo_inscatter, as the march's sky),
// or to the ground where d meets it. 0 without air.
CV_FN real3 path_sky(real3 p, real3 d, CV_INOUT(TrackCounts) c) {
  if (!kAtmosphere) return real3(0.0);
  real r = length(p);
  real alt = max(r - u_r0, real(0.0));  // a ground vertex a hair below the sphere: on it (path_sun_air)
  real3 up = p / r;
  real mu = dot(d, up);
  real nu = length(cross(d, up));
  real a0;
  real a1;
  if (!ray_sphere_rel_nu(u_r0, alt, mu, nu, CV_ATMO_TOP_M, a0, a1) || !(a1 > real(0.0))) return real3(0.0);
  real t_end = a1;
  real g0;
  real g1;
  if (ray_sphere_rel_nu(u_r0, alt, mu, nu, real(0.0), g0, g1) && g1 > real(0.0)) t_end = max(g0, real(0.0));
  c.iterations += uint(u_sky_steps) * (uint(u_atmo_sun_steps) + 3u) + 2u;  // atmo_inscatter's loops
  real3 tr;
  return atmo_inscatter(u_r0, alt, mu, dot(u_to_sun, up), dot(d, u_to_sun), max(a0, real(0.0)), t_end, u_sky_steps, u_atmo_sun_steps, tr);
}

// The air along the view ray d from the camera to t_cam metres from it (CV_PATH_FAR, or anything
// past the ground or the atmosphere's top: to where the ray meets the one or leaves the other): its
// single-scattered light per unit sun irradiance (atmo_inscatter, the integral of the march's sky in
// front of its cloud and ground) and, in tr, its transmittance; none without air. The ray in the
// air's frame as the march's sky_and_ground takes it (camera_air_ray).
CV_FN real3 path_air_front(real3 d, real t_cam, CV_OUT(real3) tr, CV_INOUT(TrackCounts) c) {
  tr = real3(1.0);
  if (!kAtmosphere) return real3(0.0);
  AirRay air = camera_air_ray(d);
  if (!air.in_air) return real3(0.0);
  real t = clamp(t_cam - air.t_in, real(0.0), air.t_end);
  c.iterations += uint(u_sky_steps) * (uint(u_atmo_sun_steps) + 3u) + 2u;  // atmo_inscatter's loops
  return atmo_inscatter(u_r0, air.h, air.mu, dot(u_to_sun, air.up), dot(d, u_to_sun), real(0.0), t, u_sky_steps, u_atmo_sun_steps, tr);
}

// What a pixel sees whose view ray misses the grid's shell (path_camera_origin): the air from the
// camera (the sky), none without air.
CV_FN real3 path_miss(real3 d, CV_INOUT(TrackCounts) c) {
  real3 tr;
  return u_irradiance * path_air_front(d, CV_PATH_FAR, tr, c);
}

// Transmittance of the cloud from p along d by ratio tracking; 0 when the ray meets the Earth.
CV_FN real path_transmittance(real3 p, real3 d, CV_INOUT(TrackRng) rng, CV_INOUT(TrackCounts) c) {
  c.iterations += 4u;  // path_shell_parts' loop
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

// A path in flight: where it is, where it goes, what it carries, and the vertex its direction was
// drawn at when the peak technique could have drawn it too. A path can stop between vertices and
// resume later (the GPU path tracer does, to stay inside llvmpipe's loop budget).
struct PathState {
  real3 p;
  real3 d;
  real3 beta;
  real3 radiance;
  real3 absorbed;
  int end;
  int scatterings;
  bool done;
  bool prev_peak;
  real prev_sl;
  real prev_si;
  real3 prev_d;
  ivec2 px;  // the pixel whose view ray the path starts on: its opaque and translucent inputs (overlays)
};

#if defined(CV_PATH_SPLIT) && defined(CV_GLSL)
// The branch stack, defined by the includer (GLSL wants a function declared before its use; C++
// finds the class's members anyway): whether it has room for one more branch, push, pop.
bool path_room();
void path_split(PathState b);
bool path_pop(out PathState b);
#endif

// A path from p along unit d (the first segment is the view ray).
CV_FN PathState path_begin(real3 p, real3 d) {
  PathState s;
  s.p = p;
  s.d = d;
  s.beta = real3(1.0);
  s.radiance = real3(0.0);
  s.absorbed = real3(0.0);
  s.end = CV_PATH_SPACE;
  s.scatterings = 0;
  s.done = false;
  s.prev_peak = false;
  s.prev_sl = real(0.0);
  s.prev_si = real(0.0);
  s.prev_d = real3(0.0);
  s.px = ivec2(0, 0);
  return s;
}

// What the pixel's view ray meets in front of its first vertex, t_cam metres from the camera: the
// air, whose light the path adds and whose transmittance dims what it gathers from there on, and the
// translucent fragments (the overlays' surfaces, nearest first) before it, each adding its radiance
// times its alpha and passing 1 - alpha. The march composites the same: its sky in front of the
// cloud and the fragments, which stand among the cloud (sky_and_ground, tl_composite).
CV_FN void path_front(CV_INOUT(PathState) s, real t_cam, CV_INOUT(TrackCounts) c) {
  if (kAtmosphere) {
    real3 tr;
    real3 l = path_air_front(s.d, t_cam, tr, c);
    s.radiance += s.beta * u_irradiance * l;
    s.beta *= tr;
  }
  for (int k = 0; k < u_tl_count; ++k) {
    c.iterations += 1u;
    if (!(tl_distance(s.px, k) < t_cam)) break;
    real4 f = real4(texelFetch(u_tl_color, ivec2(s.px.x + k * u_size.x, s.px.y), 0));
    s.radiance += s.beta * (f.w * real3(f.x, f.y, f.z));
    s.beta *= real(1.0) - f.w;
  }
}

// The radiance of the opaque geometry the pixel's view ray ends on (the overlays' colour input);
// none where only its depth is given.
CV_FN real3 path_opaque_radiance(ivec2 px) { return u_has_opaque_color ? real3(texelFetch(u_opaque, px, 0)) : real3(0.0); }

// A view ray that misses the grid's shell (path_camera_origin): the air, the fragments and the
// opaque geometry on it, if any, else the sky.
CV_FN void path_view_misses(CV_INOUT(PathState) s, CV_INOUT(TrackCounts) c) {
  real t_stop = opaque_distance(s.px);
  path_front(s, t_stop, c);
  if (t_stop < CV_PATH_FAR) {
    s.radiance += s.beta * path_opaque_radiance(s.px);
    s.end = CV_PATH_GROUND;
  }
  s.done = true;
}

// How much more a path heading along d is worth keeping than its weight says: with splitting, a
// path heading into the droplets' peak around the sun is about to meet a next-event estimate of up
// to q per sr, so its survival is raised by q and a survivor's weight is never raised above 1 / q
// there (a boosted path in the peak would be the heavy tail again); 1 otherwise.
CV_FN real path_importance(real3 d, MieParams mie, bool peak) {
#ifdef CV_PATH_SPLIT
  if (peak) return max(real(1.0), phase_hg_c(dot(d, u_to_sun), mie.g_hg, mie.c_hg));
#endif
  return real(1.0);
}

// Russian roulette on the path's throughput from u_path_roulette_after vertices on: false when it
// ends the path; a survivor's throughput is divided by its survival probability (its weight times
// `importance`, path_importance, at most 1).
CV_FN bool path_roulette(CV_INOUT(PathState) s, CV_INOUT(TrackRng) rng, CV_INOUT(PathCounts) pc, real importance) {
  if (s.scatterings < u_path_roulette_after) return true;
  real q = min(real(1.0), importance * max(s.beta.x, max(s.beta.y, s.beta.z)));
  if (q >= real(1.0)) return true;
  if (track_uniform(rng) >= q) {
    s.end = CV_PATH_ROULETTE;
    pc.roulette_killed += 1u;
    return false;
  }
  s.beta /= q;
  return true;
}

// After a vertex's light is added: whether the path goes on past it. It ends (s.done, s.end set)
// at u_path_max_bounces vertices (truncated) or when Russian roulette ends it.
CV_FN bool path_continues(CV_INOUT(PathState) s, CV_INOUT(TrackRng) rng, CV_INOUT(PathCounts) pc, real importance) {
  if (s.scatterings >= u_path_max_bounces) {
    s.end = CV_PATH_TRUNCATED;
    pc.truncated += 1u;
    s.done = true;
    return false;
  }
  if (!path_roulette(s, rng, pc, importance)) {
    s.done = true;
    return false;
  }
  return true;
}

// Advances the path vertex by vertex until it ends (s.done) or the walk's loop iterations
// (c.iterations) reach max_iterations, checked before each vertex.
CV_FN void path_advance(CV_INOUT(PathState) s, CV_INOUT(TrackRng) rng, CV_INOUT(TrackCounts) c, CV_INOUT(PathCounts) pc,
                        uint max_iterations) {
  MieParams mie = mie_params(u_droplet_um);
  real liquid_g = mie_mean_cosine(mie);  // for u_liquid_phase_hg
  // The second technique for the direction into a vertex: the droplets' HG peak lobe around the
  // sun, drawn at every cloud vertex holding liquid (Henyey-Greenstein liquid has no peak).
  bool peak = u_path_peak_mis && !u_liquid_phase_hg;
  while (!s.done && c.iterations < max_iterations) {
    // This loop's test, and the Mie sampler's rejection loop (a few tries: it accepts at least 1/3).
    c.iterations += 8u;
    // The pixel's view ray itself (no vertex yet; a branch starts at one): what lies between the
    // camera and the first vertex counts (path_front), and opaque geometry nearer than that vertex
    // (the overlays' depth input) ends the ray with its own radiance. Distances from the camera:
    // t_skip to where the path starts (the grid's top for a camera above it).
    bool front = s.scatterings == 0;
    real t_ground;
    real t = path_free_path(s.p, s.d, rng, c, t_ground);
    real t_skip = front ? max(dot(s.p - u_cam_ecef, s.d), real(0.0)) : real(0.0);
    real t_stop = front ? opaque_distance(s.px) : CV_PATH_FAR;
    if (t_stop < CV_PATH_FAR && t_stop - t_skip < min(t, t_ground)) {
      path_front(s, t_stop, c);
      s.radiance += s.beta * path_opaque_radiance(s.px);
      s.p += (t_stop - t_skip) * s.d;
      s.end = CV_PATH_GROUND;
      s.done = true;
      break;
    }
    if (t < CV_PATH_FAR) {
      s.p += t * s.d;
      if (front) path_front(s, t_skip + t, c);
      real sl;
      real si;
      medium_at_point(s.p, sl, si);
      real sigma = sl + si;
      s.scatterings += 1;
      pc.vertices += 1u;
      // Next-event estimation: the sun is a delta light, reachable only this way. The scattering
      // cosine is between the sunlight's propagation (-to_sun) and the light's toward the camera
      // (-d). Balance heuristic against the peak technique, which could have drawn d at the vertex before.
      real w = real(1.0);
      if (s.prev_peak) {
        real p_prev = path_phase(s.prev_sl, s.prev_si, dot(s.prev_d, s.d), mie, liquid_g);
        w = p_prev / (p_prev + phase_hg_c(dot(s.d, u_to_sun), mie.g_hg, mie.c_hg));
      }
      s.radiance += s.beta * u_irradiance * path_sun_air(s.p, c) *
                    (w * path_phase(sl, si, dot(s.d, u_to_sun), mie, liquid_g) * path_transmittance(s.p, u_to_sun, rng, c));
      if (!path_continues(s, rng, pc, path_importance(s.d, mie, peak))) break;
      // Splitting (CV_PATH_SPLIT): the direction wq ~ q around the sun starts a branch of its own,
      // weighted p / (p + q) by the balance heuristic and kept by Russian roulette on that weight;
      // the path's own direction is weighted the same way below. Without it, or where the branch
      // stack is full (the GPU's holds a few per pixel), the one-sample technique instead.
#ifdef CV_PATH_SPLIT
      bool split_here = peak && sl > real(0.0) && path_room();
#else
      bool split_here = false;
#endif
      real3 d_in = s.d;
      s.prev_peak = peak && sl > real(0.0) && !split_here;
      if (split_here) {
#ifdef CV_PATH_SPLIT
        real q;
        real u1 = track_uniform(rng);
        real u2 = track_uniform(rng);
        real3 wq = sample_hg(u_to_sun, mie.g_hg, real2(u1, u2), q);
        q = phase_hg_c(dot(wq, u_to_sun), mie.g_hg, mie.c_hg);
        real p_here = path_phase(sl, si, dot(s.d, wq), mie, liquid_g);
        real3 bb = s.beta * (p_here / (p_here + q));
        real keep = min(real(1.0), max(real(1.0), q) * max(bb.x, max(bb.y, bb.z)));
        if (keep > real(0.0) && track_uniform(rng) < keep) {
          pc.peak_samples += 1u;
          PathState b = path_begin(s.p, wq);
          b.beta = bb / keep;
          b.scatterings = s.scatterings;
          path_split(b);
        }
#endif
      } else if (s.prev_peak) {
        // The one-sample technique: a direction wq ~ q around the sun, the free path along it, the
        // sun's light at the vertex it reaches, weighted q / (p + q) (the path's own technique is
        // weighted at its next vertex, above).
        pc.peak_samples += 1u;
        real q;
        real u1 = track_uniform(rng);
        real u2 = track_uniform(rng);
        real3 wq = sample_hg(u_to_sun, mie.g_hg, real2(u1, u2), q);
        q = phase_hg_c(dot(wq, u_to_sun), mie.g_hg, mie.c_hg);  // c_hg kept apart: the sampler's pdf loses digits near g = 1
        real p_here = path_phase(sl, si, dot(s.d, wq), mie, liquid_g);
        real tg2;
        real tq = path_free_path(s.p, wq, rng, c, tg2);
        if (tq < CV_PATH_FAR && p_here > real(0.0)) {
          real3 x = s.p + tq * wq;
          real sl2;
          real si2;
          medium_at_point(x, sl2, si2);
          s.radiance += s.beta * u_irradiance * path_sun_air(x, c) *
                        (p_here / (p_here + q) * path_phase(sl2, si2, dot(wq, u_to_sun), mie, liquid_g) *
                         path_transmittance(x, u_to_sun, rng, c));
        }
        s.prev_sl = sl;
        s.prev_si = si;
        s.prev_d = s.d;
      }
      // Clouds do not absorb (albedo 1): the new direction is drawn from the phase function of the
      // component that scattered, chosen by its share of the extinction; beta is unchanged.
      real pdf;
      if (track_uniform(rng) * sigma < sl || !(sigma > real(0.0))) {
        if (u_liquid_phase_hg) {
          real v1 = track_uniform(rng);
          real v2 = track_uniform(rng);
          s.d = sample_hg(s.d, liquid_g, real2(v1, v2), pdf);
        } else {
          uint state = track_bits(rng);
          s.d = sample_mie(s.d, mie, state, pdf);
        }
      } else {
        real v1 = track_uniform(rng);
        real v2 = track_uniform(rng);
        s.d = sample_hg(s.d, u_ice_g, real2(v1, v2), pdf);
      }
      if (split_here) {
        real p_mix = path_phase(sl, si, dot(d_in, s.d), mie, liquid_g);
        s.beta *= p_mix / (p_mix + phase_hg_c(dot(s.d, u_to_sun), mie.g_hg, mie.c_hg));
      }
    } else if (kGlobe && t_ground < CV_PATH_FAR) {
      // The ground as the march sees it (ground_at): Lambertian land of its albedo and a water
      // fraction with the glint and the water body (water_radiance), lit by the sun through the
      // air and the clouds; the sky's light reaches it by the paths that leave it.
      s.p = normalize(s.p + t_ground * s.d) * u_r0;
      // The fragments on the ground itself count (the overlay pass keeps those within max(1 m, 1e-6
      // of the distance) behind the sphere, overlay.frag).
      if (front) path_front(s, t_skip + t_ground + max(real(1.0), real(1.0e-6) * (t_skip + t_ground)), c);
      real3 n = s.p / u_r0;
      s.scatterings += 1;
      pc.vertices += 1u;
      real3 ll = ecef_to_sphere(s.p, u_r0);
      real4 g = ground_at(ll.x, ll.y);
      real3 land = real3(g.x, g.y, g.z);
      real water = clamp(g.w, real(0.0), real(1.0));
      real mss = cox_munk_mss(u_ocean_wind);
      real mu_v = -dot(s.d, n);  // toward where the path came from
      real mu_s = dot(n, u_to_sun);
      if (mu_s > real(0.0)) {
        real tr = path_transmittance(s.p, u_to_sun, rng, c);
        s.radiance += s.beta * u_irradiance *
                      ground_radiance_water(land, water, CV_WATER_BODY, mu_s, mu_v, -dot(s.d, u_to_sun), mss,
                                            path_sun_air(s.p, c) * tr, real3(0.0));
      }
      // The bounce: off water with the probability of its fraction, a cosine-distributed direction
      // weighted by pi x the water's BRDF; else off land, the albedo as the weight. Without water
      // the random numbers are drawn as they always were.
      bool wet = water > real(0.0) && track_uniform(rng) < water;
      real3 o = n;
      real3 weight = land;
      if (wet) {
        real u1 = track_uniform(rng);
        real u2 = track_uniform(rng);
        o = direction_around(n, sqrt(u1), CV_TWO_PI * u2);
        weight = CV_PI * water_brdf(CV_WATER_BODY, dot(o, n), mu_v, -dot(s.d, o), mss);
      }
      s.absorbed += s.beta * (real3(1.0) - weight);  // in expectation, 1 - the albedo
      s.beta *= weight;
      if (!path_continues(s, rng, pc, path_importance(s.d, mie, peak))) break;
      s.prev_peak = false;  // a cosine draw from the ground: no other technique makes it
      if (!wet) {
        real v1 = track_uniform(rng);
        real v2 = track_uniform(rng);
        o = direction_around(n, sqrt(v1), CV_TWO_PI * v2);
      }
      s.d = o;
    } else {
      s.end = t_ground < CV_PATH_FAR ? CV_PATH_GROUND : CV_PATH_SPACE;
      // Into the sky: its light from that direction (none without air). The view ray's from the
      // camera, as a pixel that misses the grid sees it (path_miss), the air in front of a black
      // ground included (the march draws that air too), and the fragments on it.
      if (front) path_front(s, CV_PATH_FAR, c);
      else if (s.end == CV_PATH_SPACE) s.radiance += s.beta * u_irradiance * path_sky(s.p, s.d, c);
      s.done = true;
    }
  }
}

// One whole path from p along unit d.
CV_FN PathResult trace_path(real3 p, real3 d, CV_INOUT(TrackRng) rng, CV_INOUT(TrackCounts) c, CV_INOUT(PathCounts) pc) {
  PathState s = path_begin(p, d);
  path_advance(s, rng, c, pc, 0xFFFFFFFFu);
  PathResult r;
  r.escaped = real3(0.0);
  r.grounded = real3(0.0);
  r.scatterings_branches = 0;
#ifdef CV_PATH_SPLIT
  // The branches, last made first: their light joins the path's.
  PathState b;
  while (path_pop(b)) {
    int b0 = b.scatterings;  // the vertices before the split are the path's
    path_advance(b, rng, c, pc, 0xFFFFFFFFu);
    s.radiance += b.radiance;
    s.absorbed += b.absorbed;
    r.escaped += b.end == CV_PATH_SPACE ? b.beta : real3(0.0);
    r.grounded += b.end == CV_PATH_GROUND ? b.beta : real3(0.0);
    r.scatterings_branches += b.scatterings - b0;
  }
#endif
  r.escaped += s.end == CV_PATH_SPACE ? s.beta : real3(0.0);
  r.grounded += s.end == CV_PATH_GROUND ? s.beta : real3(0.0);
  r.radiance = s.radiance;
  r.weight = s.beta;
  r.absorbed = s.absorbed;
  r.end = s.end;
  r.scatterings = s.scatterings;
  return r;
}
