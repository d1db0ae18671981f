// The two-stream source: a delta-scaled two-stream column per grid column, fed by the sun's beam in 3-D.
#include "kernel/ms_source.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <utility>

#include <glm/vec2.hpp>

#include "geo/geodesy.hpp"
#include "io/parallel.hpp"
#include "kernel/ms_beam.glsl"
#include "kernel/ms_slab.glsl"
#include "kernel/ms_lateral.hpp"
#include "kernel/ms_slab.hpp"
#include "physics/physics.hpp"
#include "volume/sampler.hpp"

namespace cv::core {
namespace {
constexpr double kPi = 3.14159265358979323846;
}

// The two-stream fluxes up and down, F+ and F-, of a conservative column (omega = 1), delta-scaled:
// f = g^2, dtau' = (1 - f) dtau, g' = g / (1 + g), lit by the sun's scaled beam E (irradiance
// normal to the beam per unit incident; plane-parallel E = exp(-tau'/mu0), or given per node),
// which keeps the light the forward peak scatters; tau' downward from the top:
//   dF+/dtau' = gamma1 (F+ - F-) - gamma3 E,   dF-/dtau' = gamma1 (F+ - F-) + gamma4 E,
// gamma4 = 1 - gamma3, gamma1 = c (1 - g') (gamma2 = gamma1 with no absorption). The net flux
// N = F+ - F- and the sum S = F+ + F- then integrate in closed form, for any g' per layer and any
// beam: dN/dtau' = -E gives N = N0 - D with D = int E dtau' (the beam's light deposited above);
// dS/dtau' = 2 gamma1 N + (gamma4 - gamma3) E gives
//   S = N0 + 2 c int (1 - g') (N0 - D) dtau' + B,  B = int (1 - 2 gamma3) E dtau',
// with no diffuse light down at the top (S0 = N0). At the bottom the upward diffuse flux is the
// ground's albedo A times what reaches it: (1 - A) S + (1 + A) N = 2 A mu0 E, linear in N0:
//   N0 ((1 - A)(1 + 2 c G) + 1 + A) = 2 A mu0 E + (1 - A)(2 c H - B) + (1 + A) D   (at the bottom),
// G = int (1 - g') dtau' = int (1 - g) dtau, H = int (1 - g') D dtau'; the coefficient is never
// small. Between nodes E is exponential (its two ends), so each layer's integrals are exact:
// int E = dt (E1 - E2) / z and int (dt - x) E = dt^2 (E1 (z - 1) + E2) / z^2, z = ln(E1 / E2),
// by their series where |z| is small; the second pass sums 2 c int (1 - g') (N0 - D) with N0 - D
// (the net flux, small deep in thick cloud) formed at each node, so no optical depth cancels.
// The radiance I0 + I1 mu with these hemispheric fluxes (F+- = pi (I0 +- 2/3 I1)) has
// I0 = S / 2 pi and I1 = 3 N / 4 pi. With Eddington's gamma1 and gamma3 and the plane-parallel beam
// this is the delta-Eddington solution (its moment equations dI1/dtau' = -(3/4 pi) e,
// dI0/dtau' = (1 - g') I1 + (3 g' mu0/4 pi) e).
TwoStreamColumn two_stream_column(const double* sigma, const double* g, int n, double dz, double mu0, double a,
                                  TwoStreamClosure closure, const double* beam) {
  TwoStreamColumn c;
  c.i0.assign(static_cast<std::size_t>(std::max(n, 0)), 0.0);
  c.i1.assign(c.i0.size(), 0.0);
  if (n < 1 || !(mu0 > 0.0)) return c;
  a = std::clamp(std::isfinite(a) ? a : 0.0, 0.0, 1.0);
  dz = std::abs(dz);
  const bool eddington = closure == TwoStreamClosure::Eddington;
  const double s3 = std::sqrt(3.0);
  const double cc = eddington ? 0.75 : 0.5 * s3;  // gamma1 / (1 - g')
  auto one_minus_2gamma3 = [&](double gp) { return (eddington ? 1.5 : s3) * gp * mu0; };  // 1 - 2 gamma3
  const std::size_t N = c.i0.size();
  // Per node: the scaled optical depth from the top, the beam and D; per layer (below node k + 1,
  // stored at k): its scaled depth, 1 - g' and int (dt - x) E.
  std::vector<double> tau(N, 0.0), e(N, 0.0), dep(N, 0.0), dt(N, 0.0), omg(N, 0.0), ie2(N, 0.0);
  for (int k = n - 2; k >= 0; --k) {
    const std::size_t K = static_cast<std::size_t>(k);
    const double s0 = std::max(sigma[k + 1], 0.0), s1 = std::max(sigma[k], 0.0);
    const double st = s0 + s1;
    const double dtau = std::isfinite(st) ? 0.5 * st * dz : 0.0;
    const double gl = st > 0.0 ? std::clamp((s0 * g[k + 1] + s1 * g[k]) / st, -0.999, 0.999) : 0.0;
    dt[K] = (1.0 - gl * gl) * dtau;
    omg[K] = 1.0 - gl / (1.0 + gl);
    tau[K] = tau[K + 1] + dt[K];
  }
  for (std::size_t k = 0; k < N; ++k) {
    e[k] = beam ? (std::isfinite(beam[k]) ? std::clamp(beam[k], 0.0, 1.0) : 0.0) : std::exp(-tau[k] / mu0);
  }
  // The beam's decay across a layer, z = ln(E1 / E2): the plane-parallel dt / mu0 exactly; for a
  // given beam from its ends, at least dt / mu0 where the lower end underflows (its light then lies
  // in the layer's top), and from 1e-300 where an end is 0.
  constexpr double kTiny = 1e-300;
  auto decay = [&](double d, double e1, double e2) {
    if (!beam) return d / mu0;
    double z = std::log(std::max(e1, kTiny) / std::max(e2, kTiny));
    if (e2 < kTiny) z = std::max(z, d / mu0);
    return z;
  };
  double big_g = 0.0, big_h = 0.0, big_b = 0.0;
  for (int k = n - 2; k >= 0; --k) {
    const std::size_t K = static_cast<std::size_t>(k);
    const double d = dt[K], e1 = e[K + 1], e2 = e[K];
    double i1 = 0.0, i2 = 0.0;
    if (d > 0.0 && (e1 > 0.0 || e2 > 0.0)) {
      const double z = decay(d, e1, e2);
      if (std::abs(z) < 1e-3) {
        i1 = d * e1 * (1.0 - z * (0.5 - z / 6.0));
        i2 = d * d * e1 * (0.5 - z * (1.0 / 6.0 - z / 24.0));
      } else {
        const double iz = 1.0 / z;  // 0 for a beam gone within the layer (mu0 -> 0: z = inf)
        i1 = d * (e1 - e2) * iz;
        i2 = d * d * (e1 * (1.0 - iz) + e2 * iz) * iz;
      }
    }
    ie2[K] = i2;
    dep[K] = dep[K + 1] + i1;
    big_g += omg[K] * d;
    big_h += omg[K] * (dep[K + 1] * d + i2);
    big_b += one_minus_2gamma3(1.0 - omg[K]) * i1;
  }
  const double e_b = e[0];
  const double n0 = (2.0 * a * mu0 * e_b + (1.0 - a) * (2.0 * cc * big_h - big_b) + (1.0 + a) * dep[0]) /
                    ((1.0 - a) * (1.0 + 2.0 * cc * big_g) + 1.0 + a);
  double k2 = 0.0, bsum = 0.0;  // int (1 - g') (N0 - D) dtau' and B, from the top
  for (int k = n - 1; k >= 0; --k) {
    const std::size_t K = static_cast<std::size_t>(k);
    if (k < n - 1) {
      k2 += omg[K] * ((n0 - dep[K + 1]) * dt[K] - ie2[K]);
      bsum += one_minus_2gamma3(1.0 - omg[K]) * (dep[K] - dep[K + 1]);
    }
    c.i0[K] = (n0 + 2.0 * cc * k2 + bsum) / (2.0 * kPi);
    c.i1[K] = 3.0 * (n0 - dep[K]) / (4.0 * kPi);
  }
  const std::size_t top = N - 1;
  c.reflected = kPi * (c.i0[top] + (2.0 / 3.0) * c.i1[top]) / mu0;
  const double down = kPi * (c.i0[0] - (2.0 / 3.0) * c.i1[0]) + mu0 * e_b;
  c.transmitted = down / mu0;
  c.absorbed_ground = (1.0 - a) * down / mu0;
  return c;
}

std::string ms_columns_alone_why(const VolumeGrid& grid, const MsSourceKey& key) {
  if (!key.lateral) return "the exchange was turned off (MsSourceKey::lateral)";
  if (grid.points() > kLateralMaxNodes) {
    return "the grid's " + std::to_string(grid.points()) + " nodes are beyond the " + std::to_string(kLateralMaxNodes) +
           " the exchange is solved on";
  }
  if (static_cast<std::size_t>(std::max(grid.lon_deg.count, 0)) * static_cast<std::size_t>(std::max(grid.lat_deg.count, 0)) <= 1) {
    return "the grid has one column";
  }
  return "";
}

MsSourceKey ms_source_key(const MarchSettings& s, const glm::dvec3& to_sun, const AlbedoMap* ground) {
  MsSourceKey k;
  k.to_sun = to_sun;
  const physics::f64::MieParams mie = physics::f64::mie_params(s.medium.droplet_diameter_um);
  k.liquid_g = physics::f64::mie_mean_cosine(mie);  // HG for liquid has the same mean cosine
  k.ice_g = s.medium.ice_g;
  k.ground_albedo = s.features.globe ? (s.medium.ground_albedo.x + s.medium.ground_albedo.y + s.medium.ground_albedo.z) / 3.0 : 0.0;
  k.mask = medium_mask(s);
  k.slab = ms_slab_on(s);
  if (s.features.globe && ground && ground->width > 0 && ground->height > 0 &&
      ground->rgba.size() == 4 * static_cast<std::size_t>(ground->width) * static_cast<std::size_t>(ground->height)) {
    k.ground = ground;
    k.ground_id = ground->id;
  }
  return k;
}

double column_ground_albedo(const AlbedoMap& map, double lat_deg, double lon_deg) {
  namespace p = physics::f64;
  constexpr double kRad = 3.14159265358979323846 / 180.0;
  if (!std::isfinite(lat_deg) || !std::isfinite(lon_deg)) return 0.0;
  lon_deg = std::fmod(lon_deg, 360.0);  // a huge longitude would lose the texel to rounding
  const glm::dvec4 c = p::equirect_texel(std::clamp(lat_deg, -90.0, 90.0) * kRad, lon_deg * kRad, map.width, map.height);
  const int x0 = std::clamp(static_cast<int>(c.x), 0, map.width - 1), y0 = std::clamp(static_cast<int>(c.y), 0, map.height - 1);
  const int x1 = (x0 + 1) % map.width, y1 = std::min(y0 + 1, map.height - 1);
  auto texel = [&](int x, int y) {
    const std::size_t i = 4 * (static_cast<std::size_t>(y) * static_cast<std::size_t>(map.width) + static_cast<std::size_t>(x));
    return glm::dvec4(map.rgba[i], map.rgba[i + 1], map.rgba[i + 2], map.rgba[i + 3]);
  };
  const glm::dvec4 t = glm::mix(glm::mix(texel(x0, y0), texel(x1, y0), c.z), glm::mix(texel(x0, y1), texel(x1, y1), c.z), c.w);
  // The march's diffuse albedo of the ground (land, or water by the water fraction), grey.
  const glm::dvec3 rgb = p::ground_diffuse_albedo(glm::dvec3(t), t.w);
  const double a = (rgb.x + rgb.y + rgb.z) / 3.0;
  return std::isfinite(a) ? std::clamp(a, 0.0, 0.99) : 0.0;
}

double column_ground_albedo(const AlbedoMap& map, double lat_deg, double lon_deg, double dlat_deg, double dlon_deg) {
  if (map.width <= 0 || map.height <= 0) return 0.0;
  constexpr double kRad = 3.14159265358979323846 / 180.0;
  const double span_lat = std::isfinite(dlat_deg) ? std::clamp(std::abs(dlat_deg), 0.0, 180.0) : 0.0;
  const double span_lon = std::isfinite(dlon_deg) ? std::clamp(std::abs(dlon_deg), 0.0, 360.0) : 0.0;
  // Lattice points per axis: one per texel the footprint spans, at least one, at most 32.
  auto points = [](double span, double texel) { return std::clamp(static_cast<int>(std::ceil(span / texel - 1e-9)), 1, 32); };
  const int n_lat = points(span_lat, 180.0 / map.height), n_lon = points(span_lon, 360.0 / map.width);
  if (n_lat == 1 && n_lon == 1) return column_ground_albedo(map, lat_deg, lon_deg);
  double sum = 0.0, weight = 0.0;
  for (int a = 0; a < n_lat; ++a) {
    const double lat = std::clamp(lat_deg + span_lat * ((a + 0.5) / n_lat - 0.5), -90.0, 90.0);
    const double w = std::max(std::cos(lat * kRad), 0.0);
    for (int b = 0; b < n_lon; ++b) {
      sum += w * column_ground_albedo(map, lat, lon_deg + span_lon * ((b + 0.5) / n_lon - 0.5));
      weight += w;
    }
  }
  return weight > 0.0 ? sum / weight : column_ground_albedo(map, lat_deg, lon_deg);
}

namespace {
// sun_beam_field into `beam` (grid.points() floats, none of them `scaled`'s): the levels above
// top_level are set to 1, every node at or below it is written.
void sweep_sun_beam(const VolumeGrid& grid, const float* scaled, const glm::dvec3& to_sun_in, int top_level, float* beam) {
  const int nx = grid.lon_deg.count, ny = grid.lat_deg.count, nz = grid.alt_m.count;
  if (nx < 1 || ny < 1 || nz < 1) {
    std::fill(beam, beam + grid.points(), 1.0f);
    return;
  }
  const glm::dvec3 to_sun = glm::length(to_sun_in) > 0.0 ? glm::normalize(to_sun_in) : glm::dvec3(0.0, 0.0, 1.0);
  const bool wraps = grid.wraps_lon();
  static const std::vector<float> kNoField;
  const bool global_lat = VolumeSampler(grid, kNoField).global_lat();  // rows to the poles: latitude clamps, as the march reads
  const double d2r = kPi / 180.0, dz = std::abs(grid.alt_m.step);
  top_level = std::clamp(top_level, 0, nz - 1);
  const std::size_t layer = static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny);
  std::fill(beam + static_cast<std::size_t>(top_level + 1) * layer, beam + grid.points(), 1.0f);
  // Per column: the sun's cosine mu0 to the local vertical and its horizontal direction (index
  // units per metre of arc on the reference sphere), and the pieces of path per level. The ray to
  // the sun is straight over a curved Earth: from a node at radius r it reaches the radius of m
  // levels up after s = -r mu0 + sqrt(r^2 mu0^2 + (2 r + m dz) m dz) (for mu0 well above 0 about
  // m dz / mu0, the flat column; for a sun at or a little below the local horizon tens of
  // kilometres, where the flat column's dz / mu0 grew without bound), first dipping below the node
  // where the sun is below its horizon. A node whose ray meets the Earth (the sun below the
  // horizon by more than the dip at its height) is in the Earth's shadow: no beam.
  struct Shift {
    double mu0 = 1.0, sin0 = 0.0;  // the sun's cosine and sine to the local vertical
    bool flat = true;              // a sun high enough that the Earth's curve changes a hop's path by under 0.5 %
    double ie = 0.0, jn = 0.0;     // index units per metre of arc along the sun's horizontal direction
    int sub = 1;                   // pieces of path per level
  };
  const double R = grid.earth_radius_m;
  const double r_top = R + grid.alt_m.at(top_level);
  std::vector<Shift> shift(static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny));
  // Along the ray from a node at radius r: the distance to m levels up, and at distance t the
  // height above the node and the arc (m) on the reference sphere.
  auto reach = [&](const Shift& s, double r, int m) {
    const double rise = m * dz;
    if (s.flat) return rise / s.mu0;
    return -r * s.mu0 + std::sqrt(std::max(r * r * s.mu0 * s.mu0 + (2.0 * r + rise) * rise, 0.0));
  };
  // (The height as (2 r mu0 t + t^2) / (rho + r), without the cancellation of rho - r; the arc's
  // arctangent by its series where the angle is small, as it is but for long grazing paths.)
  auto lift = [&](const Shift& s, double r, double t) {
    if (s.flat) return t * s.mu0;
    const double num = (2.0 * r * s.mu0 + t) * t;
    return num / (std::sqrt(std::max(r * r + num, 0.0)) + r);
  };
  auto arc = [&](const Shift& s, double r, double t) {
    if (s.flat) return t * s.sin0;
    const double y = t * s.sin0, x = r + t * s.mu0;
    if (x > 0.0 && y < 1e-2 * x) {
      const double u = y / x, u2 = u * u;
      return R * u * (1.0 - u2 * (1.0 / 3.0 - u2 * (0.2 - u2 / 7.0)));
    }
    return R * std::atan2(y, x);
  };
  auto shadowed = [&](const Shift& s, double r) { return s.mu0 < 0.0 && r * s.sin0 <= R; };
  for (int j = 0; j < ny; ++j) {
    const double lat = grid.lat_deg.at(j);
    const double dx = grid.earth_radius_m * std::cos(lat * d2r) * grid.lon_deg.step * d2r;
    const double dy = grid.earth_radius_m * grid.lat_deg.step * d2r;
    for (int i = 0; i < nx; ++i) {
      const geo::EnuFrame f = geo::sphere_enu(lat, grid.lon_deg.at(i));
      Shift& s = shift[static_cast<std::size_t>(j) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(i)];
      s.mu0 = std::clamp(glm::dot(f.up, to_sun), -1.0, 1.0);
      s.sin0 = std::sqrt(std::max(1.0 - s.mu0 * s.mu0, 0.0));
      s.flat = s.mu0 >= 0.3;
      const double he = glm::dot(f.east, to_sun), hn = glm::dot(f.north, to_sun);
      if (s.sin0 > 1e-12) {
        s.ie = std::abs(dx) > 1e-9 ? he / s.sin0 / dx : 0.0;
        s.jn = std::abs(dy) > 1e-9 ? hn / s.sin0 / dy : 0.0;
      }
      const double a1 = arc(s, r_top, reach(s, r_top, 1));
      s.sub = static_cast<int>(std::clamp(std::ceil(2.0 * a1 * std::max(std::abs(s.ie), std::abs(s.jn))), 1.0, 64.0));
    }
  }
  // Index-space lookups: outside a regional grid is clear air; longitude wraps on global grids and
  // latitude clamps at the edge rows.
  auto column_of = [&](double fi, double fj, int& i0, int& i1, int& j0, int& j1, double& wi, double& wj) {
    if (!(std::isfinite(fi) && std::isfinite(fj))) return false;
    if (wraps) {
      if (fi < 0.0 || fi >= nx) {  // fmod only off the grid: most points are on it
        fi = std::fmod(fi, double(nx));
        if (fi < 0.0) fi += nx;
      }
    } else if (fi < 0.0 || fi > nx - 1) {
      return false;
    }
    if (fj < 0.0 || fj > ny - 1) {
      if (!global_lat) return false;
      fj = std::clamp(fj, 0.0, double(ny - 1));
    }
    i0 = std::min(static_cast<int>(fi), nx - 1), j0 = std::min(static_cast<int>(fj), ny - 1);
    wi = fi - i0, wj = fj - j0;
    i1 = wraps ? (i0 + 1) % nx : std::min(i0 + 1, nx - 1);
    j1 = std::min(j0 + 1, ny - 1);
    return true;
  };
  // A point's bilinear reading, found once and read on any level (the last point of a path reads
  // the extinction and the optical depth already reached there).
  struct Tap {
    std::size_t c00 = 0, c10 = 0, c01 = 0, c11 = 0;
    double wi = 0.0, wj = 0.0;
    bool in = false;
    double on(const float* lv) const {
      if (!in) return 0.0;
      return (1.0 - wj) * ((1.0 - wi) * double(lv[c00]) + wi * double(lv[c10])) + wj * ((1.0 - wi) * double(lv[c01]) + wi * double(lv[c11]));
    }
  };
  auto tap_at = [&](double fi, double fj) {
    Tap t;
    int i0, i1, j0, j1;
    if (!column_of(fi, fj, i0, i1, j0, j1, t.wi, t.wj)) return t;
    const std::size_t r0 = static_cast<std::size_t>(j0) * static_cast<std::size_t>(nx), r1 = static_cast<std::size_t>(j1) * static_cast<std::size_t>(nx);
    t.c00 = r0 + static_cast<std::size_t>(i0), t.c10 = r0 + static_cast<std::size_t>(i1);
    t.c01 = r1 + static_cast<std::size_t>(i0), t.c11 = r1 + static_cast<std::size_t>(i1);
    t.in = true;
    return t;
  };
  // The scaled extinction at distance t along the ray from node (i, j) on level k (radius r): read
  // at the point's height (linear between the two levels around it; clear air below the lowest).
  auto extinction = [&](const Shift& sh, double r, int i, int j, int k, double t) {
    const double a = arc(sh, r, t);
    const double lv = std::min(k + lift(sh, r, t) / dz, double(nz - 1));  // the point's level, fractional
    if (!(lv >= 0.0)) return 0.0;
    const int lo = std::min(static_cast<int>(lv), nz - 1);
    const double w = lv - lo;
    const Tap tp = tap_at(i + a * sh.ie, double(j) + a * sh.jn);
    const float* s0 = scaled + static_cast<std::size_t>(lo) * layer;
    double v = tp.on(s0);
    if (w > 1e-9 && lo + 1 < nz) v = (1.0 - w) * v + w * tp.on(s0 + layer);
    return v;
  };
  // How far along the ray from node (i, j) it stays over a regional grid (infinite where the grid
  // wraps or reaches the poles on the axis it leaves by): beyond is clear air.
  auto inside = [&](const Shift& sh, double r, int i, int j) {
    constexpr double kFar = 1e30;
    double a_out = kFar;  // the arc (m) at which the point's index leaves [0, n - 1]
    if (!wraps && sh.ie != 0.0) a_out = std::min(a_out, ((sh.ie > 0.0 ? nx - 1 - i : -i)) / sh.ie);
    if (!global_lat && sh.jn != 0.0) a_out = std::min(a_out, ((sh.jn > 0.0 ? ny - 1 - j : -j)) / sh.jn);
    if (!(a_out < kFar)) return kFar;
    if (sh.flat) return a_out / sh.sin0;  // ie or jn is not 0, so neither is sin0
    // The ray's arc grows as R atan(t sin0 / (r + t mu0)): invert it (beyond its reach, far).
    const double th = a_out / R;
    if (!(th < 0.5 * kPi)) return kFar;
    const double tn = std::tan(th), den = sh.sin0 - sh.mu0 * tn;
    return den > 0.0 ? std::max(r * tn / den, 0.0) : kFar;
  };
  // beam holds tau' on the levels swept while the sweep runs (each is written before a level below
  // reads it), then exp(-tau'); above top_level it stays 1.
  constexpr int stride = 8;
  // Per column, the number of levels m (1..stride) after which the upstream point lies nearest to
  // grid nodes: the bilinear reading of the optical depth there smears least per level (the smear
  // of one reading is frac (1 - frac) cells squared in each direction). At most 64 pieces of path
  // per node: a low sun's long steps take one level at a time. The fewest levels whose smear is
  // within 1.5 times the least (plus 0.002 cells^2 per level): where the sun is high the upstream
  // point moves a small part of a cell per level, the smear is about that part whatever m is, and
  // one level at a time costs least.
  std::vector<std::uint8_t> hop(shift.size(), 1);
  for (std::size_t c = 0; c < shift.size(); ++c) {
    const Shift& sh = shift[c];
    const int most = std::clamp(64 / std::max(sh.sub, 1), 1, stride);
    auto smear = [&](int m) {
      auto f = [](double x) {
        const double r = x - std::floor(x);
        return r * (1.0 - r);
      };
      const double a = arc(sh, r_top, reach(sh, r_top, m));
      return (f(a * sh.ie) + f(a * sh.jn)) / m;
    };
    double best = 1e30;
    for (int m = 1; m <= most; ++m) best = std::min(best, smear(m));
    for (int m = 1; m <= most; ++m) {
      if (smear(m) <= 1.5 * best + 0.002) {
        hop[c] = static_cast<std::uint8_t>(m);
        break;
      }
    }
  }
  for (int k = top_level; k >= 0; --k) {
    const double r = R + grid.alt_m.at(k);
    parallel_ranges(static_cast<std::size_t>(ny), 16, [&](std::size_t jb, std::size_t je, unsigned) {
      for (std::size_t j = jb; j < je; ++j) {
        for (int i = 0; i < nx; ++i) {
          const std::size_t c = j * static_cast<std::size_t>(nx) + static_cast<std::size_t>(i);
          const Shift& sh = shift[c];
          const int m = std::min(int(hop[c]), nz - 1 - k);
          double tau = 0.0;
          if (shadowed(sh, r)) {
            tau = 1e30;
          } else if (m > 0) {
            // The path up m levels by the trapezoid on sub pieces per level (each point read at its
            // height: a level alone where it lies on one, else linear between the two levels around
            // it, clear air below the grid's lowest level), then the optical depth already reached
            // at the upstream point on level k + m. Where the path leaves a regional grid before
            // that level, the pieces cover the part inside it (the rest is clear air): a long
            // grazing path keeps its pieces where the cloud is.
            const int pieces = sh.sub * m;
            const double s_m = reach(sh, r, m);
            const double t_end = std::min(s_m, inside(sh, r, i, static_cast<int>(j)));
            double sum = 0.5 * double(scaled[static_cast<std::size_t>(k) * layer + c]);
            for (int q = 1; q < pieces; ++q) sum += extinction(sh, r, i, static_cast<int>(j), k, t_end * q / pieces);
            if (t_end < s_m) {
              sum += 0.5 * extinction(sh, r, i, static_cast<int>(j), k, t_end);
              tau = sum * t_end / pieces;
            } else {
              // The last point, on level k + m: its extinction ends the path, its optical depth adds.
              const double a = arc(sh, r, s_m);
              const Tap last = tap_at(i + a * sh.ie, double(j) + a * sh.jn);
              const std::size_t up = static_cast<std::size_t>(k + m) * layer;
              sum += 0.5 * last.on(scaled + up);
              tau = sum * s_m / pieces + (k + m <= top_level ? last.on(beam + up) : 0.0);
            }
          } else if (sh.mu0 < 0.0) {
            // The grid's top level under a sun below its horizon: the ray dips through the cloud
            // below and is back at this height after -2 r mu0, clear air above.
            const int pieces = std::max(sh.sub, 8);
            const double t_end = std::min(-2.0 * r * sh.mu0, inside(sh, r, i, static_cast<int>(j)));
            double sum = 0.5 * double(scaled[static_cast<std::size_t>(k) * layer + c]);
            for (int q = 1; q <= pieces; ++q) {
              const double v = extinction(sh, r, i, static_cast<int>(j), k, t_end * q / pieces);
              sum += q == pieces ? 0.5 * v : v;
            }
            tau = sum * t_end / pieces;
          }
          beam[static_cast<std::size_t>(k) * layer + c] = static_cast<float>(std::min(tau, 1e30));
        }
      }
    });
  }
  const std::size_t swept = static_cast<std::size_t>(top_level + 1) * layer;
  parallel_ranges(swept, std::size_t(1) << 16, [&](std::size_t b, std::size_t e, unsigned) {
    for (std::size_t n = b; n < e; ++n) beam[n] = static_cast<float>(std::exp(-std::min(double(beam[n]), 700.0)));
  });
}
}  // namespace

