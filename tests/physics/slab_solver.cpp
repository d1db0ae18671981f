// Adding-doubling for a homogeneous plane-parallel slab (see slab_solver.hpp). Written for the
// tests from the textbook equations (van de Hulst 1980, ch. 5; Hansen & Travis 1974, sec. 3.2), with
// nothing taken from the project's code.
#include "physics/slab_solver.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace slabcheck {
namespace {
constexpr double kPi = 3.14159265358979323846;

// 2 pi times the HG phase function, in the form (1 - g^2) / (1 + g^2 - 2 g mu)^1.5 / 2 with the
// denominator written as c^2 + 2 g (1 - mu), c = 1 - g, so that a forward peak near g = 1 keeps its
// digits (c is passed in, for g = exp(-x) formed without cancellation).
double hg_value(double mu, double g, double c) {
  const double den = c * c + 2.0 * g * (1.0 - mu);
  return c * (2.0 - c) / (4.0 * kPi * den * std::sqrt(den));
}

std::vector<double> hg_moments(double g, int l_max) {
  std::vector<double> m(static_cast<std::size_t>(l_max) + 1);
  double gl = 1.0;
  for (int l = 0; l <= l_max; ++l, gl *= g) m[static_cast<std::size_t>(l)] = gl;
  return m;
}

// Moments of HG(g) times mu^2, from mu P_l = ((l + 1) P_{l+1} + l P_{l-1}) / (2 l + 1) applied twice.
std::vector<double> hg_mu2_moments(double g, int l_max) {
  const std::vector<double> h = hg_moments(g, l_max + 2);
  std::vector<double> m(static_cast<std::size_t>(l_max) + 1);
  for (int l = 0; l <= l_max; ++l) {
    const double L = l;
    const double up = (L + 1.0) * (L + 2.0) / ((2.0 * L + 1.0) * (2.0 * L + 3.0));
    const double same = (L + 1.0) * (L + 1.0) / ((2.0 * L + 1.0) * (2.0 * L + 3.0)) +
                        (l > 0 ? L * L / ((2.0 * L + 1.0) * (2.0 * L - 1.0)) : 0.0);
    const double down = l > 1 ? L * (L - 1.0) / ((2.0 * L + 1.0) * (2.0 * L - 1.0)) : 0.0;
    m[static_cast<std::size_t>(l)] = up * h[static_cast<std::size_t>(l) + 2] + same * h[static_cast<std::size_t>(l)] +
                                     (l > 1 ? down * h[static_cast<std::size_t>(l) - 2] : 0.0);
  }
  return m;
}

// Legendre polynomials P_0..P_lmax at x.
void legendre(double x, int l_max, double* p) {
  p[0] = 1.0;
  if (l_max >= 1) p[1] = x;
  for (int l = 2; l <= l_max; ++l) p[l] = ((2.0 * l - 1.0) * x * p[l - 1] - (l - 1.0) * p[l - 2]) / l;
}

// The normalised associated Legendre functions Lambda_l^m(x) = sqrt((l - m)! / (l + m)!) P_l^m(x),
// without the Condon-Shortley sign, for l = m .. l_max (p[l]; p[l] = 0 for l < m): with them the
// addition theorem reads P_l(cos Theta) = sum_m (2 - delta_m0) Lambda_l^m(mu) Lambda_l^m(mu') cos(m dphi).
void legendre_m(double x, int m, int l_max, double* p) {
  for (int l = 0; l <= l_max && l < m; ++l) p[l] = 0.0;
  if (m > l_max) return;
  double mm = 1.0;
  const double s = std::sqrt(std::max(0.0, 1.0 - x * x));
  for (int k = 1; k <= m; ++k) mm *= std::sqrt((2.0 * k - 1.0) / (2.0 * k)) * s;
  p[m] = mm;
  if (m + 1 <= l_max) p[m + 1] = x * std::sqrt(2.0 * m + 1.0) * mm;
  for (int l = m + 2; l <= l_max; ++l) {
    p[l] = ((2.0 * l - 1.0) * x * p[l - 1] - std::sqrt((l - 1.0) * (l - 1.0) - double(m) * m) * p[l - 2]) /
           std::sqrt(double(l) * l - double(m) * m);
  }
}

// Dense n x n matrices, row-major.
using Mat = std::vector<double>;

Mat mul(const Mat& a, const Mat& b, int n) {
  Mat c(static_cast<std::size_t>(n) * n, 0.0);
  for (int i = 0; i < n; ++i) {
    double* ci = &c[static_cast<std::size_t>(i) * n];
    for (int k = 0; k < n; ++k) {
      const double aik = a[static_cast<std::size_t>(i) * n + k];
      if (aik == 0.0) continue;
      const double* bk = &b[static_cast<std::size_t>(k) * n];
      for (int j = 0; j < n; ++j) ci[j] += aik * bk[j];
    }
  }
  return c;
}

// a diag(d) and diag(d) a.
Mat scale_cols(Mat a, const std::vector<double>& d, int n) {
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) a[static_cast<std::size_t>(i) * n + j] *= d[static_cast<std::size_t>(j)];
  return a;
}
Mat scale_rows(Mat a, const std::vector<double>& d, int n) {
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) a[static_cast<std::size_t>(i) * n + j] *= d[static_cast<std::size_t>(i)];
  return a;
}
Mat add(Mat a, const Mat& b) {
  for (std::size_t i = 0; i < a.size(); ++i) a[i] += b[i];
  return a;
}

