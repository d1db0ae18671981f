// Benchmark (not a test): how many angular moments a multiple-scattering source needs once the
// view path truncates less of the forward peak. Issue 11's oblique views are held back by the
// delta-Eddington scaling of the march's diffuse path (BENCHMARKS, "What the delta-Eddington scaling
// costs by itself"): truncating less (a share f = g^(L+1) of the scattering, as delta-M does) leaves
// a phase whose radiance field needs moments up to L. This tool measures, on a conservative
// plane-parallel Henyey-Greenstein slab over a black ground, the reflected radiance of the model
//
//   I(view) = exact single scattering (the true phase and extinction, as the march's sun path)
//           + the scattering of the delta-M-scaled problem's diffuse radiance, kept to moments <= L,
//             integrated along the scaled view path,
//
// where the scaled problem's diffuse radiance is itself exact (a Monte Carlo of the scaled medium
// tallying its spherical-harmonic moments by track length, in layers of optical depth). So the
// figures are the floor of any source of order L with that truncation: the error of the scaling
// and of the truncated moments, not of a solver. "all" is the same model with every moment (the
// scaled problem's local estimate). The reference is a Monte Carlo of the true slab (local
// estimate, orders >= 2, plus the exact single scattering). Written for this question, sharing no
// code with the renderer's Monte Carlo.
//   bench_slab_moments [--tau 2,5,...] [--zenith SUN,...] [--view V,...] [--azimuth A,...]
//                      [--g G] [--photons N] [--seed S] [--rows]
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "bench/bench_args.hpp"
#include "kernel/ms_source.hpp"

namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr int kMaxL = 7;                                   // moments tallied: l = 0 .. kMaxL, m = 0 .. l (cos m phi)
constexpr int kMoments = (kMaxL + 1) * (kMaxL + 2) / 2;  // 36

struct Dir {
  double x, y, z;  // z up
};

double hg(double g, double mu) { return (1.0 - g * g) / (4.0 * kPi * std::pow(1.0 + g * g - 2.0 * g * mu, 1.5)); }

double hg_sample(double g, double xi) {
  if (std::abs(g) < 1e-6) return 2.0 * xi - 1.0;
  const double s = (1.0 - g * g) / (1.0 - g + 2.0 * g * xi);
  return std::clamp((1.0 + g * g - s * s) / (2.0 * g), -1.0, 1.0);
}

// The direction at angle acos(mu) from d, at azimuth phi about it.
Dir turn(const Dir& d, double mu, double phi) {
  const double s = std::sqrt(std::max(0.0, 1.0 - mu * mu)), c = std::cos(phi), sn = std::sin(phi);
  if (std::abs(d.z) > 0.99999) {
    const double sign = d.z > 0 ? 1.0 : -1.0;
    return {s * c, s * sn, sign * mu};
  }
  const double t = std::sqrt(1.0 - d.z * d.z);
  return {s * (d.x * d.z * c - d.y * sn) / t + d.x * mu, s * (d.y * d.z * c + d.x * sn) / t + d.y * mu, -s * c * t + d.z * mu};
}

// Real orthonormal spherical harmonics with cos(m phi), l <= kMaxL, m <= l, at (mu, phi):
// sqrt((2 - delta_m0) (2l + 1) / (4 pi) (l - m)! / (l + m)!) P_l^m(mu) cos(m phi). Index l (l + 1) / 2 + m.
void harmonics(double mu, double phi, std::array<double, kMoments>& y) {
  double p[kMaxL + 1][kMaxL + 1] = {};
  const double s = std::sqrt(std::max(0.0, 1.0 - mu * mu));
  p[0][0] = 1.0;
  for (int m = 1; m <= kMaxL; ++m) p[m][m] = -(2 * m - 1) * s * p[m - 1][m - 1];
  for (int m = 0; m < kMaxL; ++m) p[m + 1][m] = (2 * m + 1) * mu * p[m][m];
  for (int m = 0; m <= kMaxL; ++m) {
    for (int l = m + 2; l <= kMaxL; ++l) p[l][m] = ((2 * l - 1) * mu * p[l - 1][m] - (l + m - 1) * p[l - 2][m]) / (l - m);
  }
  // The normalisations, once (this runs for every flight of every photon).
  static const std::array<double, kMoments> norm = [] {
    std::array<double, kMoments> n{};
    for (int l = 0; l <= kMaxL; ++l) {
      for (int m = 0; m <= l; ++m) {
        double ratio = 1.0;  // (l - m)! / (l + m)!
        for (int k = l - m + 1; k <= l + m; ++k) ratio /= k;
        n[static_cast<std::size_t>(l * (l + 1) / 2 + m)] = std::sqrt((m ? 2.0 : 1.0) * (2 * l + 1) / (4.0 * kPi) * ratio);
      }
    }
    return n;
  }();
  for (int l = 0; l <= kMaxL; ++l) {
    for (int m = 0; m <= l; ++m) {
      const std::size_t i = static_cast<std::size_t>(l * (l + 1) / 2 + m);
      y[i] = norm[i] * p[l][m] * std::cos(m * phi);
    }
  }
}