// The sun's delta-scaled beam per node, swept down level by level (see the header).
std::vector<float> sun_beam_field(const VolumeGrid& grid, const std::vector<float>& scaled, const glm::dvec3& to_sun, int top_level) {
  std::vector<float> beam(grid.points(), 1.0f);
  if (scaled.size() == grid.points()) sweep_sun_beam(grid, scaled.data(), to_sun, top_level, beam.data());
  return beam;
}

MsSource build_ms_source(const PreparedVolume& v, const MsSourceKey& key) {
  const auto t0 = std::chrono::steady_clock::now();
  const VolumeGrid& grid = v.grid;
  const int nx = grid.lon_deg.count, ny = grid.lat_deg.count, nz = grid.alt_m.count;
  const std::size_t layer = static_cast<std::size_t>(std::max(nx, 0)) * static_cast<std::size_t>(std::max(ny, 0));
  MsSource out;
  const glm::dvec3 to_sun = glm::length(key.to_sun) > 0.0 ? glm::normalize(key.to_sun) : glm::dvec3(0.0);
  // The medium shown at a node (the layer mask and the hidden phases as the march reads them):
  // liquid and ice extinction.
  auto shown_at = [&](int i, int j, int k, double& sl, double& si) {
    // The column's ground, as the march's band test reads it at a node (the column map's second channel).
    const std::size_t col = grid.column(i, j), idx = grid.index(i, j, k);
    const double ground = kColumnMapChannels * col + 1 < v.column_maps.size() ? double(v.column_maps[kColumnMapChannels * col + 1]) : 0.0;
    const bool shown = key.mask.shown(grid.alt_m.at(k), ground);
    sl = shown && !key.mask.hide_liquid ? std::max(0.0, double(v.extinction.liquid_per_m[idx])) : 0.0;
    si = shown && !key.mask.hide_ice ? std::max(0.0, double(v.extinction.ice_per_m[idx])) : 0.0;
  };
  // The two outputs hold the build's scratch until the columns overwrite them, so a global grid's
  // build makes no arrays beyond its output (fresh pages cost more than the arithmetic here): i0
  // holds the delta-scaled extinction the beam meets, i1 the beam (sun_beam_field). Each column
  // reads its own beam before it writes its i0 and i1; a column left out is zeroed.
  out.i0.assign(grid.points(), 0.0f);
  out.i1.assign(grid.points(), 0.0f);
  if (key.slab) out.tau_above.assign(grid.points(), 0.0f), out.tau_below.assign(grid.points(), 0.0f), out.sigma.assign(grid.points(), 0.0f);
  float* scaled = out.i0.data();
  float* beam = out.i1.data();
  // The scaled extinction, and the highest level with cloud (the beam is whole above the level
  // over it), rows on the machine's cores.
  std::vector<int> row_top(static_cast<std::size_t>(std::max(ny, 0)), -1);
  parallel_ranges(static_cast<std::size_t>(std::max(ny, 0)), 8, [&](std::size_t jb, std::size_t je, unsigned) {
    for (std::size_t jj = jb; jj < je; ++jj) {
      const int j = static_cast<int>(jj);
      for (int k = 0; k < nz; ++k) {
        for (int i = 0; i < nx; ++i) {
          double sl, si;
          shown_at(i, j, k, sl, si);
          if (!(sl + si > 0.0)) continue;
          scaled[grid.index(i, j, k)] = static_cast<float>(sl * (1.0 - key.liquid_g * key.liquid_g) + si * (1.0 - key.ice_g * key.ice_g));
          row_top[jj] = std::max(row_top[jj], std::min(k + 1, nz - 1));
        }
      }
    }
  });
  const int top_level = row_top.empty() ? -1 : *std::max_element(row_top.begin(), row_top.end());
  out.columns_alone = ms_columns_alone_why(grid, key);
  if (top_level < 0) {  // no cloud: nothing to exchange either
    if (out.columns_alone.empty()) out.lateral_iterations = 0;
    if (key.slab) out.slab_excess.assign(out.i0.size(), 0.0f), out.slab_ground.assign(out.i0.size(), 0.0f);  // all four fields, all 0
    out.build_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    return out;
  }
  // The sun's beam through the cloud in three dimensions: light that enters a cloud's sunlit side
  // feeds its columns as light through the top does (docs/physics.md, "The columns lit by the
  // beam in three dimensions").
  sweep_sun_beam(grid, scaled, to_sun, top_level, beam);
  // Each column's ground: the map's under its footprint where the march draws one, else the
  // constant; made when a cloudy column first asks (each column belongs to one thread at a time).
  std::vector<double> ground(layer, std::numeric_limits<double>::quiet_NaN());
  auto ground_at = [&](int i, int j) {
    double& g = ground[grid.column(i, j)];
    if (std::isnan(g)) {
      g = key.ground ? column_ground_albedo(*key.ground, grid.lat_deg.at(j), grid.lon_deg.at(i), grid.lat_deg.step, grid.lon_deg.step)
                     : key.ground_albedo;
    }
    return g;
  };
  // Light between the columns (docs/physics.md, "Light between the columns"): the 3-D diffusion of
  // the scaled problem against the columns' own, from the same beam, before the columns overwrite it.
  LateralRatio lateral;
  std::vector<unsigned char> cloudy;  // per column: any cloud shown
  const bool use_lateral = out.columns_alone.empty();
  if (use_lateral) {
    const auto tl = std::chrono::steady_clock::now();
    LateralMedium lm;
    const std::size_t np = grid.points();
    lm.kappa.assign(np, 0.0f);
    lm.scaled.assign(np, 0.0f);
    lm.gcoef.assign(np, 0.0f);
    lm.beam.assign(beam, beam + np);
    lm.beam_dir.resize(layer);
    lm.ground.assign(layer, 0.0);
    cloudy.assign(layer, 0);
    parallel_ranges(static_cast<std::size_t>(ny), 8, [&](std::size_t jb, std::size_t je, unsigned) {
      for (std::size_t jj = jb; jj < je; ++jj) {
        const int j = static_cast<int>(jj);
        for (int i = 0; i < nx; ++i) {
          const std::size_t c = grid.column(i, j);
          const geo::EnuFrame enu = geo::sphere_enu(grid.lat_deg.at(j), grid.lon_deg.at(i));
          lm.beam_dir[c] = glm::dvec3(-glm::dot(enu.east, to_sun), -glm::dot(enu.north, to_sun), -glm::dot(enu.up, to_sun));
          for (int k = 0; k < nz; ++k) {
            double sl, si;
            shown_at(i, j, k, sl, si);
            const double kap = sl * (1.0 - key.liquid_g) + si * (1.0 - key.ice_g);
            if (!(kap > 0.0) || !std::isfinite(kap)) continue;
            const std::size_t a = grid.index(i, j, k);
            lm.kappa[a] = static_cast<float>(kap);
            lm.scaled[a] = static_cast<float>(sl * (1.0 - key.liquid_g * key.liquid_g) + si * (1.0 - key.ice_g * key.ice_g));
            lm.gcoef[a] = static_cast<float>((sl * (1.0 - key.liquid_g) * key.liquid_g + si * (1.0 - key.ice_g) * key.ice_g) / kap);
            cloudy[c] = 1;
          }
          if (cloudy[c]) lm.ground[c] = ground_at(i, j);
        }
      }
    });
    // The sunlit ground of a clear column beside cloud (its sunlight A mu0 E at the lowest level)
    // lights the cloud's sides that face it (docs/physics.md, "Light between the columns").
    lm.ground_light.assign(layer, 0.0);
    const bool wrap = grid.wraps_lon();
    if (key.ground || key.ground_albedo > 0.0) {
      parallel_ranges(static_cast<std::size_t>(ny), 8, [&](std::size_t jb, std::size_t je, unsigned) {
        for (std::size_t jj = jb; jj < je; ++jj) {
          const int j = static_cast<int>(jj);
          for (int i = 0; i < nx; ++i) {
            const std::size_t c = grid.column(i, j);
            bool near = false;
            for (int dj = -1; dj <= 1 && !near && !cloudy[c]; ++dj) {
              for (int di = -1; di <= 1 && !near; ++di) {
                const int ii = wrap ? (i + di + nx) % nx : i + di, jn = j + dj;
                near = ii >= 0 && ii < nx && jn >= 0 && jn < ny && cloudy[grid.column(ii, jn)];
              }
            }
            if (near) lm.ground_light[c] = ground_at(i, j) * std::max(-lm.beam_dir[c].z, 0.0) * std::clamp(double(beam[c]), 0.0, 1.0);
          }
        }
      });
    }
    lateral = lateral_ratio(grid, lm);
    out.lateral_iterations = lateral.iterations;
    out.lateral_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - tl).count();
  }
  parallel_ranges(static_cast<std::size_t>(ny), 8, [&](std::size_t jb, std::size_t je, unsigned) {
    std::vector<double> sigma(static_cast<std::size_t>(nz)), g(static_cast<std::size_t>(nz)), col_beam(static_cast<std::size_t>(nz)),
        col_scaled(static_cast<std::size_t>(nz));
    std::vector<int> cloudy_below(static_cast<std::size_t>(nz)), cloudy_above(static_cast<std::size_t>(nz));
    for (std::size_t jj = jb; jj < je; ++jj) {
      const int j = static_cast<int>(jj);
      for (int i = 0; i < nx; ++i) {
        const std::size_t c = jj * static_cast<std::size_t>(nx) + static_cast<std::size_t>(i);
        auto clear = [&] {  // no source here: the scratch goes
          for (int k = 0; k < nz; ++k) out.i0[c + static_cast<std::size_t>(k) * layer] = 0.0f, out.i1[c + static_cast<std::size_t>(k) * layer] = 0.0f;
        };
        const double mu0 = glm::dot(geo::sphere_enu(grid.lat_deg.at(j), grid.lon_deg.at(i)).up, to_sun);
        bool any = false, lit = false;
        for (int k = 0; k < nz; ++k) {
          const std::size_t K = static_cast<std::size_t>(k);
          double sl, si;
          shown_at(i, j, k, sl, si);
          sigma[K] = sl + si;
          g[K] = sl + si > 0.0 ? (sl * key.liquid_g + si * key.ice_g) / (sl + si) : 0.0;
          col_beam[K] = beam[grid.index(i, j, k)];
          any = any || sl + si > 0.0;
          lit = lit || col_beam[K] > 0.0f;
        }
        // A clear column holds no diffuse light from cloud (the sky is the air's); a column the
        // beam reaches nowhere (the Earth's shadow) holds none either.
        if (!any || !lit || !std::isfinite(mu0)) {
          clear();
          continue;
        }
        // The sun below the column's horizon, its cloud lit through the air beside it (a sun up to
        // the dip at the cloud's height, a degree or three): the beam climbs, so the column is
        // solved upside down (its top the ground's side) with |mu0>, the ground dark (the sun is
        // below its horizon too; the light it would send back up is left out), and turned back.
        const bool below = !(mu0 > 0.0);
        if (below) {
          std::reverse(sigma.begin(), sigma.end());
          std::reverse(g.begin(), g.end());
          std::reverse(col_beam.begin(), col_beam.end());
        }
        const TwoStreamColumn tc = two_stream_column(sigma.data(), g.data(), nz, grid.alt_m.step, below ? std::max(-mu0, 1e-6) : mu0,
                                                     below ? 0.0 : ground_at(i, j), TwoStreamClosure::Quadrature, col_beam.data());
        for (int k = 0; k < nz; ++k) {
          const std::size_t K = static_cast<std::size_t>(below ? nz - 1 - k : k);
          out.i0[grid.index(i, j, k)] = static_cast<float>(tc.i0[K]);
          out.i1[grid.index(i, j, k)] = static_cast<float>(below ? -tc.i1[K] : tc.i1[K]);
        }
        if (key.slab) {
          // Where each node stands in the slab the march reads (docs/physics.md, "The higher-order
          // source"): above it the depth at which the slab's beam is the node's own 3-D beam,
          // -mu0 ln(beam) / (1 - g^2) (mu0 as the table reads it), at most the column's optical
          // depth (the trapezoid between levels): in a horizontally uniform cloud the depth from the
          // top, on a cloud's sunlit side near 0 (its light there is the newly scattered beam's), in
          // a shadow deep; below it the column's depth under it in the node's own phase, by
          // similarity: sum (1 - g_k^2) dtau_k / (1 - g^2), so that ice over water reads an ice slab
          // that reflects as the water under it does (the raw depth made ice of the water, and the
          // orbit's tropical columns 7 % bright; a clear node takes the g of its column's nearest
          // cloudy node). (The slab a node is measured against here thus holds t + b; the march reads
          // the table at the column's depth less t below. Measured against that slab instead, the
          // cumulus field went from -16 to -60 % and the towering cell from -3 to -19 %: BENCHMARKS.)
          double total = 0.0, total_scaled = 0.0;
          std::vector<double>& above_scaled = col_scaled;  // the depth from the column's top in (1 - g^2) dtau
          for (int k = nz - 1; k >= 0; --k) {
            const std::size_t K = static_cast<std::size_t>(k);
            if (k < nz - 1) {
              total += 0.5 * (sigma[K] + sigma[K + 1]) * grid.alt_m.step;
              total_scaled += 0.5 * (sigma[K] * (1.0 - g[K] * g[K]) + sigma[K + 1] * (1.0 - g[K + 1] * g[K + 1])) * grid.alt_m.step;
            }
            above_scaled[K] = total_scaled;
          }
          // Each level's nearest cloudy level at or below it and at or above it (-1: none).
          for (int k = 0, last = -1; k < nz; ++k) {
            if (sigma[static_cast<std::size_t>(k)] > 0.0) last = k;
            cloudy_below[static_cast<std::size_t>(k)] = last;
          }
          for (int k = nz - 1, last = -1; k >= 0; --k) {
            if (sigma[static_cast<std::size_t>(k)] > 0.0) last = k;
            cloudy_above[static_cast<std::size_t>(k)] = last;
          }
          const double mu0c = std::max(std::abs(mu0), double(CV_MS_SLAB_MU0_LO));
          for (int k = 0; k < nz; ++k) {
            const std::size_t a = grid.index(i, j, k);
            const std::size_t K = static_cast<std::size_t>(below ? nz - 1 - k : k);
            const double gk = g[K], e = std::clamp(double(col_beam[K]), 1e-300, 1.0);
            double gb = gk;  // the phase the node's depth below is counted in
            if (!(sigma[K] > 0.0)) {
              const int kb = cloudy_below[K], ka = cloudy_above[K], kk = static_cast<int>(K);
              if (kb >= 0 && (ka < 0 || kk - kb <= ka - kk)) {
                gb = g[static_cast<std::size_t>(kb)];
              } else if (ka >= 0) {
                gb = g[static_cast<std::size_t>(ka)];
              }
            }
            out.tau_above[a] = static_cast<float>(std::min(-mu0c * std::log(e) / (1.0 - gk * gk), total));
            out.tau_below[a] = static_cast<float>(std::max(total_scaled - above_scaled[K], 0.0) / (1.0 - gb * gb));
            out.sigma[a] = static_cast<float>(sigma[K]);
          }
        }
      }
    }
  });
  if (use_lateral) {
    // The columns' light scaled by the ratio, its horizontal first moment from the 3-D flux.
    out.i1e.assign(out.i0.size(), 0.0f);
    out.i1n.assign(out.i0.size(), 0.0f);
    parallel_ranges(out.i0.size(), 65536, [&](std::size_t b, std::size_t e, unsigned) {
      for (std::size_t a = b; a < e; ++a) {
        out.i0[a] *= lateral.ratio[a];
        out.i1[a] *= lateral.ratio[a];
        out.i1e[a] = out.i0[a] * lateral.east[a];
        out.i1n[a] = out.i0[a] * lateral.north[a];
      }
    });
    // A clear column beside cloudy ones: the march interpolates the source between its nodes and
    // theirs through cells that hold the cloud's fringe, so at a level where a neighbour (of its 8)
    // holds cloud within one level, it takes those neighbours' mean there (the light at the cloud's
    // edge) instead of 0. Other levels keep 0: the ground beside a cloud takes no diffuse light from
    // under it. Each neighbour's values count with the weight min(1, H / dx), H its cloud's height
    // (its cloudy levels' span and a level), dx the distance between the columns: light leaving a
    // cloud's side reaches a column dx away as the side's height over the distance (its angle seen
    // from there), and a fringe many cloud heights wide is its own thin column's (the orbit's
    // 550 km columns under clouds 5-11 km high: filled whole, +8 %, a thin fringe lit as the thick
    // cloud beside it; the cumulus field's 1.1 km columns under clouds as high keep the whole fill).
    const bool wrap = grid.wraps_lon();
    std::vector<float>* fields[7] = {&out.i0, &out.i1, &out.i1e, &out.i1n, &out.tau_above, &out.tau_below, &out.sigma};
    const int nf = key.slab ? 7 : 4;
    std::vector<float> cloud_height(layer, 0.0f);
    parallel_ranges(layer, 4096, [&](std::size_t b, std::size_t e, unsigned) {
      for (std::size_t c = b; c < e; ++c) {
        if (!cloudy[c]) continue;
        const int i = static_cast<int>(c % static_cast<std::size_t>(nx)), j = static_cast<int>(c / static_cast<std::size_t>(nx));
        int lo = -1, hi = -1;
        for (int k = 0; k < nz; ++k) {
          double sl, si;
          shown_at(i, j, k, sl, si);
          if (!(sl + si > 0.0)) continue;
          if (lo < 0) lo = k;
          hi = k;
        }
        if (lo >= 0) cloud_height[c] = static_cast<float>((hi - lo + 1) * std::abs(grid.alt_m.step));
      }
    });
    parallel_ranges(static_cast<std::size_t>(ny), 8, [&](std::size_t jb, std::size_t je, unsigned) {
      std::vector<glm::ivec2> near;
      std::vector<double> weights;  // min(1, H / dx) per neighbour in `near`
      for (std::size_t jj = jb; jj < je; ++jj) {
        const int j = static_cast<int>(jj);
        for (int i = 0; i < nx; ++i) {
          if (cloudy[grid.column(i, j)]) continue;
          near.clear();
          weights.clear();
          for (int dj = -1; dj <= 1; ++dj) {
            for (int di = -1; di <= 1; ++di) {
              int ii = i + di;
              const int jn = j + dj;
              if (wrap) ii = (ii + nx) % nx;
              if (ii < 0 || ii >= nx || jn < 0 || jn >= ny || (ii == i && jn == j)) continue;
              if (cloudy[grid.column(ii, jn)] && std::find(near.begin(), near.end(), glm::ivec2(ii, jn)) == near.end()) {
                near.emplace_back(ii, jn);
                const double dx = geo::great_circle_distance_m(grid.lat_deg.at(j), grid.lon_deg.at(i), grid.lat_deg.at(jn),
                                                               grid.lon_deg.at(ii), grid.earth_radius_m);
                weights.push_back(std::min(1.0, double(cloud_height[grid.column(ii, jn)]) / std::max(dx, 1e-3)));
              }
            }
          }
          for (int k = 0; k < nz && !near.empty(); ++k) {
            const std::size_t off = static_cast<std::size_t>(k) * layer;
            double sum[7] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
            int count = 0;
            for (std::size_t n = 0; n < near.size(); ++n) {
              const glm::ivec2 c = near[n];
              bool fringe = false;
              for (int kk = std::max(k - 1, 0); kk <= std::min(k + 1, nz - 1) && !fringe; ++kk) {
                double sl, si;
                shown_at(c.x, c.y, kk, sl, si);
                fringe = sl + si > 0.0;
              }
              if (!fringe) continue;
              ++count;
              for (int f = 0; f < nf; ++f) sum[f] += weights[n] * (*fields[f])[grid.column(c.x, c.y) + off];
            }
            if (count == 0) continue;
            for (int f = 0; f < nf; ++f) (*fields[f])[grid.column(i, j) + off] = static_cast<float>(sum[f] / count);
          }
        }
      }
    });
  }
  if (key.slab) {
    // The higher-order source's light per node against the homogeneous slab's with the node's
    // depths above and below it, over its column's ground, under its column's sun (as the march
    // reads the table: mu0 at least CV_MS_SLAB_MU0_LO; a column under a sun below its horizon has
    // no ground light): the difference from the slab's two-stream I0 (ms_slab_two_stream), and the
    // ground's albedo, with which the march finds the slab's ground radiance from the tables.
    // The march takes the slab's light (from the sun, and from the ground at that radiance) scaled
    // down where the sample holds less (a shaded column, an edge losing light), and adds what it
    // holds beyond as isotropic light (from neighbouring columns): the slab's shape belongs to the
    // light that came through the column. Where the medium's column at the sample holds the
    // nodes' slab it reads this difference (a difference interpolates between nodes without
    // amplifying anything: a ratio carried a thin column's ground light, times the slab's light
    // over its I0, into its thick neighbours; and it follows the slab between two nodes, where
    // the nodes' light, linear, does not); in a cloud's fringe, its own I0 against its column's
    // slab (march.glsl ms_slab_source_at, ms_slab_keep).
    out.slab_excess.assign(out.i0.size(), 0.0f);
    out.slab_ground.assign(out.i0.size(), 0.0f);
    parallel_ranges(static_cast<std::size_t>(ny), 8, [&](std::size_t jb, std::size_t je, unsigned) {
      for (std::size_t jj = jb; jj < je; ++jj) {
        const int j = static_cast<int>(jj);
        for (int i = 0; i < nx; ++i) {
          const double mu_true = glm::dot(geo::sphere_enu(grid.lat_deg.at(j), grid.lon_deg.at(i)).up, to_sun);
          const double mu0 = std::max(std::abs(mu_true), double(CV_MS_SLAB_MU0_LO));
          const double ground = mu_true > 0.0 ? ground_at(i, j) : 0.0;
          for (int k = 0; k < nz; ++k) {
            const std::size_t a = grid.index(i, j, k);
            if (!(out.i0[a] > 0.0f)) continue;
            double sl, si;
            shown_at(i, j, k, sl, si);
            const double g = sl + si > 0.0 ? (sl * key.liquid_g + si * key.ice_g) / (sl + si) : key.liquid_g;
            const MsSlabTwoStream ref = ms_slab_two_stream(out.tau_above[a], out.tau_below[a], mu0, g, ground);
            out.slab_excess[a] = static_cast<float>(double(out.i0[a]) - ref.i0);
            out.slab_ground[a] = static_cast<float>(ground);
          }
        }
      }
    });
  }
  out.build_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