// Solves a x = b for the n columns of b (LU with partial pivoting); a and b are overwritten.
Mat solve(Mat a, Mat b, int n) {
  for (int k = 0; k < n; ++k) {
    int piv = k;
    for (int i = k + 1; i < n; ++i) {
      if (std::abs(a[static_cast<std::size_t>(i) * n + k]) > std::abs(a[static_cast<std::size_t>(piv) * n + k])) piv = i;
    }
    if (a[static_cast<std::size_t>(piv) * n + k] == 0.0) throw std::runtime_error("slab solver: singular matrix");
    if (piv != k) {
      for (int j = 0; j < n; ++j) {
        std::swap(a[static_cast<std::size_t>(k) * n + j], a[static_cast<std::size_t>(piv) * n + j]);
        std::swap(b[static_cast<std::size_t>(k) * n + j], b[static_cast<std::size_t>(piv) * n + j]);
      }
    }
    const double inv = 1.0 / a[static_cast<std::size_t>(k) * n + k];
    for (int i = k + 1; i < n; ++i) {
      const double f = a[static_cast<std::size_t>(i) * n + k] * inv;
      if (f == 0.0) continue;
      for (int j = k; j < n; ++j) a[static_cast<std::size_t>(i) * n + j] -= f * a[static_cast<std::size_t>(k) * n + j];
      for (int j = 0; j < n; ++j) b[static_cast<std::size_t>(i) * n + j] -= f * b[static_cast<std::size_t>(k) * n + j];
    }
  }
  for (int k = n - 1; k >= 0; --k) {
    const double inv = 1.0 / a[static_cast<std::size_t>(k) * n + k];
    for (int j = 0; j < n; ++j) {
      double s = b[static_cast<std::size_t>(k) * n + j];
      for (int i = k + 1; i < n; ++i) s -= a[static_cast<std::size_t>(k) * n + i] * b[static_cast<std::size_t>(i) * n + j];
      b[static_cast<std::size_t>(k) * n + j] = s * inv;
    }
  }
  return b;
}