// Legendre polynomial P_l(mu).
double legendre(int l, double mu) {
  double p0 = 1.0, p1 = mu;
  if (l == 0) return p0;
  for (int k = 2; k <= l; ++k) {
    const double p2 = ((2 * k - 1) * mu * p1 - (k - 1) * p0) / k;
    p0 = p1, p1 = p2;
  }
  return p1;
}

// The phase of a (scaled) medium: HG(g) itself, or what is left of it once a share f of its
// forward peak is truncated, in one of two ways:
//  - "hg": a Henyey-Greenstein of mean cosine (g - f) / (1 - f) (the delta-scaled HG the march's
//    diffuse path assumes with f = g^2);
//  - "clip": the peak cut flat at the level p_c that leaves the share f above it, min(p, p_c) /
//    (1 - f): the true phase's shape outside the cut cone (what delta-M's moments approximate).
struct Phase {
  double g = 0.0, f = 0.0, gs = 0.0, pc = 0.0;
  bool clip = false;
  std::array<double, kMaxL + 1> chi{};  // Legendre moments, chi_0 = 1
  double eval(double mu) const { return clip ? std::min(hg(g, mu), pc) / (1.0 - f) : hg(gs, mu); }
  template <class Rng>
  double sample(Rng& rng) const {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    if (!clip) return hg_sample(gs, u(rng));
    for (;;) {  // HG(g), kept with probability min(1, p_c / p): density min(p, p_c)
      const double mu = hg_sample(g, u(rng));
      const double p = hg(g, mu);
      if (p <= pc || u(rng) * p <= pc) return mu;
    }
  }
};

Phase make_phase(double g, double f, bool clip) {
  Phase ph;
  ph.g = g, ph.f = f, ph.clip = clip && f > 0.0;
  ph.gs = (g - f) / (1.0 - f);
  if (ph.clip) {
    // The cut level by bisection on the cone's cosine: the share above it is f.
    auto above = [&](double mu_c) {
      const double level = hg(g, mu_c);
      const int n = 4000;
      double sum = 0.0;
      for (int i = 0; i < n; ++i) {
        const double mu = mu_c + (1.0 - mu_c) * (i + 0.5) / n;
        sum += std::max(0.0, hg(g, mu) - level);
      }
      return 2.0 * kPi * sum * (1.0 - mu_c) / n;
    };
    double lo = -1.0, hi = 1.0;
    for (int it = 0; it < 100; ++it) {
      const double mid = 0.5 * (lo + hi);
      (above(mid) > f ? lo : hi) = mid;
    }
    ph.pc = hg(g, 0.5 * (lo + hi));
  }
  // Moments by quadrature (fine near the forward peak).
  const int n = 200000;
  for (int l = 0; l <= kMaxL; ++l) {
    double sum = 0.0;
    for (int i = 0; i < n; ++i) {
      const double x = (i + 0.5) / n;
      const double mu = 1.0 - 2.0 * x * x;  // denser toward mu = 1
      sum += ph.eval(mu) * legendre(l, mu) * 4.0 * x / n;
    }
    ph.chi[static_cast<std::size_t>(l)] = 2.0 * kPi * sum;
  }
  return ph;
}

struct View {
  double zenith_deg, azimuth_deg;
  Dir out;  // the radiance's direction, leaving the top
  double mu;
};

// Layers of optical depth for the moments: thin at the top, where oblique views see.
std::vector<double> layer_edges(double tau) {
  std::vector<double> e{0.0};
  while (e.back() < tau) e.push_back(std::min(tau, e.back() + std::min(1.0, 0.02 + 0.05 * e.back())));
  return e;
}