namespace {
std::vector<float> interleave(const std::vector<float>& a, const std::vector<float>& b) {
  std::vector<float> out;
  if (a.empty() || a.size() != b.size()) return out;
  out.resize(2 * a.size());
  parallel_ranges(a.size(), 65536, [&](std::size_t lo, std::size_t hi, unsigned) {
    for (std::size_t i = lo; i < hi; ++i) out[2 * i] = a[i], out[2 * i + 1] = b[i];
  });
  return out;
}
}  // namespace

int ms_moments_channels(const MsSource& s) {
  const std::size_t n = s.i0.size();
  return !s.tau_above.empty() && s.tau_above.size() == n && s.tau_below.size() == n && s.slab_excess.size() == n &&
                 s.slab_ground.size() == n && s.sigma.size() == n
             ? 4
             : 2;
}

std::vector<float> ms_moments_texels(const MsSource& s) {
  if (ms_moments_channels(s) != 4) return interleave(s.i0, s.i1);
  std::vector<float> out(4 * s.i0.size());
  parallel_ranges(s.i0.size(), 65536, [&](std::size_t lo, std::size_t hi, unsigned) {
    for (std::size_t i = lo; i < hi; ++i) out[4 * i] = s.i0[i], out[4 * i + 1] = s.sigma[i], out[4 * i + 2] = s.tau_above[i], out[4 * i + 3] = s.slab_ground[i];
  });
  return out;
}
int ms_horizontal_channels(const MsSource& s) { return ms_moments_channels(s); }
std::vector<float> ms_horizontal_texels(const MsSource& s) {
  if (ms_horizontal_channels(s) != 4) return interleave(s.i1e, s.i1n);
  const bool lateral = s.i1e.size() == s.i0.size() && s.i1n.size() == s.i0.size();
  std::vector<float> out(4 * s.i0.size());
  parallel_ranges(s.i0.size(), 65536, [&](std::size_t lo, std::size_t hi, unsigned) {
    for (std::size_t i = lo; i < hi; ++i) {
      out[4 * i] = lateral ? s.i1e[i] : 0.0f, out[4 * i + 1] = lateral ? s.i1n[i] : 0.0f;
      out[4 * i + 2] = s.tau_below[i], out[4 * i + 3] = s.slab_excess[i];
    }
  });
  return out;
}

