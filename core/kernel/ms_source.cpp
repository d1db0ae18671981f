// The two-stream source: a closed-form delta-scaled two-stream column per grid column.
#include "kernel/ms_source.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "geo/geodesy.hpp"
#include "physics/physics.hpp"

namespace cv::core {
namespace {
constexpr double kPi = 3.14159265358979323846;
}

// The two-stream fluxes up and down, F+ and F-, of a conservative column (omega = 1), delta-scaled:
// f = g^2, dtau' = (1 - f) dtau, g' = g / (1 + g), the direct beam exp(-tau'/mu0) per unit
// irradiance (it keeps the light the forward peak scatters), tau' downward from the top:
//   dF+/dtau' = gamma1 (F+ - F-) - gamma3 e,   dF-/dtau' = gamma1 (F+ - F-) + gamma4 e,
// e = exp(-tau'/mu0), gamma4 = 1 - gamma3, gamma1 = c (1 - g') (gamma2 = gamma1 with no absorption).
// The net flux N = F+ - F- and the sum S = F+ + F- then integrate in closed form, for any g' per
// layer: dN/dtau' = -e gives N = N0 + mu0 (e - 1); dS/dtau' = 2 gamma1 N + (gamma4 - gamma3) e gives
//   S = N0 + 2 c (N0 - mu0) G + B,  G = int (1 - g') dtau' = int (1 - g) dtau,
//   B = int (2 c mu0 (1 - g') + 1 - 2 gamma3) e dtau',
// with no diffuse light down at the top (S0 = N0). At the bottom the upward diffuse flux is the
// ground's albedo A times what reaches it: (1 - A) S + (1 + A) N = 2 A mu0 e, linear in N0, whose
// coefficient (1 - A)(1 + 2 c G) + 1 + A is never small: no optical depth overflows or cancels.
// The radiance I0 + I1 mu with these hemispheric fluxes (F+- = pi (I0 +- 2/3 I1)) has
// I0 = S / 2 pi and I1 = 3 N / 4 pi. With Eddington's gamma1 and gamma3 this is the delta-Eddington
// solution (its moment equations dI1/dtau' = -(3/4 pi) e, dI0/dtau' = (1 - g') I1 + (3 g' mu0/4 pi) e).
TwoStreamColumn two_stream_column(const double* sigma, const double* g, int n, double dz, double mu0, double a,
                                  TwoStreamClosure closure) {
  TwoStreamColumn c;
  c.i0.assign(static_cast<std::size_t>(std::max(n, 0)), 0.0);
  c.i1.assign(c.i0.size(), 0.0);
  if (n < 1 || !(mu0 > 0.0)) return c;
  a = std::clamp(std::isfinite(a) ? a : 0.0, 0.0, 1.0);
  dz = std::abs(dz);
  const bool eddington = closure == TwoStreamClosure::Eddington;
  const double s3 = std::sqrt(3.0);
  const double cc = eddington ? 0.75 : 0.5 * s3;  // gamma1 / (1 - g')
  // What the beam's scattering adds to dS/dtau' per unit e: 2 gamma1 mu0 + gamma4 - gamma3.
  auto beam_weight = [&](double gp) {
    const double gamma3 = eddington ? (2.0 - 3.0 * gp * mu0) / 4.0 : 0.5 * (1.0 - s3 * gp * mu0);
    return 2.0 * cc * mu0 * (1.0 - gp) + 1.0 - 2.0 * gamma3;
  };
  // Scaled optical depth, G and B at each node, from the top (node n - 1) down; layers by the
  // trapezoid for the optical depth, with the layer's g' for G and B (exact for e within a layer).
  std::vector<double> tau(c.i0.size(), 0.0), big_g(c.i0.size(), 0.0), big_b(c.i0.size(), 0.0);
  double e_above = 1.0;
  for (int k = n - 2; k >= 0; --k) {
    const std::size_t K = static_cast<std::size_t>(k);
    const double s0 = std::max(sigma[k + 1], 0.0), s1 = std::max(sigma[k], 0.0);
    const double st = s0 + s1;
    const double dtau = std::isfinite(st) ? 0.5 * st * dz : 0.0;
    const double gl = st > 0.0 ? std::clamp((s0 * g[k + 1] + s1 * g[k]) / st, -0.999, 0.999) : 0.0;
    tau[K] = tau[K + 1] + (1.0 - gl * gl) * dtau;
    big_g[K] = big_g[K + 1] + (1.0 - gl) * dtau;
    const double e_below = std::exp(-tau[K] / mu0);
    big_b[K] = big_b[K + 1] + beam_weight(gl / (1.0 + gl)) * mu0 * (e_above - e_below);
    e_above = e_below;
  }
  const double e_b = std::exp(-tau[0] / mu0), g_b = big_g[0], b_b = big_b[0];
  const double n0 = (2.0 * a * mu0 * e_b - (1.0 - a) * (b_b - 2.0 * cc * mu0 * g_b) - (1.0 + a) * mu0 * (e_b - 1.0)) /
                    ((1.0 - a) * (1.0 + 2.0 * cc * g_b) + 1.0 + a);
  for (std::size_t k = 0; k < c.i0.size(); ++k) {
    const double e = std::exp(-tau[k] / mu0);
    const double net = n0 + mu0 * (e - 1.0);
    const double sum = n0 + 2.0 * cc * (n0 - mu0) * big_g[k] + big_b[k];
    c.i0[k] = sum / (2.0 * kPi);
    c.i1[k] = 3.0 * net / (4.0 * kPi);
  }
  const std::size_t top = c.i0.size() - 1;
  c.reflected = kPi * (c.i0[top] + (2.0 / 3.0) * c.i1[top]) / mu0;
  const double down = kPi * (c.i0[0] - (2.0 / 3.0) * c.i1[0]) + mu0 * e_b;
  c.transmitted = down / mu0;
  c.absorbed_ground = (1.0 - a) * down / mu0;
  return c;
}

MsSourceKey ms_source_key(const MarchSettings& s, const glm::dvec3& to_sun) {
  MsSourceKey k;
  k.to_sun = to_sun;
  const physics::f64::MieParams mie = physics::f64::mie_params(s.medium.droplet_diameter_um);
  k.liquid_g = physics::f64::mie_mean_cosine(mie);  // HG for liquid has the same mean cosine
  k.ice_g = s.medium.ice_g;
  k.ground_albedo = s.features.globe ? (s.medium.ground_albedo.x + s.medium.ground_albedo.y + s.medium.ground_albedo.z) / 3.0 : 0.0;
  k.mask = medium_mask(s);
  return k;
}

MsSource build_ms_source(const PreparedVolume& v, const MsSourceKey& key) {
  const auto t0 = std::chrono::steady_clock::now();
  const VolumeGrid& grid = v.grid;
  const int nx = grid.lon_deg.count, ny = grid.lat_deg.count, nz = grid.alt_m.count;
  MsSource out;
  out.i0.assign(grid.points(), 0.0f);
  out.i1.assign(grid.points(), 0.0f);
  std::vector<double> sigma(static_cast<std::size_t>(nz)), g(static_cast<std::size_t>(nz));
  const glm::dvec3 to_sun = glm::length(key.to_sun) > 0.0 ? glm::normalize(key.to_sun) : glm::dvec3(0.0);
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const double lat = grid.lat_deg.at(j), lon = grid.lon_deg.at(i);
      const double mu0 = glm::dot(geo::sphere_enu(lat, lon).up, to_sun);
      if (!(mu0 > 0.0)) continue;  // night: no source
      bool any = false;
      // The column's ground, as the march's band test reads it at a node (the column map's second channel).
      const std::size_t col = grid.column(i, j);
      const double ground = kColumnMapChannels * col + 1 < v.column_maps.size() ? double(v.column_maps[kColumnMapChannels * col + 1]) : 0.0;
      for (int k = 0; k < nz; ++k) {
        const std::size_t idx = grid.index(i, j, k);
        const bool shown = key.mask.shown(grid.alt_m.at(k), ground);
        const double sl = shown && !key.mask.hide_liquid ? std::max(0.0, double(v.extinction.liquid_per_m[idx])) : 0.0;
        const double si = shown && !key.mask.hide_ice ? std::max(0.0, double(v.extinction.ice_per_m[idx])) : 0.0;
        sigma[static_cast<std::size_t>(k)] = sl + si;
        g[static_cast<std::size_t>(k)] = sl + si > 0.0 ? (sl * key.liquid_g + si * key.ice_g) / (sl + si) : 0.0;
        any = any || sl + si > 0.0;
      }
      if (!any) continue;  // a clear column holds no diffuse light from cloud (the sky is the air's)
      const TwoStreamColumn c = two_stream_column(sigma.data(), g.data(), nz, grid.alt_m.step, mu0, key.ground_albedo);
      for (int k = 0; k < nz; ++k) {
        out.i0[grid.index(i, j, k)] = static_cast<float>(c.i0[static_cast<std::size_t>(k)]);
        out.i1[grid.index(i, j, k)] = static_cast<float>(c.i1[static_cast<std::size_t>(k)]);
      }
    }
  }
  out.build_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return out;
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

MsPeaks ms_peaks(const MarchSettings& s) {
  struct Memo {
    double droplet_um = -1.0, ice_g = -2.0;
    bool liquid_hg = false;
    MsPeaks peaks;
  };
  thread_local Memo memo;
  const double d = s.medium.droplet_diameter_um, ice_g = s.medium.ice_g;
  const bool hg = s.medium.liquid_phase_hg;
  if (memo.droplet_um == d && memo.ice_g == ice_g && memo.liquid_hg == hg) return memo.peaks;
  const physics::f64::MieParams mie = physics::f64::mie_params(d);
  const double gl = physics::f64::mie_mean_cosine(mie);
  MsPeaks out;
  out.liquid = hg ? ms_peak([gl](double m) { return physics::f64::phase_hg(m, gl); }, gl * gl)
                  : ms_peak([&mie](double m) { return physics::f64::phase_mie(m, mie); }, gl * gl);
  out.ice = ms_peak([ice_g](double m) { return physics::f64::phase_hg(m, ice_g); }, ice_g * ice_g);
  memo = Memo{d, ice_g, hg, out};
  return out;
}

}  // namespace cv::core