// The azimuthal mean (1 / 2 pi) int P(cos Theta) dphi of 4 pi p, for directions with cosines
// mu_out (outgoing, signed: > 0 up) and -mu0 (incident, going down): cos Theta = -mu_out mu0 +
// s s0 cos phi. Gauss-Legendre over phi in (0, pi) (the integrand is even in phi).
double azimuthal_mean(const std::function<double(double)>& p, double mu_out, double mu0) {
  static thread_local std::vector<double> x, w;
  if (x.empty()) gauss_legendre(512, 0.0, kPi, x, w);
  const double s = std::sqrt(std::max(0.0, 1.0 - mu_out * mu_out)), s0 = std::sqrt(std::max(0.0, 1.0 - mu0 * mu0));
  double sum = 0.0;
  for (std::size_t k = 0; k < x.size(); ++k) {
    const double c = std::clamp(-mu_out * mu0 + s * s0 * std::cos(x[k]), -1.0, 1.0);
    sum += w[k] * 4.0 * kPi * p(c);
  }
  return sum / kPi;
}

}  // namespace

void gauss_legendre(int n, double a, double b, std::vector<double>& x, std::vector<double>& w) {
  x.assign(static_cast<std::size_t>(n), 0.0);
  w.assign(static_cast<std::size_t>(n), 0.0);
  std::vector<double> p(static_cast<std::size_t>(n) + 1);
  for (int i = 0; i < n; ++i) {
    double z = std::cos(kPi * (i + 0.75) / (n + 0.5)), dp = 0.0;
    for (int it = 0; it < 100; ++it) {
      legendre(z, n, p.data());
      dp = n * (z * p[static_cast<std::size_t>(n)] - p[static_cast<std::size_t>(n) - 1]) / (z * z - 1.0);
      const double dz = p[static_cast<std::size_t>(n)] / dp;
      z -= dz;
      if (std::abs(dz) < 1e-16) break;
    }
    legendre(z, n, p.data());
    dp = n * (z * p[static_cast<std::size_t>(n)] - p[static_cast<std::size_t>(n) - 1]) / (z * z - 1.0);
    // Ascending order on (a, b).
    const std::size_t k = static_cast<std::size_t>(n - 1 - i);
    x[k] = 0.5 * (a + b) + 0.5 * (b - a) * z;
    w[k] = (b - a) / ((1.0 - z * z) * dp * dp);
  }
}

PhaseFunction isotropic_phase() {
  return {[](double) { return 1.0 / (4.0 * kPi); },
          [](int l_max) {
            std::vector<double> m(static_cast<std::size_t>(l_max) + 1, 0.0);
            m[0] = 1.0;
            return m;
          }};
}

PhaseFunction henyey_greenstein_phase(double g) {
  if (!(std::abs(g) < 1.0)) throw std::invalid_argument("henyey_greenstein_phase: |g| must be below 1");
  return {[g](double mu) {
            // For g < 0 the mirrored form keeps the backward peak's digits.
            return g >= 0.0 ? hg_value(mu, g, 1.0 - g) : hg_value(-mu, -g, 1.0 + g);
          },
          [g](int l_max) { return hg_moments(g, l_max); }};
}

PhaseFunction draine_phase(double g, double alpha) {
  const double norm = 1.0 + alpha * (1.0 + 2.0 * g * g) / 3.0;
  return {[g, alpha, norm](double mu) { return hg_value(mu, g, 1.0 - g) * (1.0 + alpha * mu * mu) / norm; },
          [g, alpha, norm](int l_max) {
            std::vector<double> m = hg_moments(g, l_max);
            const std::vector<double> m2 = hg_mu2_moments(g, l_max);
            for (std::size_t l = 0; l < m.size(); ++l) m[l] = (m[l] + alpha * m2[l]) / norm;
            return m;
          }};
}