std::shared_ptr<const MsSource> ms_source_for(const PreparedVolume& v, const MsSourceKey& key, bool* built) {
  const bool ahead = v.ms_prebuilt && v.ms_prebuilt->key == key;
  if (built) *built = !ahead;
  if (ahead) return std::shared_ptr<const MsSource>(v.ms_prebuilt, &v.ms_prebuilt->source);
  return std::make_shared<const MsSource>(build_ms_source(v, key));
}

MsPeak ms_peak(const std::function<double(double)>& phase, double f) {
  // The phase on cosines packed geometrically toward the forward direction (a droplet's peak is
  // narrower than a degree: 1 - mu down to 1e-10), integrated by the trapezoid in mu.
  constexpr int kNodes = 4001;
  std::vector<double> mu(kNodes), p(kNodes);
  for (int i = 0; i < kNodes; ++i) {
    const double s = i == 0 ? 0.0 : 1e-10 * std::pow(2.0e10, static_cast<double>(i - 1) / (kNodes - 2));
    mu[static_cast<std::size_t>(i)] = 1.0 - s;
    const double v = phase(1.0 - s);
    p[static_cast<std::size_t>(i)] = std::isfinite(v) ? std::max(v, 0.0) : 0.0;
  }
  // The integrals of max(p - c, 0) and of max(p - c, 0) mu over the sphere.
  auto above = [&](double c, double* first_moment) {
    double sum = 0.0, moment = 0.0;
    for (std::size_t i = 0; i + 1 < mu.size(); ++i) {
      const double a = std::max(p[i] - c, 0.0), b = std::max(p[i + 1] - c, 0.0), w = 0.5 * (mu[i] - mu[i + 1]);
      sum += (a + b) * w;
      moment += (a * mu[i] + b * mu[i + 1]) * w;
    }
    if (first_moment) *first_moment = 2.0 * kPi * moment;
    return 2.0 * kPi * sum;
  };
  MsPeak out;
  const double peak = *std::max_element(p.begin(), p.end());
  if (!(f > 0.0) || !(peak > 0.0)) {
    out.cut = peak;
    return out;
  }
  double c = 0.0;
  if (f < 1.0) {
    const double target = f * above(0.0, nullptr);
    // above(c) falls from the whole integral at c = 0 to 0 at the peak's value: bisection.
    double lo = 0.0, hi = peak;
    for (int it = 0; it < 200 && hi - lo > 1e-12 * hi; ++it) {
      const double m = 0.5 * (lo + hi);
      (above(m, nullptr) > target ? lo : hi) = m;
    }
    c = 0.5 * (lo + hi);
  }
  double moment = 0.0;
  const double share = above(c, &moment);
  out.cut = c;
  out.g = share > 0.0 ? std::clamp(moment / share, -1.0, 1.0) : 1.0;
  return out;
}