struct ScaledResult {
  std::vector<double> edges;
  std::vector<std::array<double, kMoments>> moments;  // per layer, of the diffuse radiance (per unit incident flux)
  std::vector<double> local;                          // per view: the scattering of the diffuse radiance, every moment
};

// One Monte Carlo of a conservative slab of optical depth tau, phase HG(g), lit by a unit flux
// (normal to the beam) from sun zenith mu0. Returns per view the radiance of orders >= 2 (local
// estimate) and, when tally_moments, the diffuse radiance's moments per layer (track length).
ScaledResult run_slab(double tau, const Phase& phase, double mu0, const std::vector<View>& views, long long photons,
                      std::uint64_t seed, bool tally_moments) {
  ScaledResult r;
  r.local.assign(views.size(), 0.0);
  if (tally_moments) {
    r.edges = layer_edges(tau);
    r.moments.assign(r.edges.size() - 1, {});
  }
  const std::size_t nl = r.edges.empty() ? 0 : r.edges.size() - 1;
  std::vector<std::array<double, kMoments>> full(nl + 1);  // difference array: layers crossed whole add y / |mu|
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const Dir beam{-std::sqrt(1.0 - mu0 * mu0), 0.0, -mu0};  // the sun at azimuth 0, the beam going down
  std::array<double, kMoments> y{};
  auto layer_of = [&](double t) {
    const auto it = std::upper_bound(r.edges.begin(), r.edges.end(), t);
    return static_cast<std::size_t>(std::clamp<std::ptrdiff_t>(it - r.edges.begin() - 1, 0, static_cast<std::ptrdiff_t>(nl) - 1));
  };
  // Track length of a diffuse segment from depth a along d for optical length s (depth grows down).
  auto tally = [&](double a, const Dir& d, double s) {
    const double b = std::clamp(a - d.z * s, 0.0, tau);
    const double lo = std::min(a, b), hi = std::max(a, b), amu = std::abs(d.z);
    if (amu > 0.0) s = std::min(s, (hi - lo) / amu);  // the length inside the slab
    harmonics(d.z, std::atan2(d.y, d.x), y);
    const std::size_t k0 = layer_of(lo), k1 = layer_of(hi);
    auto add_part = [&](std::size_t k) {
      const double overlap = std::min(hi, r.edges[k + 1]) - std::max(lo, r.edges[k]);
      const double len = amu > 0.0 ? std::min(s, overlap / amu) : s;
      const double w = len / (r.edges[k + 1] - r.edges[k]);
      for (int i = 0; i < kMoments; ++i) r.moments[k][static_cast<std::size_t>(i)] += w * y[static_cast<std::size_t>(i)];
    };
    add_part(k0);
    if (k1 != k0) {
      add_part(k1);
      if (k1 > k0 + 1) {  // the layers between are crossed whole: each gets y / |mu|
        for (int i = 0; i < kMoments; ++i) {
          full[k0 + 1][static_cast<std::size_t>(i)] += y[static_cast<std::size_t>(i)] / amu;
          full[k1][static_cast<std::size_t>(i)] -= y[static_cast<std::size_t>(i)] / amu;
        }
      }
    }
  };
  for (long long n = 0; n < photons; ++n) {
    Dir d = beam;
    double t = 0.0;  // depth in optical depth
    bool scattered = false;
    for (;;) {
      const double s = -std::log(1.0 - u(rng));
      const double next = t - d.z * s;
      if (scattered && tally_moments) tally(t, d, s);
      if (next < 0.0 || next > tau) break;  // leaves the slab (the ground is black)
      t = next;
      if (scattered) {
        // Local estimate toward each view: scattered here into it, then attenuated to the top.
        for (std::size_t v = 0; v < views.size(); ++v) {
          const View& w = views[v];
          const double c = d.x * w.out.x + d.y * w.out.y + d.z * w.out.z;
          r.local[v] += phase.eval(c) * std::exp(-t / w.mu) / w.mu;
        }
      }
      scattered = true;
      const double mu = phase.sample(rng);
      d = turn(d, mu, 2.0 * kPi * u(rng));
    }
  }
  // Per unit incident flux normal to the beam: each photon carries mu0 / N of it per unit area.
  const double k = mu0 / static_cast<double>(photons);
  for (double& v : r.local) v *= k;
  std::array<double, kMoments> run{};
  for (std::size_t l = 0; l < nl; ++l) {
    for (int i = 0; i < kMoments; ++i) {
      run[static_cast<std::size_t>(i)] += full[l][static_cast<std::size_t>(i)];
      r.moments[l][static_cast<std::size_t>(i)] = k * (r.moments[l][static_cast<std::size_t>(i)] + run[static_cast<std::size_t>(i)]);
    }
  }
  return r;
}