MieFit approximate_mie_fit(double d) {
  if (!(d >= 5.0 && d <= 50.0)) {
    throw std::invalid_argument("approximate_mie_fit: only the 5-50 um branch is written, got " + std::to_string(d));
  }
  // Jendersie & d'Eon (2023), the fit for 5 <= d <= 50 um:
  //   g_HG = exp(-0.0990567 / (d - 1.67154)),       g_D = exp(-2.20679 / (d + 3.91029) - 0.428934),
  //   alpha = exp(3.62489 - 8.29288 / (d + 5.52825)), w_D = exp(-0.599085 / (d - 0.641583) - 0.665888).
  MieFit f;
  const double x = 0.0990567 / (d - 1.67154);
  f.g_hg = std::exp(-x);
  f.one_minus_g_hg = -std::expm1(-x);
  f.g_d = std::exp(-2.20679 / (d + 3.91029) - 0.428934);
  f.alpha = std::exp(3.62489 - 8.29288 / (d + 5.52825));
  f.w_d = std::exp(-0.599085 / (d - 0.641583) - 0.665888);
  return f;
}

PhaseFunction approximate_mie_phase(double d) {
  const MieFit f = approximate_mie_fit(d);
  const PhaseFunction dr = draine_phase(f.g_d, f.alpha);
  return {[f, dr](double mu) { return (1.0 - f.w_d) * hg_value(mu, f.g_hg, f.one_minus_g_hg) + f.w_d * dr.value(mu); },
          [f, dr](int l_max) {
            std::vector<double> m = hg_moments(f.g_hg, l_max);
            const std::vector<double> md = dr.moments(l_max);
            for (std::size_t l = 0; l < m.size(); ++l) m[l] = (1.0 - f.w_d) * m[l] + f.w_d * md[l];
            return m;
          }};
}

std::vector<double> moments_by_quadrature(const std::function<double(double)>& value, int l_max) {
  // In u = 1 - mu: panels [0, 1e-12], [1e-12, 1e-11], ..., [1e-3, 1e-2] toward the peak, then panels
  // 0.01 wide to u = 2 (P_l for l in the hundreds oscillates on that scale), 32 nodes each.
  std::vector<double> x, w, p(static_cast<std::size_t>(l_max) + 1);
  gauss_legendre(32, 0.0, 1.0, x, w);
  std::vector<double> m(static_cast<std::size_t>(l_max) + 1, 0.0);
  std::vector<double> edges{0.0};
  for (int e = -12; e <= -2; ++e) edges.push_back(std::pow(10.0, e));
  for (int k = 2; k <= 200; ++k) edges.push_back(0.01 * k);
  for (std::size_t k = 0; k + 1 < edges.size(); ++k) {
    const double a = edges[k], b = edges[k + 1];
    for (std::size_t i = 0; i < x.size(); ++i) {
      const double u = a + (b - a) * x[i], mu = 1.0 - u;
      legendre(mu, l_max, p.data());
      const double f = 2.0 * kPi * value(mu) * (b - a) * w[i];
      for (int l = 0; l <= l_max; ++l) m[static_cast<std::size_t>(l)] += f * p[static_cast<std::size_t>(l)];
    }
  }
  return m;
}

int SlabSolution::index(double mu) const {
  for (std::size_t i = 0; i < mu_.size(); ++i) {
    if (weight_[i] == 0.0 && std::abs(mu_[i] - mu) < 1e-12) return static_cast<int>(i);
  }
  throw std::invalid_argument("slab solution: mu " + std::to_string(mu) + " is not among the problem's mu_extra");
}

double SlabSolution::reflection(double mu, double mu0) const {
  const int n = static_cast<int>(mu_.size());
  const std::size_t k = static_cast<std::size_t>(index(mu)) * n + static_cast<std::size_t>(index(mu0));
  return r_[k] + r_ss_fix_[k];
}