namespace {
// The droplets' beam table (ms_beam_table) for the Mie fit at droplet diameter d_um, remembered for
// the last diameter asked (the ice's settings do not change it). The fit's HG lobe is kept apart (its
// spike, narrower than a degree for large droplets) where it lies within the peak,
// a = (1 - w_d) / f < 1: droplets above about 2 um. Below that the lobe is broad (g_hg < 0.92, wider
// than 4 degrees), a > 1 would make its chain grow as e^(lambda (a - 1)), and the whole phase is
// tabulated.
std::shared_ptr<const MsBeamTable> droplet_beam_table(double d_um, double cut, double f) {
  thread_local double memo_d = -1.0, memo_cut = -1.0;
  thread_local std::shared_ptr<const MsBeamTable> memo;
  if (memo && memo_d == d_um && memo_cut == cut) return memo;
  const physics::f64::MieParams mie = physics::f64::mie_params(d_um);
  const double wd = mie.w_d, gd = mie.g_d, al = mie.alpha;
  if (1.0 - wd < f) {
    memo = std::make_shared<const MsBeamTable>(ms_beam_table(
        [wd, gd, al](double m) { return wd * physics::f64::phase_draine(m, gd, al); }, 1.0 - wd, mie.g_hg, mie.c_hg, cut, f));
  } else {
    memo = std::make_shared<const MsBeamTable>(
        ms_beam_table([mie](double m) { return physics::f64::phase_mie(m, mie); }, 0.0, 0.0, 1.0, cut, f));
  }
  memo_d = d_um, memo_cut = cut;
  return memo;
}
}  // namespace