// The march's own two-stream column (core::two_stream_column, closed form) for the slab, on a fine
// grid of nodes: built once per slab, sun and closure, then scattered into each view.
constexpr int kColumnNodes = 4001;
cv::core::TwoStreamColumn slab_column(double tau, double g, double mu0, cv::core::TwoStreamClosure closure) {
  const double dz = 1.0;
  const std::vector<double> sigma(kColumnNodes, tau / ((kColumnNodes - 1) * dz)), gs(kColumnNodes, g);
  return cv::core::two_stream_column(sigma.data(), gs.data(), kColumnNodes, dz, mu0, 0.0, closure);
}

// The column's I0 + g' I1 mu (g' = g / (1 + g)) integrated along the scaled view path. With
// horizontal, the diffuse light's horizontal flux too, from the first-moment balance with P1's
// closure: F_h = g' / (1 - g') E_b Omega0_h (E_b the scaled beam), I1_h = 3 F_h / (4 pi).
double from_two_stream(const cv::core::TwoStreamColumn& c, double tau, double g, double mu0, const View& w, bool horizontal) {
  const double f = g * g, gp = g / (1.0 + g), dt = (1.0 - f) * tau / (kColumnNodes - 1);
  // The beam travels toward -x (the sun at azimuth 0): Omega0_h . out = -sin(theta0) out.x.
  const double h = horizontal ? 3.0 / (4.0 * kPi) * gp / (1.0 - gp) * -std::sqrt(1.0 - mu0 * mu0) * w.out.x : 0.0;
  const auto j = [&](int n) {
    const double eb = std::exp(-(kColumnNodes - 1 - n) * dt / mu0);
    return c.i0[static_cast<std::size_t>(n)] + gp * (c.i1[static_cast<std::size_t>(n)] * w.mu + h * eb);
  };
  double sum = 0.0;
  for (int k = kColumnNodes - 1; k > 0; --k) {  // from the top (node kColumnNodes - 1) down, layer by layer
    const double t0 = (kColumnNodes - 1 - k) * dt, t1 = t0 + dt;
    sum += 0.5 * (j(k) + j(k - 1)) * (std::exp(-t0 / w.mu) - std::exp(-t1 / w.mu));
  }
  return sum;
}

// The scaled problem's exact l = 1, m = 1 moment (the diffuse light's horizontal flux) scattered into
// the view, integrated along the scaled view path.
double from_horizontal_moment(const ScaledResult& r, const Phase& phase, const View& w) {
  std::array<double, kMoments> y{};
  harmonics(w.out.z, std::atan2(w.out.y, w.out.x), y);
  double sum = 0.0;
  for (std::size_t k = 0; k + 1 < r.edges.size(); ++k)
    sum += phase.chi[1] * r.moments[k][2] * y[2] * (std::exp(-r.edges[k] / w.mu) - std::exp(-r.edges[k + 1] / w.mu));
  return sum;
}

// Exact single scattering of the true slab into a view.
double single_scattering(double tau, double g, double mu0, const View& w) {
  const Dir beam{-std::sqrt(1.0 - mu0 * mu0), 0.0, -mu0};
  const double c = beam.x * w.out.x + beam.y * w.out.y + beam.z * w.out.z;
  return hg(g, c) * mu0 / (mu0 + w.mu) * (1.0 - std::exp(-tau * (1.0 / mu0 + 1.0 / w.mu)));
}

// The scaled problem's diffuse radiance, moments <= L, scattered with HG(gs) into the view and
// integrated along the scaled view path.
double from_moments(const ScaledResult& r, const Phase& phase, int L, const View& w) {
  std::array<double, kMoments> y{};
  harmonics(w.out.z, std::atan2(w.out.y, w.out.x), y);
  double sum = 0.0;
  for (std::size_t k = 0; k + 1 < r.edges.size(); ++k) {
    double j = 0.0;
    for (int l = 0; l <= L; ++l) {
      double lm = 0.0;
      for (int m = 0; m <= l; ++m) {
        const std::size_t i = static_cast<std::size_t>(l * (l + 1) / 2 + m);
        lm += r.moments[k][i] * y[i];
      }
      j += phase.chi[static_cast<std::size_t>(l)] * lm;
    }
    sum += j * (std::exp(-r.edges[k] / w.mu) - std::exp(-r.edges[k + 1] / w.mu));
  }
  return sum;
}
}  // namespace