double SlabSolution::reflection(double mu, double mu0, double dphi) const {
  if (r_modes_.size() < 2) throw std::invalid_argument("slab solution: solved for the azimuthal mean only (SlabOptions::azimuth_modes)");
  const int n = static_cast<int>(mu_.size());
  const std::size_t k = static_cast<std::size_t>(index(mu)) * n + static_cast<std::size_t>(index(mu0));
  double r = 0.0, truncated = 0.0;
  for (std::size_t m = 0; m < r_modes_.size(); ++m) {
    const double c = (m == 0 ? 1.0 : 2.0) * std::cos(static_cast<double>(m) * dphi);
    r += c * r_modes_[m][k];
    truncated += c * p_refl_modes_[m][k];
  }
  if (tms_) {
    // TMS at this azimuth: single scattering with the whole phase function instead of the truncated one.
    const double s1 = std::sqrt(std::max(0.0, 1.0 - mu * mu)), s0 = std::sqrt(std::max(0.0, 1.0 - mu0 * mu0));
    const double cos_theta = std::clamp(-mu * mu0 + s1 * s0 * std::cos(dphi), -1.0, 1.0);
    const double geom = -std::expm1(-scaled_tau * (1.0 / mu + 1.0 / mu0)) / (mu + mu0) / 4.0;
    r += geom * (omega_ / (1.0 - f_ * omega_) * 4.0 * kPi * phase_value_(cos_theta) - omega_s_ * truncated);
  }
  return r;
}

double SlabSolution::diffuse_transmission(double mu, double mu0) const {
  const int n = static_cast<int>(mu_.size());
  return t_[static_cast<std::size_t>(index(mu)) * n + static_cast<std::size_t>(index(mu0))];
}

double SlabSolution::plane_albedo(double mu0) const {
  const int n = static_cast<int>(mu_.size()), j = index(mu0);
  double a = 0.0;
  for (int i = 0; i < n; ++i) a += weight_[static_cast<std::size_t>(i)] * r_[static_cast<std::size_t>(i) * n + j];
  return a;
}

double SlabSolution::total_transmission(double mu0) const {
  const int n = static_cast<int>(mu_.size()), j = index(mu0);
  double t = direct_[static_cast<std::size_t>(j)];
  for (int i = 0; i < n; ++i) t += weight_[static_cast<std::size_t>(i)] * t_[static_cast<std::size_t>(i) * n + j];
  return t;
}

double SlabSolution::spherical_albedo() const {
  const int n = static_cast<int>(mu_.size());
  double s = 0.0;
  for (int j = 0; j < n; ++j) {
    const double wj = weight_[static_cast<std::size_t>(j)];
    if (wj == 0.0) continue;
    double a = 0.0;
    for (int i = 0; i < n; ++i) a += weight_[static_cast<std::size_t>(i)] * r_[static_cast<std::size_t>(i) * n + j];
    s += wj * a;
  }
  return s;
}

double SlabSolution::nadir_radiance_over_ground(double mu0, double ground) const {
  return nadir_radiance(mu0) +
         ground / 3.14159265358979323846 * mu0 * total_transmission(mu0) * total_transmission(1.0) / (1.0 - ground * spherical_albedo());
}