bool ms_slab_on(const MarchSettings& s) { return s.medium.ms_two_stream && s.medium.ms_slab; }

MsPeaks ms_peaks(const MarchSettings& s) {
  struct Memo {
    double droplet_um = -1.0, ice_g = -2.0;
    bool liquid_hg = false, slab = false;
    MsPeaks peaks;
  };
  thread_local Memo memo;
  const double d = s.medium.droplet_diameter_um, ice_g = s.medium.ice_g;
  const bool hg = s.medium.liquid_phase_hg, slab = ms_slab_on(s);
  if (memo.droplet_um == d && memo.ice_g == ice_g && memo.liquid_hg == hg && memo.slab == slab) return memo.peaks;
  const physics::f64::MieParams mie = physics::f64::mie_params(d);
  const double gl = physics::f64::mie_mean_cosine(mie);
  // The share truncated: g^2, or the higher-order source's (chi_8; for droplets at least their
  // fit's narrow lobe, which the beam's table keeps apart).
  const bool lobe_apart = !hg && 1.0 - mie.w_d < gl * gl;  // as droplet_beam_table decides at g^2
  const double fl = slab ? ms_slab_share(hg ? std::function<double(double)>([gl](double m) { return physics::f64::phase_hg(m, gl); })
                                            : std::function<double(double)>([&mie](double m) { return physics::f64::phase_mie(m, mie); }),
                                         lobe_apart ? 1.0 - mie.w_d : 0.0)
                         : gl * gl;
  const double fi = slab ? std::pow(ice_g, 8) : ice_g * ice_g;
  MsPeaks out;
  out.f_liquid = fl;
  out.f_ice = fi;
  out.liquid = hg ? ms_peak([gl](double m) { return physics::f64::phase_hg(m, gl); }, fl)
                  : ms_peak([&mie](double m) { return physics::f64::phase_mie(m, mie); }, fl);
  out.ice = ms_peak([ice_g](double m) { return physics::f64::phase_hg(m, ice_g); }, fi);
  out.beam = hg ? nullptr : droplet_beam_table(d, out.liquid.cut, fl);
  memo = Memo{d, ice_g, hg, slab, out};
  return out;
}