int main(int argc, char** argv) {
  std::vector<double> taus{2, 5, 10, 20, 50}, zeniths{0, 30, 60}, view_zeniths{0, 45, 70, 85}, azimuths{0, 90, 180};
  std::vector<double> truncations{2, 4, 8};
  double g = 0.85;
  int photons = 100000;
  std::uint64_t seed = 11;
  bool rows = false;
  std::string scaled_phase = "hg", single = "exact";
  bool two_stream = false;
  namespace ba = cv::bench_args;
  const int code = ba::parse(
      "bench_slab_moments",
      "usage: bench_slab_moments [--tau 2,5,...] [--zenith SUN,...] [--view V,...] [--azimuth A,...]\n"
      "                          [--truncation N,...] [--scaled-phase hg|clip] [--single exact|tms]\n"
      "                          [--g G] [--photons N] [--seed S] [--two-stream] [--rows]\n"
      "  the reflected radiance of a conservative Henyey-Greenstein slab over a black ground, modelled as\n"
      "  exact single scattering plus the scattering of a delta-M-scaled problem's exact diffuse radiance\n"
      "  kept to moments <= L (L = 1, 3, 5, 7 and all), against a Monte Carlo of the true slab;\n"
      "  --truncation N: the scaled problem truncates the share g^N (extinction (1 - g^N) sigma, HG\n"
      "  (g - g^N) / (1 - g^N), or with --scaled-phase clip the true phase with its peak cut flat where the\n"
      "  share g^N lies above the cut); --single tms: the single scattering of Nakajima and Tanaka's TMS\n"
      "  correction (the true phase over 1 - f, along the scaled extinction) instead of the exact one; --view: view zenith angles (degrees); --azimuth: the camera's heading\n"
      "  from the sun's azimuth (0: looking toward the sun); --two-stream adds the march's own closed-form\n"
      "  two-stream columns (I0, I1 with Eddington's and the quadrature's closure) in place of the exact\n"
      "  L <= 1 moments (and, where --truncation has 2, the quadrature's with the g^2 problem's exact\n"
      "  l = 1, m = 1 moment);\n"
      "  --rows prints every case\n",
      argc, argv,
      {ba::numbers("--tau", taus), ba::numbers("--zenith", zeniths), ba::numbers("--view", view_zeniths),
       ba::numbers("--azimuth", azimuths), ba::numbers("--truncation", truncations),
       {"--g", "a number in 0..0.99", [&g](const std::string& v) {
          char* end = nullptr;
          const double x = std::strtod(v.c_str(), &end);
          if (v.empty() || *end || !(x >= 0.0 && x <= 0.99)) return false;
          g = x;
          return true;
        }},
       ba::one_of("--scaled-phase", scaled_phase, {"hg", "clip"}), ba::one_of("--single", single, {"exact", "tms"}), ba::integer("--photons", photons), ba::seed("--seed", seed),
       {"--two-stream", "", [&two_stream](const std::string&) {
          two_stream = true;
          return true;
        }},
       {"--rows", "", [&rows](const std::string&) {
                                                                         rows = true;
                                                                         return true;
                                                                       }}});
  if (code >= 0) return code;
  for (double t : taus) {
    if (!(t > 0.0 && t <= 200.0)) {
      std::fprintf(stderr, "bench_slab_moments: --tau: found %g, expected optical depths in (0, 200]\n", t);
      return 2;
    }
  }
  for (double z : zeniths) {
    if (!(z >= 0.0 && z < 89.0)) {
      std::fprintf(stderr, "bench_slab_moments: --zenith: found %g, expected sun zenith angles in 0..89 degrees\n", z);
      return 2;
    }
  }
  for (double z : view_zeniths) {
    if (!(z >= 0.0 && z < 89.5)) {
      std::fprintf(stderr, "bench_slab_moments: --view: found %g, expected view zenith angles in 0..89.5 degrees\n", z);
      return 2;
    }
  }
  for (double n : truncations) {
    if (!(n >= 1.0 && n <= 64.0)) {
      std::fprintf(stderr, "bench_slab_moments: --truncation: found %g, expected exponents in 1..64\n", n);
      return 2;
    }
  }
  std::vector<View> views;
  for (double vz : view_zeniths) {
    for (double az : azimuths) {
      if (vz == 0.0 && az != azimuths.front()) continue;  // nadir has no azimuth
      const double th = vz * kPi / 180.0, ph = az * kPi / 180.0;
      // Looking toward the sun (heading 0): the radiance travels away from it, toward -x.
      views.push_back({vz, az, {-std::sin(th) * std::cos(ph), -std::sin(th) * std::sin(ph), std::cos(th)}, std::cos(th)});
    }
  }
  const int orders[] = {1, 3, 5, 7};
  constexpr int kOrders = 4;
  // Sums of |error| per truncation, per order (and "all"), per view zenith.
  const std::size_t nz = view_zeniths.size(), nt = truncations.size();
  // [thin or thick][truncation][order][view zenith]: sums of |error|; and the largest |error|.
  std::vector<double> abs_err(2 * nt * (kOrders + 1) * nz, 0.0), worst(2 * nt * (kOrders + 1), 0.0);
  std::vector<int> cases(2 * nz, 0);
  // [closure][thin or thick][view zenith] and [closure][thin or thick]
  const cv::core::TwoStreamClosure closures[3] = {cv::core::TwoStreamClosure::Eddington, cv::core::TwoStreamClosure::Quadrature,
                                                  cv::core::TwoStreamClosure::Quadrature};
  const char* closure_names[4] = {"Eddington", "quadrature", "quadrature, horizontal flux", "quadrature, exact l=1 m=1"};
  constexpr int kClosures = 4;
  // The exact l = 1, m = 1 moment is the g^2 problem's: its row only where --truncation has 2.
  const std::size_t g2 = static_cast<std::size_t>(std::find(truncations.begin(), truncations.end(), 2.0) - truncations.begin());
  const int closures_shown = g2 < truncations.size() ? kClosures : kClosures - 1;
  std::vector<double> ts_err(2 * kClosures * nz, 0.0), ts_worst(2 * kClosures, 0.0);
  auto cell = [&](int thick, std::size_t ti, int o) { return (static_cast<std::size_t>(thick) * nt + ti) * (kOrders + 1) + static_cast<std::size_t>(o); };
  std::printf("conservative HG %.2f slab over a black ground, %d photons per run, scaled phase %s, single scattering %s\n", g,
              photons, scaled_phase.c_str(), single.c_str());
  std::vector<Phase> phases;
  for (double n : truncations) {
    phases.push_back(make_phase(g, std::pow(g, n), scaled_phase == "clip"));
    const Phase& ph = phases.back();
    std::printf("truncation g^%g = %.4f: scaled moments", n, ph.f);
    for (double c : ph.chi) std::printf(" %.4f", c);
    std::printf(" (delta-M: ");
    for (int l = 0; l <= kMaxL; ++l) std::printf(" %.4f", (std::pow(g, l) - ph.f) / (1.0 - ph.f));
    std::printf(")\n");
  }
  if (rows) std::printf("| tau | sun | view | azimuth | reference I/E | truncation | L=1 | L=3 | L=5 | L=7 | all |\n");
  std::uint64_t run_seed = seed;
  for (double tau : taus) {
    for (double sz : zeniths) {
      const double mu0 = std::cos(sz * kPi / 180.0);
      const ScaledResult ref = run_slab(tau, make_phase(g, 0.0, false), mu0, views, photons, run_seed++, false);
      std::vector<ScaledResult> scaled;
      for (std::size_t ti = 0; ti < truncations.size(); ++ti) {
        const double f = std::pow(g, truncations[ti]);
        scaled.push_back(run_slab((1.0 - f) * tau, phases[ti], mu0, views, photons, run_seed++, true));
      }
      std::vector<cv::core::TwoStreamColumn> columns;
      if (two_stream) {
        for (const auto closure : closures) columns.push_back(slab_column(tau, g, mu0, closure));
      }
      for (std::size_t v = 0; v < views.size(); ++v) {
        const View& w = views[v];
        const double exact_ss = single_scattering(tau, g, mu0, w);
        const double truth = exact_ss + ref.local[v];
        const std::size_t zi = static_cast<std::size_t>(std::find(view_zeniths.begin(), view_zeniths.end(), w.zenith_deg) - view_zeniths.begin());
        const int thick = tau >= 5.0 ? 1 : 0;
        ++cases[static_cast<std::size_t>(thick) * nz + zi];
        if (two_stream) {
          const double f = g * g;
          const double ss = single == "tms" ? single_scattering((1.0 - f) * tau, g, mu0, w) / (1.0 - f) : exact_ss;
          for (int cl = 0; cl < closures_shown; ++cl) {
            const double model = cl == 3 ? ss + from_two_stream(columns[1], tau, g, mu0, w, false) + from_horizontal_moment(scaled[g2], phases[g2], w)
                                         : ss + from_two_stream(columns[static_cast<std::size_t>(cl)], tau, g, mu0, w, cl == 2);
            const double e = model / truth - 1.0;
            const std::size_t at = static_cast<std::size_t>(2 * cl + thick);
            ts_err[at * nz + zi] += std::abs(e);
            ts_worst[at] = std::max(ts_worst[at], std::abs(e));
            if (rows) {
              std::printf("| %g | %g | %g | %g | %.5f | two-stream, %s | %+.1f %% |\n", tau, sz, w.zenith_deg, w.azimuth_deg, truth,
                          closure_names[cl], 100.0 * e);
            }
          }
        }
        for (std::size_t ti = 0; ti < nt; ++ti) {
          const double f = phases[ti].f;
          // TMS: light scattered into the truncated peak stays in the scaled beam, so the single
          // scattering goes along the scaled extinction with the phase over 1 - f.
          const double ss = single == "tms" ? single_scattering((1.0 - f) * tau, g, mu0, w) / (1.0 - f) : exact_ss;
          double err[kOrders + 1];
          for (int o = 0; o < kOrders; ++o) err[o] = (ss + from_moments(scaled[ti], phases[ti], orders[o], w)) / truth - 1.0;
          err[kOrders] = (ss + scaled[ti].local[v]) / truth - 1.0;
          for (int o = 0; o <= kOrders; ++o) {
            abs_err[cell(thick, ti, o) * nz + zi] += std::abs(err[o]);
            worst[cell(thick, ti, o)] = std::max(worst[cell(thick, ti, o)], std::abs(err[o]));
          }
          if (rows) {
            std::printf("| %g | %g | %g | %g | %.5f | g^%g |", tau, sz, w.zenith_deg, w.azimuth_deg, truth, truncations[ti]);
            for (int o = 0; o <= kOrders; ++o) std::printf(" %+.1f %% |", 100.0 * err[o]);
            std::printf("\n");
          }
        }
      }
      std::fprintf(stderr, "bench_slab_moments: tau %g, sun %g done\n", tau, sz);
    }
  }
  for (int thick : {1, 0}) {
    int n = 0;
    for (std::size_t zi = 0; zi < nz; ++zi) n += cases[static_cast<std::size_t>(thick) * nz + zi];
    if (!n) continue;
    std::printf("\nmean absolute error by view zenith angle, optical depths %s 5, and the largest\n| truncation | moments |",
                thick ? ">=" : "below");
    for (double vz : view_zeniths) std::printf(" %g deg |", vz);
    std::printf(" largest |\n");
    for (std::size_t ti = 0; ti < nt; ++ti) {
      for (int o = 0; o <= kOrders; ++o) {
        std::printf("| g^%g | %s |", truncations[ti], o < kOrders ? ("L <= " + std::to_string(orders[o])).c_str() : "all");
        for (std::size_t zi = 0; zi < nz; ++zi) {
          const int c = cases[static_cast<std::size_t>(thick) * nz + zi];
          std::printf(" %.1f %% |", 100.0 * abs_err[cell(thick, ti, o) * nz + zi] / std::max(1, c));
        }
        std::printf(" %.1f %% |\n", 100.0 * worst[cell(thick, ti, o)]);
      }
    }
    if (two_stream) {
      for (int cl = 0; cl < closures_shown; ++cl) {
        const std::size_t at = static_cast<std::size_t>(2 * cl + thick);
        std::printf("| g^2 | two-stream columns, %s |", closure_names[cl]);
        for (std::size_t zi = 0; zi < nz; ++zi) {
          const int c = cases[static_cast<std::size_t>(thick) * nz + zi];
          std::printf(" %.1f %% |", 100.0 * ts_err[at * nz + zi] / std::max(1, c));
        }
        std::printf(" %.1f %% |\n", 100.0 * ts_worst[at]);
      }
    }
  }
  return 0;
}