SlabSolution solve_slab(const SlabProblem& prob, const SlabOptions& opt) {
  if (opt.streams < 2) throw std::invalid_argument("solve_slab: at least 2 streams per hemisphere");
  if (!(prob.tau > 0.0) || !(prob.omega > 0.0 && prob.omega <= 1.0)) throw std::invalid_argument("solve_slab: tau > 0, 0 < omega <= 1");
  SlabSolution s;
  // Nodes: double Gauss on (0, 1), then the extra directions with zero weight.
  std::vector<double> x, w;
  gauss_legendre(opt.streams, 0.0, 1.0, x, w);
  for (std::size_t i = 0; i < x.size(); ++i) {
    s.mu_.push_back(x[i]);
    s.weight_.push_back(2.0 * w[i] * x[i]);
  }
  for (double m : prob.mu_extra) {
    if (!(m > 0.0 && m <= 1.0)) throw std::invalid_argument("solve_slab: mu_extra must lie in (0, 1]");
    bool have = false;
    for (std::size_t i = opt.streams; i < s.mu_.size(); ++i) have = have || std::abs(s.mu_[i] - m) < 1e-12;
    if (!have) {
      s.mu_.push_back(m);
      s.weight_.push_back(0.0);
    }
  }
  const int n = static_cast<int>(s.mu_.size());
  // Delta-M: the moments beyond 2N - 1 go into a forward delta of weight f = chi_2N.
  const int L = 2 * opt.streams;
  const std::vector<double> chi = prob.phase.moments(L);
  const double f = opt.delta_m ? chi[static_cast<std::size_t>(L)] : 0.0;
  const double omega = prob.omega;
  const double omega_s = (1.0 - f) * omega / (1.0 - f * omega), tau_s = (1.0 - f * omega) * prob.tau;
  std::vector<double> chi_s(static_cast<std::size_t>(L));
  for (int l = 0; l < L; ++l) chi_s[static_cast<std::size_t>(l)] = (chi[static_cast<std::size_t>(l)] - f) / (1.0 - f);
  s.truncated_fraction = f;
  s.scaled_tau = tau_s;
  // The kernels of Fourier mode m in 4 pi normalisation: sum over l of (2l + 1) chi_l Lambda_l^m(mu)
  // Lambda_l^m(+-mu0) (Lambda_l^0 = P_l), and each mode's reflection and transmission by doubling.
  // Every mode's adding equations have the m = 0 form (the azimuth integrals of the cosine series
  // give each mode alone), so one routine serves them all.
  const int modes = opt.azimuth_modes <= 0 ? L : std::min(opt.azimuth_modes, L);
  std::vector<double> pl(static_cast<std::size_t>(n) * L);
  Mat eye(static_cast<std::size_t>(n) * n, 0.0);
  for (int i = 0; i < n; ++i) eye[static_cast<std::size_t>(i) * n + i] = 1.0;
  // The thin starting layer: tau_s / 2^k at most opt.thin_layer thick, single scattering only.
  int k = 0;
  double t0 = tau_s;
  while (t0 > opt.thin_layer) {
    t0 *= 0.5;
    ++k;
  }
  s.doublings = k;
  Mat r, tr;
  for (int m = 0; m < modes; ++m) {
    for (int i = 0; i < n; ++i) legendre_m(s.mu_[static_cast<std::size_t>(i)], m, L - 1, &pl[static_cast<std::size_t>(i) * L]);
    Mat p_refl(static_cast<std::size_t>(n) * n), p_tran(static_cast<std::size_t>(n) * n);
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        double sr = 0.0, st = 0.0;
        for (int l = m; l < L; ++l) {
          const double term = (2.0 * l + 1.0) * chi_s[static_cast<std::size_t>(l)] * pl[static_cast<std::size_t>(i) * L + l] *
                              pl[static_cast<std::size_t>(j) * L + l];
          st += term;
          sr += ((l + m) % 2 ? -term : term);  // Lambda_l^m(-x) = (-1)^(l + m) Lambda_l^m(x)
        }
        p_refl[static_cast<std::size_t>(i) * n + j] = sr;
        p_tran[static_cast<std::size_t>(i) * n + j] = st;
      }
    }
    double t = t0;
    r.assign(static_cast<std::size_t>(n) * n, 0.0);
    tr.assign(static_cast<std::size_t>(n) * n, 0.0);
    for (int i = 0; i < n; ++i) {
      const double mu = s.mu_[static_cast<std::size_t>(i)];
      for (int j = 0; j < n; ++j) {
        const double mu0 = s.mu_[static_cast<std::size_t>(j)];
        const std::size_t ij = static_cast<std::size_t>(i) * n + j;
        r[ij] = omega_s / 4.0 * p_refl[ij] * -std::expm1(-t * (1.0 / mu + 1.0 / mu0)) / (mu + mu0);
        // (exp(-t/mu) - exp(-t/mu0)) / (mu - mu0) = -exp(-t/mu) expm1(t/mu - t/mu0) / (mu - mu0).
        const double a = t / mu, b = t / mu0;
        const double diff = std::abs(mu - mu0) < 1e-12 ? std::exp(-a) * t / (mu * mu0) : -std::exp(-a) * std::expm1(a - b) / (mu - mu0);
        tr[ij] = omega_s / 4.0 * p_tran[ij] * diff;
      }
    }
    // Doubling: two identical layers (a homogeneous layer is the same seen from either side).
    std::vector<double> e(static_cast<std::size_t>(n));
    for (int d = 0; d < k; ++d) {
      for (int i = 0; i < n; ++i) e[static_cast<std::size_t>(i)] = std::exp(-t / s.mu_[static_cast<std::size_t>(i)]);
      const Mat rm = scale_cols(r, s.weight_, n), tm = scale_cols(tr, s.weight_, n);  // R M, T M
      const Mat rmr = mul(rm, r, n);                                                  // R M R
      Mat a = eye;
      const Mat rmrm = scale_cols(rmr, s.weight_, n);
      for (std::size_t q = 0; q < a.size(); ++q) a[q] -= rmrm[q];
      // D = (I - R M R M)^-1 (T + R M R E), U = R E + R M D.
      const Mat dn = solve(a, add(tr, scale_cols(rmr, e, n)), n);
      const Mat up = add(scale_cols(r, e, n), mul(rm, dn, n));
      // R' = R + E U + T M U, T' = E D + T E + T M D.
      Mat r2 = add(add(r, scale_rows(up, e, n)), mul(tm, up, n));
      Mat t2 = add(add(scale_rows(dn, e, n), scale_cols(tr, e, n)), mul(tm, dn, n));
      r = std::move(r2);
      tr = std::move(t2);
      t *= 2.0;
    }
    if (m == 0) {
      s.p_refl0_ = p_refl;
      s.t_ = tr;
      s.r_ = r;
    }
    s.r_modes_.push_back(std::move(r));
    s.p_refl_modes_.push_back(std::move(p_refl));
  }
  s.omega_ = omega;
  s.f_ = f;
  s.omega_s_ = omega_s;
  s.tms_ = opt.tms;
  s.phase_value_ = prob.phase.value;
  s.direct_.resize(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) s.direct_[static_cast<std::size_t>(i)] = std::exp(-tau_s / s.mu_[static_cast<std::size_t>(i)]);
  // TMS: in R at the extra directions, single scattering with the truncated phase is replaced by
  // single scattering with the whole phase function (omega / (1 - f omega)) in the scaled layer.
  s.r_ss_fix_.assign(static_cast<std::size_t>(n) * n, 0.0);
  if (opt.tms) {
    for (int i = opt.streams; i < n; ++i) {
      for (int j = opt.streams; j < n; ++j) {
        const double mu = s.mu_[static_cast<std::size_t>(i)], mu0 = s.mu_[static_cast<std::size_t>(j)];
        const double geom = -std::expm1(-tau_s * (1.0 / mu + 1.0 / mu0)) / (mu + mu0) / 4.0;
        const double exact = omega / (1.0 - f * omega) * azimuthal_mean(prob.phase.value, mu, mu0);
        s.r_ss_fix_[static_cast<std::size_t>(i) * n + j] = geom * (exact - omega_s * s.p_refl0_[static_cast<std::size_t>(i) * n + j]);
      }
    }
  }
  return s;
}

double delta_eddington_albedo(double tau, double g, double mu0) {
  // Conservative Eddington (Meador & Weaver 1980, omega = 1) after delta scaling g' = g / (1 + g),
  // tau' = (1 - g^2) tau: R = (c1 tau + (c3 - c1 mu0)(1 - exp(-tau / mu0))) / (1 + c1 tau) with
  // c1 = 3 (1 - g') / 4, c3 = (2 - 3 g' mu0) / 4.
  const double gs = g / (1.0 + g), ts = (1.0 - g * g) * tau;
  const double c1 = 0.75 * (1.0 - gs), c3 = (2.0 - 3.0 * gs * mu0) / 4.0;
  return (c1 * ts + (c3 - c1 * mu0) * -std::expm1(-ts / mu0)) / (1.0 + c1 * ts);
}

}  // namespace slabcheck