std::shared_ptr<const std::vector<float>> ms_slab_tables(const MarchSettings& s) {
  struct Memo {
    double droplet_um = -1.0, ice_g = -2.0;
    bool liquid_hg = false;
    std::shared_ptr<const std::vector<float>> tables;
  };
  thread_local Memo memo;
  const double d = s.medium.droplet_diameter_um, ice_g = s.medium.ice_g;
  const bool hg = s.medium.liquid_phase_hg;
  if (memo.tables && memo.droplet_um == d && memo.ice_g == ice_g && memo.liquid_hg == hg) return memo.tables;
  const physics::f64::MieParams mie = physics::f64::mie_params(d);
  const double gl = physics::f64::mie_mean_cosine(mie);
  MarchSettings slab_settings = s;  // the shares the tables are made for, whatever s's shape
  slab_settings.medium.ms_two_stream = slab_settings.medium.ms_slab = true;
  const MsPeaks peaks = ms_peaks(slab_settings);
  const MsSlabTable liquid = hg ? ms_slab_table([gl](double m) { return physics::f64::phase_hg(m, gl); }, peaks.f_liquid, gl)
                                : ms_slab_table([&mie](double m) { return physics::f64::phase_mie(m, mie); }, peaks.f_liquid, gl);
  const MsSlabTable ice = ms_slab_table([ice_g](double m) { return physics::f64::phase_hg(m, ice_g); }, peaks.f_ice, ice_g);
  auto both = std::make_shared<std::vector<float>>(liquid.values);  // the layout of CV_MS_SLAB_TOTAL
  both->insert(both->end(), ice.values.begin(), ice.values.end());
  both->insert(both->end(), liquid.below.begin(), liquid.below.end());
  both->insert(both->end(), ice.below.begin(), ice.below.end());
  memo = Memo{d, ice_g, hg, both};
  return memo.tables;
}

namespace {
// Gauss-Legendre nodes and weights of n points on [-1, 1] (Newton on the Legendre recurrence).
void gauss_legendre_unit(int n, std::vector<double>& x, std::vector<double>& w) {
  x.assign(static_cast<std::size_t>(n), 0.0);
  w.assign(static_cast<std::size_t>(n), 0.0);
  for (int i = 0; i < (n + 1) / 2; ++i) {
    double z = std::cos(kPi * (i + 0.75) / (n + 0.5)), dp = 1.0;
    for (int it = 0; it < 100; ++it) {
      double p0 = 1.0, p1 = z;
      for (int l = 1; l < n; ++l) {
        const double p2 = ((2.0 * l + 1.0) * z * p1 - l * p0) / (l + 1.0);
        p0 = p1;
        p1 = p2;
      }
      dp = n * (z * p1 - p0) / (z * z - 1.0);
      const double dz = p1 / dp;
      z -= dz;
      if (std::abs(dz) < 1e-15) break;
    }
    x[static_cast<std::size_t>(i)] = z;
    x[static_cast<std::size_t>(n - 1 - i)] = -z;
    w[static_cast<std::size_t>(i)] = w[static_cast<std::size_t>(n - 1 - i)] = 2.0 / ((1.0 - z * z) * dp * dp);
  }
}

// The same mapped onto [a, b]; the unit rule is made once.
void gauss_legendre(double a, double b, std::vector<double>& x, std::vector<double>& w) {
  constexpr int kNodes = 1700;
  static const std::pair<std::vector<double>, std::vector<double>> unit = [] {
    std::pair<std::vector<double>, std::vector<double>> r;
    gauss_legendre_unit(kNodes, r.first, r.second);
    return r;
  }();
  const double h = 0.5 * (b - a), m = 0.5 * (b + a);
  x.resize(unit.first.size());
  w.resize(unit.second.size());
  for (std::size_t i = 0; i < x.size(); ++i) {
    x[i] = m + h * unit.first[i];
    w[i] = h * unit.second[i];
  }
}

// out[l] += 2 pi sum_i w_i f(x_i) P_l(x_i), l = 0..L (degree by degree over all nodes: the
// recurrence runs across the nodes, which vectorises).
template <class F>
void legendre_moments(const std::vector<double>& x, const std::vector<double>& w, F f, std::vector<double>& out) {
  const int L = static_cast<int>(out.size()) - 1;
  const std::size_t n = x.size();
  std::vector<double> fx(n), prev(n, 1.0), cur(x);
  for (std::size_t i = 0; i < n; ++i) fx[i] = 2.0 * kPi * w[i] * f(x[i]);
  double s0 = 0.0, s1 = 0.0;
  for (std::size_t i = 0; i < n; ++i) s0 += fx[i], s1 += fx[i] * x[i];
  out[0] += s0;
  if (L >= 1) out[1] += s1;
  for (int l = 1; l < L; ++l) {
    const double a = (2.0 * l + 1.0) / (l + 1.0), b = static_cast<double>(l) / (l + 1.0);
    double sum = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      const double next = a * x[i] * cur[i] - b * prev[i];
      prev[i] = cur[i];
      cur[i] = next;
      sum += fx[i] * next;
    }
    out[static_cast<std::size_t>(l + 1)] += sum;
  }
}
}  // namespace

MsBeamTable ms_beam_table(const std::function<double(double)>& smooth, double spike_weight, double spike_g, double spike_c,
                          double cut, double f) {
  const double w = 1.0 - spike_weight, c = cut;  // w: the smooth part's share
  MsBeamTable out;
  out.values.assign(static_cast<std::size_t>(CV_MS_BEAM_ROWS) * CV_MS_BEAM_ANGLES, static_cast<float>(1.0 / (4.0 * kPi)));
  if (!(f > 0.0) || !(f < 1.0) || !(c > 0.0)) return out;  // no peak: the table is not read (lambda = 0)
  const double a = spike_weight / f;
  out.spike_share = a;
  auto hg = [&](double m) { return spike_weight > 0.0 ? physics::f64::phase_hg_c(m, spike_g, spike_c) : 0.0; };
  auto p0 = [&](double m) { return smooth(m) + spike_weight * hg(m); };
  // The cone mu >= mu_c where p exceeds the cut (p falls from the forward direction until it meets c).
  double th = 0.0;
  const double dth = 0.05 * kPi / 180.0;
  while (th < kPi && p0(std::cos(th)) > c) th += dth;
  double lo = std::max(th - dth, 0.0), hi = std::min(th, kPi);
  for (int it = 0; it < 100; ++it) {
    const double m = 0.5 * (lo + hi);
    (p0(std::cos(m)) > c ? lo : hi) = m;
  }
  const double mu_c = std::cos(0.5 * (lo + hi));
  // Legendre coefficients chi_l = 2 pi int f P_l dmu of p, and of K_r = K - a HG: (smooth - c) / f
  // on the cone, (max(p - c, 0) - spike_weight HG) / f off it (the HG lobe's spike, narrower than a
  // degree for large droplets, is never integrated: its coefficients are g^l).
  // Degrees up to 3000 (the HG lobe's g^l, g = 0.998 for 50 um droplets, is below 0.003 there).
  // gauss_legendre's 1700 nodes integrate P_l f exactly for f a polynomial of degree below 400 on
  // each side of the cone's edge, where the integrands are smooth: 3200 nodes gave the same table
  // to 6e-8.
  constexpr int kL = 3000;
  std::vector<double> chi_p(kL + 1, 0.0), chi_kr(kL + 1, 0.0), x, wt;
  gauss_legendre(-1.0, 1.0, x, wt);
  legendre_moments(x, wt, smooth, chi_p);
  gauss_legendre(mu_c, 1.0, x, wt);
  legendre_moments(x, wt, [&](double m) { return (smooth(m) - c) / f; }, chi_kr);
  gauss_legendre(-1.0, mu_c, x, wt);
  legendre_moments(x, wt, [&](double m) { return (std::max(p0(m) - c, 0.0) - (1.0 - w) * hg(m)) / f; }, chi_kr);
  const double log_g = spike_weight > 0.0 ? std::log1p(-spike_c) : 0.0;
  std::vector<double> gl(kL + 1), chi_k(kL + 1);
  for (int l = 0; l <= kL; ++l) {
    const auto i = static_cast<std::size_t>(l);
    gl[i] = spike_weight > 0.0 ? std::exp(l * log_g) : 0.0;
    chi_p[i] = (1.0 - w) * gl[i] + chi_p[i];
    chi_k[i] = a * gl[i] + chi_kr[i];
  }
  out.norm_error = std::abs(chi_k[0] - 1.0);
  // The rows' coefficients r_l(lambda): chi_l(p) exp(-lambda (1 - chi_l(K))) less the HG lobe's own chain.
  constexpr int kRows = CV_MS_BEAM_ROWS, kAngles = CV_MS_BEAM_ANGLES;
  std::vector<double> r(static_cast<std::size_t>(kL + 1) * kRows);  // degree-major
  for (int i = 0; i < kRows; ++i) {
    const double s = static_cast<double>(i) / (kRows - 1);
    const bool infinite = i == kRows - 1;  // lambda infinite: isotropic
    const double lambda = infinite ? 0.0 : CV_MS_BEAM_LAMBDA0 * s / (1.0 - s);
    for (int l = 0; l <= kL; ++l) {
      const auto k = static_cast<std::size_t>(l);
      r[k * kRows + static_cast<std::size_t>(i)] =
          infinite ? (l == 0 ? 1.0 : 0.0)
                   : chi_p[k] * std::exp(-lambda * (1.0 - chi_k[k])) - (1.0 - w) * gl[k] * std::exp(-lambda * (1.0 - a * gl[k]));
    }
  }
  // The sums over l of (2l + 1) / 4 pi r_l P_l(cos theta_j), degree by degree (P_l's recurrence
  // across the angles), into an angle-major table.
  std::vector<double> table(static_cast<std::size_t>(kAngles) * kRows, 0.0), mu(kAngles), prev(kAngles, 0.0), cur(kAngles, 1.0);
  for (int j = 0; j < kAngles; ++j) mu[static_cast<std::size_t>(j)] = std::cos(kPi * j / (kAngles - 1));
  for (int l = 0; l <= kL; ++l) {
    const double* rl = &r[static_cast<std::size_t>(l) * kRows];
    const double scale = (2.0 * l + 1.0) / (4.0 * kPi);
    for (int j = 0; j < kAngles; ++j) {
      const double pj = scale * cur[static_cast<std::size_t>(j)];
      double* tj = &table[static_cast<std::size_t>(j) * kRows];
      for (int i = 0; i < kRows; ++i) tj[i] += rl[i] * pj;
    }
    const double a1 = (2.0 * l + 1.0) / (l + 1.0), b1 = static_cast<double>(l) / (l + 1.0);
    for (int j = 0; j < kAngles; ++j) {
      const auto jj = static_cast<std::size_t>(j);
      const double next = a1 * mu[jj] * cur[jj] - b1 * prev[jj];
      prev[jj] = cur[jj];
      cur[jj] = next;
    }
  }
  for (int i = 0; i < kRows; ++i) {
    for (int j = 0; j < kAngles; ++j) {
      out.values[static_cast<std::size_t>(i) * kAngles + static_cast<std::size_t>(j)] =
          static_cast<float>(table[static_cast<std::size_t>(j) * kRows + static_cast<std::size_t>(i)]);
    }
  }
  return out;
}

}  // namespace cv::core
