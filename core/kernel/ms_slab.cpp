// The slab's diffuse radiance by discrete ordinates (ms_slab.hpp; docs/physics.md, "The slab's
// diffuse radiance by discrete ordinates"). Per Fourier mode the 2N equations for the radiance at
// the double-Gauss nodes reduce to an N x N eigenproblem (Stamnes and Swanson 1981, J. Atmos. Sci.
// 38): with A = M^-1 (alpha - 1), B = M^-1 beta (alpha, beta the in-scatter between nodes of the same
// and of opposite hemispheres), e^(-k tau) solutions have k^2 the eigenvalues of (A - B)(A + B).
#include "kernel/ms_slab.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include <Eigen/Dense>

#include "io/parallel.hpp"
#include "kernel/ms_slab.glsl"
#include "kernel/ms_source.hpp"

namespace cv::core {
namespace {
constexpr double kPi = 3.14159265358979323846;

// Gauss-Legendre nodes and weights on (a, b), n of them, by Newton's iteration on P_n.
void gauss_legendre(int n, double a, double b, std::vector<double>& x, std::vector<double>& w) {
  x.assign(static_cast<std::size_t>(n), 0.0);
  w.assign(static_cast<std::size_t>(n), 0.0);
  for (int i = 0; i < n; ++i) {
    double z = std::cos(kPi * (i + 0.75) / (n + 0.5));
    double dp = 1.0;
    for (int it = 0; it < 100; ++it) {
      double p0 = 1.0, p1 = z;
      for (int k = 2; k <= n; ++k) {
        const double p2 = ((2 * k - 1) * z * p1 - (k - 1) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      if (n == 1) p0 = 1.0, p1 = z;
      dp = n * (z * p1 - p0) / (z * z - 1.0);
      const double dz = p1 / dp;
      z -= dz;
      if (std::abs(dz) < 1e-16) break;
    }
    // Recompute the derivative at the converged node for the weight.
    double p0 = 1.0, p1 = z;
    for (int k = 2; k <= n; ++k) {
      const double p2 = ((2 * k - 1) * z * p1 - (k - 1) * p0) / k;
      p0 = p1;
      p1 = p2;
    }
    dp = n * (z * p1 - p0) / (z * z - 1.0);
    const std::size_t j = static_cast<std::size_t>(n - 1 - i);  // ascending
    x[j] = 0.5 * (b - a) * z + 0.5 * (b + a);
    w[j] = (b - a) / ((1.0 - z * z) * dp * dp);
  }
}

// P_l(x) for l = 0 .. l_max.
std::vector<double> legendre_all(int l_max, double x) {
  std::vector<double> p(static_cast<std::size_t>(l_max + 1), 0.0);
  p[0] = 1.0;
  if (l_max >= 1) p[1] = x;
  for (int l = 2; l <= l_max; ++l) p[static_cast<std::size_t>(l)] = ((2 * l - 1) * x * p[static_cast<std::size_t>(l - 1)] - (l - 1) * p[static_cast<std::size_t>(l - 2)]) / l;
  return p;
}
}  // namespace

std::vector<double> ms_slab_legendre(int m, int l_max, double mu) {
  std::vector<double> out;
  if (l_max < m || m < 0) return out;
  out.assign(static_cast<std::size_t>(l_max - m + 1), 0.0);
  const double s = std::sqrt(std::max(0.0, 1.0 - mu * mu));
  double lmm = 1.0;
  for (int k = 1; k <= m; ++k) lmm *= std::sqrt((2.0 * k - 1.0) / (2.0 * k)) * s;
  out[0] = lmm;
  if (l_max >= m + 1) out[1] = std::sqrt(2.0 * m + 1.0) * mu * lmm;
  for (int l = m + 2; l <= l_max; ++l) {
    const std::size_t i = static_cast<std::size_t>(l - m);
    out[i] = ((2.0 * l - 1.0) * mu * out[i - 1] - std::sqrt(static_cast<double>((l - 1) * (l - 1) - m * m)) * out[i - 2]) /
             std::sqrt(static_cast<double>(l * l - m * m));
  }
  return out;
}

std::vector<double> ms_clipped_moments(const std::function<double(double)>& phase, double cut, int l_max, double* share_cut) {
  if (l_max < 0) throw std::invalid_argument("ms_clipped_moments: l_max " + std::to_string(l_max) + " is negative");
  auto p = [&](double mu) {
    const double v = phase(mu);
    return std::isfinite(v) ? std::max(v, 0.0) : 0.0;
  };
  // The cone's edge: from the forward direction back along cosines packed toward 1, the first place
  // the phase is below the cut, then bisection.
  double mu_c = 1.0;
  if (p(1.0) > cut) {
    constexpr int kScan = 4000;
    double prev = 1.0;
    mu_c = -1.0;
    for (int i = 1; i <= kScan; ++i) {
      const double mu = 1.0 - 2.0 * std::pow(static_cast<double>(i) / kScan, 3.0);  // dense near 1
      if (p(mu) <= cut) {
        double lo = mu, hi = prev;  // p(lo) <= cut < p(hi)
        for (int it = 0; it < 200 && hi - lo > 1e-15; ++it) {
          const double mid = 0.5 * (lo + hi);
          (p(mid) > cut ? hi : lo) = mid;
        }
        mu_c = 0.5 * (lo + hi);
        break;
      }
      prev = mu;
    }
  }
  // Below the cut: Gauss-Legendre panels on (-1, mu_c), finer toward the cone's edge.
  std::vector<double> sum(static_cast<std::size_t>(l_max + 1), 0.0);
  std::vector<double> gx, gw;
  gauss_legendre(24, 0.0, 1.0, gx, gw);
  constexpr int kPanels = 96;
  const double span = mu_c + 1.0;
  for (int k = 0; k < kPanels && span > 0.0; ++k) {
    // Panel edges at -1 + span (1 - (1 - u)^2): narrower toward mu_c.
    auto edge = [&](int e) {
      const double u = static_cast<double>(e) / kPanels;
      return -1.0 + span * (1.0 - (1.0 - u) * (1.0 - u));
    };
    const double a = edge(k), b = edge(k + 1);
    for (std::size_t q = 0; q < gx.size(); ++q) {
      const double mu = a + (b - a) * gx[q];
      const double v = std::min(p(mu), cut) * (b - a) * gw[q];
      const std::vector<double> pl = legendre_all(l_max, mu);
      for (int l = 0; l <= l_max; ++l) sum[static_cast<std::size_t>(l)] += v * pl[static_cast<std::size_t>(l)];
    }
  }
  // Above: the flat cut, int_mu_c^1 P_l = (P_(l-1)(mu_c) - P_(l+1)(mu_c)) / (2 l + 1), l >= 1.
  const std::vector<double> pc = legendre_all(l_max + 1, mu_c);
  sum[0] += cut * (1.0 - mu_c);
  for (int l = 1; l <= l_max; ++l)
    sum[static_cast<std::size_t>(l)] += cut * (pc[static_cast<std::size_t>(l - 1)] - pc[static_cast<std::size_t>(l + 1)]) / (2 * l + 1);
  const double kept = 2.0 * kPi * sum[0];
  if (!(kept > 0.0)) throw std::invalid_argument("ms_clipped_moments: the phase cut at " + std::to_string(cut) + " keeps nothing");
  if (share_cut) *share_cut = 1.0 - kept;  // the phase integrates to 1
  std::vector<double> chi(sum.size());
  for (std::size_t l = 0; l < sum.size(); ++l) chi[l] = sum[l] / sum[0];
  return chi;
}

MsSlab::MsSlab(std::vector<double> chi, double omega, int streams, int modes) : chi_(std::move(chi)), omega_(omega), n_(streams) {
  if (streams < 2 || streams > 256) throw std::invalid_argument("MsSlab: streams " + std::to_string(streams) + " outside 2..256");
  if (modes < 1) throw std::invalid_argument("MsSlab: modes " + std::to_string(modes) + " below 1");
  if (chi_.empty() || !(std::abs(chi_[0] - 1.0) < 1e-9)) throw std::invalid_argument("MsSlab: chi_0 is not 1");
  if (!(omega > 0.0 && omega <= 1.0)) throw std::invalid_argument("MsSlab: omega " + std::to_string(omega) + " outside (0, 1]");
  l_max_ = std::min(static_cast<int>(chi_.size()) - 1, 2 * n_ - 2);
  chi_.resize(static_cast<std::size_t>(l_max_ + 1));
  gauss_legendre(n_, 0.0, 1.0, mu_, w_);
  const int n = n_;
  const bool conservative = omega_ >= 1.0 - 1e-12;
  for (int m = 0; m < modes && m <= l_max_; ++m) {
    Mode md;
    md.m = m;
    const int nl = l_max_ - m + 1;
    md.lam_pos.assign(static_cast<std::size_t>(n * nl), 0.0);
    for (int i = 0; i < n; ++i) {
      const std::vector<double> lam = ms_slab_legendre(m, l_max_, mu_[static_cast<std::size_t>(i)]);
      std::copy(lam.begin(), lam.end(), md.lam_pos.begin() + static_cast<std::ptrdiff_t>(i * nl));
    }
    md.d_same.assign(static_cast<std::size_t>(n * n), 0.0);
    md.d_opp.assign(static_cast<std::size_t>(n * n), 0.0);
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        double same = 0.0, opp = 0.0;
        for (int l = m; l <= l_max_; ++l) {
          const double t = (2 * l + 1) * 0.5 * chi_[static_cast<std::size_t>(l)] * md.lam_pos[static_cast<std::size_t>(i * nl + l - m)] *
                           md.lam_pos[static_cast<std::size_t>(j * nl + l - m)];
          same += t;
          opp += ((l + m) % 2 ? -t : t);
        }
        md.d_same[static_cast<std::size_t>(i * n + j)] = omega_ * same;
        md.d_opp[static_cast<std::size_t>(i * n + j)] = omega_ * opp;
      }
    }
    Eigen::MatrixXd a(n, n), b(n, n);
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        const double wj = w_[static_cast<std::size_t>(j)];
        a(i, j) = (md.d_same[static_cast<std::size_t>(i * n + j)] * wj - (i == j ? 1.0 : 0.0)) / mu_[static_cast<std::size_t>(i)];
        b(i, j) = md.d_opp[static_cast<std::size_t>(i * n + j)] * wj / mu_[static_cast<std::size_t>(i)];
      }
    }
    const Eigen::MatrixXd apb = a + b, amb = a - b;
    Eigen::EigenSolver<Eigen::MatrixXd> es(amb * apb);
    if (es.info() != Eigen::Success) throw std::runtime_error("MsSlab: the eigenproblem of mode " + std::to_string(m) + " did not converge");
    std::vector<std::pair<double, int>> order;
    for (int j = 0; j < n; ++j) order.emplace_back(es.eigenvalues()(j).real(), j);
    std::sort(order.begin(), order.end());  // the smallest first: the conservative pair, when there is one
    md.k.assign(static_cast<std::size_t>(n), 0.0);
    md.gp.assign(static_cast<std::size_t>(n * n), 0.0);
    md.gm.assign(static_cast<std::size_t>(n * n), 0.0);
    md.conservative_pair = conservative && m == 0;
    for (int jj = 0; jj < n; ++jj) {
      if (md.conservative_pair && jj == 0) continue;  // written out in closed form (radiance())
      const int j = order[static_cast<std::size_t>(jj)].second;
      const double k2 = std::max(order[static_cast<std::size_t>(jj)].first, 0.0);
      const double k = std::sqrt(k2);
      if (!(k > 0.0)) throw std::runtime_error("MsSlab: mode " + std::to_string(m) + " has a zero eigenvalue with omega below 1");
      Eigen::VectorXd s(n);
      for (int i = 0; i < n; ++i) s(i) = es.eigenvectors()(i, j).real();
      s.normalize();
      const Eigen::VectorXd d = -(apb * s) / k;
      md.k[static_cast<std::size_t>(jj)] = k;
      for (int i = 0; i < n; ++i) {
        md.gp[static_cast<std::size_t>(i * n + jj)] = 0.5 * (s(i) + d(i));
        md.gm[static_cast<std::size_t>(i * n + jj)] = 0.5 * (s(i) - d(i));
      }
    }
    modes_.push_back(std::move(md));
  }
}

MsSlabField MsSlab::solve(double tau, double mu0) const {
  if (!(mu0 > 0.0 && mu0 <= 1.0)) throw std::invalid_argument("MsSlab::solve: mu0 " + std::to_string(mu0) + " outside (0, 1]");
  return solve_any(tau, mu0, false);
}

MsSlabField MsSlab::solve_lit_from_below(double tau) const { return solve_any(tau, 1.0, true); }

MsSlabField MsSlab::solve_any(double tau, double mu0, bool from_below) const {
  if (!(tau >= 0.0) || !std::isfinite(tau)) throw std::invalid_argument("MsSlab::solve: optical depth " + std::to_string(tau) + " is not >= 0");
  const int n = n_;
  // A sun whose 1 / mu0 meets an eigenvalue makes the beam's particular solution singular: it is
  // moved by a relative 1e-7 (Stamnes and co. do the same in DISORT), far below any figure here.
  for (const Mode& md : modes_) {
    for (int j = 0; j < n; ++j) {
      if (std::abs(md.k[static_cast<std::size_t>(j)] * mu0 - 1.0) < 1e-7) mu0 *= 1.0 - 3e-7;
    }
  }
  MsSlabField f;
  f.slab_ = this;
  f.tau_ = tau;
  f.mu0_ = mu0;
  f.beam_ = !from_below;
  const double c = 1.0 - omega_ * (chi_.size() > 1 ? chi_[1] : 0.0);
  for (const Mode& md : modes_) {
    const int m = md.m;
    const int nl = l_max_ - m + 1;
    MsSlabField::ModeSolution ms;
    ms.zp.assign(static_cast<std::size_t>(n), 0.0);
    ms.zm.assign(static_cast<std::size_t>(n), 0.0);
    ms.a.assign(static_cast<std::size_t>(n), 0.0);
    ms.b.assign(static_cast<std::size_t>(n), 0.0);
    // The beam's source at the nodes: omega (2 - delta_m0) sum_l (2 l + 1) / (4 pi) chi_l
    // Lambda_l^m(+-mu_i) Lambda_l^m(mu0).
    const std::vector<double> lam0 = ms_slab_legendre(m, l_max_, mu0);
    Eigen::VectorXd rhs(2 * n);
    double qmax = 0.0;
    for (int i = 0; i < n; ++i) {
      double qp = 0.0, qm = 0.0;
      for (int l = m; l <= l_max_; ++l) {
        const double t = (2 * l + 1) / (4.0 * kPi) * chi_[static_cast<std::size_t>(l)] * md.lam_pos[static_cast<std::size_t>(i * nl + l - m)] *
                         lam0[static_cast<std::size_t>(l - m)];
        qp += t;
        qm += ((l + m) % 2 ? -t : t);
      }
      const double scale = omega_ * (m == 0 ? 1.0 : 2.0) / mu_[static_cast<std::size_t>(i)];
      rhs(i) = from_below ? 0.0 : -qp * scale;
      rhs(n + i) = from_below ? 0.0 : qm * scale;
      qmax = std::max({qmax, std::abs(qp), std::abs(qm)});
    }
    if (from_below ? m > 0 : qmax == 0.0) {  // no light in this mode (an overhead sun's modes m >= 1; light from below has m = 0 alone)
      f.sol_.push_back(std::move(ms));
      continue;
    }
    Eigen::MatrixXd big = Eigen::MatrixXd::Identity(2 * n, 2 * n) / mu0;
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        const double wj = w_[static_cast<std::size_t>(j)];
        const double a = (md.d_same[static_cast<std::size_t>(i * n + j)] * wj - (i == j ? 1.0 : 0.0)) / mu_[static_cast<std::size_t>(i)];
        const double b = md.d_opp[static_cast<std::size_t>(i * n + j)] * wj / mu_[static_cast<std::size_t>(i)];
        big(i, j) += a;
        big(i, n + j) += b;
        big(n + i, j) -= b;
        big(n + i, n + j) -= a;
      }
    }
    const Eigen::VectorXd z = from_below ? Eigen::VectorXd::Zero(2 * n) : Eigen::VectorXd(big.fullPivLu().solve(rhs));
    for (int i = 0; i < n; ++i) {
      ms.zp[static_cast<std::size_t>(i)] = z(i);
      ms.zm[static_cast<std::size_t>(i)] = z(n + i);
    }
    // The boundaries: no diffuse light comes down at the top, none up from the black ground (or
    // radiance 1 up from it, lit from below).
    Eigen::MatrixXd bc(2 * n, 2 * n);
    Eigen::VectorXd r(2 * n);
    const double beam_bottom = std::exp(-tau / mu0);
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        const std::size_t ij = static_cast<std::size_t>(i * n + j);
        if (md.conservative_pair && j == 0) {
          bc(i, j) = 1.0;
          bc(i, n + j) = mu_[static_cast<std::size_t>(i)];
          bc(n + i, j) = 1.0;
          bc(n + i, n + j) = -mu_[static_cast<std::size_t>(i)] - c * tau;
          continue;
        }
        const double e = std::exp(-md.k[static_cast<std::size_t>(j)] * tau);
        bc(i, j) = md.gp[ij];
        bc(i, n + j) = md.gm[ij] * e;
        bc(n + i, j) = md.gm[ij] * e;
        bc(n + i, n + j) = md.gp[ij];
      }
      r(i) = -ms.zp[static_cast<std::size_t>(i)];
      r(n + i) = from_below ? 1.0 : -ms.zm[static_cast<std::size_t>(i)] * beam_bottom;
    }
    const Eigen::VectorXd x = bc.fullPivLu().solve(r);
    for (int j = 0; j < n; ++j) {
      ms.a[static_cast<std::size_t>(j)] = x(j);
      ms.b[static_cast<std::size_t>(j)] = x(n + j);
    }
    f.sol_.push_back(std::move(ms));
  }
  return f;
}

double MsSlabField::radiance(int m, int i, double t) const {
  if (m < 0 || m >= static_cast<int>(sol_.size())) return 0.0;
  const MsSlab& s = *slab_;
  const int n = s.n_;
  const MsSlab::Mode& md = s.modes_[static_cast<std::size_t>(m)];
  const ModeSolution& ms = sol_[static_cast<std::size_t>(m)];
  t = std::clamp(t, 0.0, tau_);
  const bool down = i < n;
  const int r = down ? i : i - n;
  const double mu = s.mu_[static_cast<std::size_t>(r)];
  double v = (down ? ms.zp : ms.zm)[static_cast<std::size_t>(r)] * std::exp(-t / mu0_);
  const double c = 1.0 - s.omega_ * (s.chi_.size() > 1 ? s.chi_[1] : 0.0);
  for (int j = 0; j < n; ++j) {
    const std::size_t rj = static_cast<std::size_t>(r * n + j);
    const double aj = ms.a[static_cast<std::size_t>(j)], bj = ms.b[static_cast<std::size_t>(j)];
    if (md.conservative_pair && j == 0) {
      v += aj + bj * ((down ? mu : -mu) - c * t);
      continue;
    }
    const double k = md.k[static_cast<std::size_t>(j)];
    const double top = std::exp(-k * t), bottom = std::exp(-k * (tau_ - t));
    v += down ? aj * md.gp[rj] * top + bj * md.gm[rj] * bottom : aj * md.gm[rj] * top + bj * md.gp[rj] * bottom;
  }
  return v;
}

std::vector<double> MsSlabField::moments(double t, int l_max) const {
  const MsSlab& s = *slab_;
  const int n = s.n_;
  if (l_max < 0 || l_max > 2 * n - 1)
    throw std::invalid_argument("MsSlabField::moments: l_max " + std::to_string(l_max) + " outside 0.." + std::to_string(2 * n - 1));
  std::vector<double> out(static_cast<std::size_t>((l_max + 1) * (l_max + 2) / 2), 0.0);
  for (int m = 0; m <= l_max && m < static_cast<int>(sol_.size()); ++m) {
    for (int i = 0; i < n; ++i) {
      const double w = s.w_[static_cast<std::size_t>(i)];
      const double down = radiance(m, i, t), up = radiance(m, n + i, t);
      const std::vector<double> lam = ms_slab_legendre(m, l_max, s.mu_[static_cast<std::size_t>(i)]);
      for (int l = m; l <= l_max; ++l)
        out[static_cast<std::size_t>(l * (l + 1) / 2 + m)] += w * lam[static_cast<std::size_t>(l - m)] * (down + ((l + m) % 2 ? -up : up));
    }
  }
  return out;
}

double MsSlabField::in_scatter(double t, double mu, double phi, int l_max) const {
  const MsSlab& s = *slab_;
  const std::vector<double> psi = moments(t, l_max);
  double j = 0.0;
  for (int m = 0; m <= l_max; ++m) {
    const std::vector<double> lam = ms_slab_legendre(m, l_max, mu);
    double sum = 0.0;
    for (int l = m; l <= std::min(l_max, s.l_max_); ++l)
      sum += (2 * l + 1) * 0.5 * s.chi_[static_cast<std::size_t>(l)] * lam[static_cast<std::size_t>(l - m)] * psi[static_cast<std::size_t>(l * (l + 1) / 2 + m)];
    j += std::cos(m * phi) * sum;
  }
  return s.omega_ * j;
}

double MsSlabField::net_flux(double t) const {
  const MsSlab& s = *slab_;
  double f = beam_ ? mu0_ * std::exp(-std::clamp(t, 0.0, tau_) / mu0_) : 0.0;
  for (int i = 0; i < s.n_; ++i)
    f += 2.0 * kPi * s.w_[static_cast<std::size_t>(i)] * s.mu_[static_cast<std::size_t>(i)] * (radiance(0, i, t) - radiance(0, s.n_ + i, t));
  return f;
}

double MsSlabField::up_flux(double t) const {
  const MsSlab& s = *slab_;
  double f = 0.0;
  for (int i = 0; i < s.n_; ++i) f += 2.0 * kPi * s.w_[static_cast<std::size_t>(i)] * s.mu_[static_cast<std::size_t>(i)] * radiance(0, s.n_ + i, t);
  return f;
}

double MsSlabField::reflected_flux() const {
  const MsSlab& s = *slab_;
  double f = 0.0;
  for (int i = 0; i < s.n_; ++i) f += 2.0 * kPi * s.w_[static_cast<std::size_t>(i)] * s.mu_[static_cast<std::size_t>(i)] * radiance(0, s.n_ + i, 0.0);
  return f / mu0_;
}

double MsSlabField::transmitted_diffuse_flux() const {
  const MsSlab& s = *slab_;
  double f = 0.0;
  for (int i = 0; i < s.n_; ++i) f += 2.0 * kPi * s.w_[static_cast<std::size_t>(i)] * s.mu_[static_cast<std::size_t>(i)] * radiance(0, i, tau_);
  return f / mu0_;
}

MsSlabTwoStream ms_slab_two_stream(double t, double b, double mu0, double g, double ground) {
  // A column of three nodes whose two layers hold the optical depths t and b (each layer's depth
  // is the mean of its ends' extinction, dz 1).
  t = std::max(std::isfinite(t) ? t : 0.0, 0.0);
  b = std::max(std::isfinite(b) ? b : 0.0, 0.0);
  const double s1 = std::min(t, b), gc = std::clamp(g, -0.999, 0.999);
  const double sigma[3] = {2.0 * b - s1, s1, 2.0 * t - s1}, gs[3] = {gc, gc, gc};
  const TwoStreamColumn c = two_stream_column(sigma, gs, 3, 1.0, mu0, ground);
  return {c.i0[1], std::clamp(ground, 0.0, 1.0) * c.transmitted * mu0 / kPi};
}

double ms_slab_two_stream_i0(double t, double b, double mu0, double g) { return ms_slab_two_stream(t, b, mu0, g, 0.0).i0; }

std::vector<double> ms_phase_moments(const std::function<double(double)>& phase, int l_max) {
  std::vector<double> chi(static_cast<std::size_t>(std::max(l_max, 0) + 1), 0.0);
  constexpr int kNodes = 40001;
  std::vector<double> prev = legendre_all(l_max, 1.0), cur;
  double prev_mu = 1.0, prev_p = phase(1.0);
  if (!std::isfinite(prev_p)) prev_p = 0.0;
  for (int i = 1; i < kNodes; ++i) {
    const double mu = i == kNodes - 1 ? -1.0 : 1.0 - 1e-12 * std::pow(2e12, static_cast<double>(i) / (kNodes - 1));
    double p = phase(mu);
    if (!std::isfinite(p)) p = 0.0;
    cur = legendre_all(l_max, mu);
    for (std::size_t l = 0; l < chi.size(); ++l) chi[l] += kPi * (p * cur[l] + prev_p * prev[l]) * (prev_mu - mu);
    prev.swap(cur);
    prev_mu = mu;
    prev_p = p;
  }
  return chi;
}

double ms_slab_share(const std::function<double(double)>& phase, double spike_weight) {
  const std::vector<double> chi = ms_phase_moments(phase, CV_MS_SLAB_L + 1);
  const double chi8 = chi[0] > 0.0 ? chi[CV_MS_SLAB_L + 1] / chi[0] : 0.0;
  return std::clamp(std::max(chi8, spike_weight / 0.98), 0.0, 0.99);
}

MsSlabTable ms_slab_table(const std::function<double(double)>& phase, double f, double g_two_stream, int streams) {
  MsSlabTable out;
  out.f = std::clamp(f, 0.0, 0.99);
  out.cut = ms_peak(phase, out.f).cut;
  out.chi = ms_clipped_moments(phase, out.cut, 2 * streams - 2);
  const MsSlab slab(out.chi, 1.0, streams, CV_MS_SLAB_L + 1);
  constexpr int nd = CV_MS_SLAB_DEPTHS;
  out.values.assign(static_cast<std::size_t>(CV_MS_SLAB_PHASE_SIZE), 0.0f);
  // The depth of a grid index: t = T0 u / (1 - u); the half-space row at 1e4 (its light is the
  // half-space's to rounding); the thinnest at 1e-3, whose shape the thin limit's is.
  auto depth = [](int i) {
    const double u = static_cast<double>(i) / (nd - 1);
    return i == nd - 1 ? 1.0e4 : std::max(CV_MS_SLAB_T0 * u / (1.0 - u), 5.0e-4);
  };
  const std::size_t cells = static_cast<std::size_t>(CV_MS_SLAB_SUNS * nd * nd);
  parallel_ranges(cells, 8, [&](std::size_t b0, std::size_t e0, unsigned) {
    for (std::size_t cell = b0; cell < e0; ++cell) {
      const int iu = static_cast<int>(cell % nd), iv = static_cast<int>((cell / nd) % nd), is = static_cast<int>(cell / (nd * nd));
      const double mu0 = CV_MS_SLAB_MU0_LO + (1.0 - CV_MS_SLAB_MU0_LO) * is / (CV_MS_SLAB_SUNS - 1);
      const double t = depth(iu), b = depth(iv);
      const MsSlabField field = slab.solve((1.0 - out.f) * (t + b), mu0);
      const std::vector<double> psi = field.moments((1.0 - out.f) * t, CV_MS_SLAB_L0);
      float* dst = out.values.data() + cell * static_cast<std::size_t>(CV_MS_SLAB_STRIDE);
      std::size_t k = 0;  // the table's order: m = 0 to degree L0, then m >= 1 to degree L
      for (int m = 0; m <= CV_MS_SLAB_L; ++m) {
        for (int l = m; l <= (m == 0 ? CV_MS_SLAB_L0 : CV_MS_SLAB_L); ++l, ++k) {
          const double v = (2 * l + 1) * 0.5 * out.chi[static_cast<std::size_t>(l)] * psi[static_cast<std::size_t>(l * (l + 1) / 2 + m)];
          dst[k] = std::isfinite(v) ? static_cast<float>(v) : 0.0f;
        }
      }
      const double down = field.net_flux((1.0 - out.f) * t) - mu0 * std::exp(-(1.0 - out.f) * t / mu0) + field.up_flux((1.0 - out.f) * t);
      dst[CV_MS_SLAB_FLUX_DOWN] = std::isfinite(down) ? static_cast<float>(std::max(down, 0.0)) : 0.0f;
      dst[CV_MS_SLAB_TWO_STREAM_I0] = static_cast<float>(ms_slab_two_stream_i0(t, b, mu0, g_two_stream));
    }
  });
  // Lit from below: per (b, t) cell (no sun).
  out.below.assign(static_cast<std::size_t>(CV_MS_SLAB_BELOW_SIZE), 0.0f);
  parallel_ranges(static_cast<std::size_t>(nd * nd), 8, [&](std::size_t b0, std::size_t e0, unsigned) {
    for (std::size_t cell = b0; cell < e0; ++cell) {
      const int iu = static_cast<int>(cell % nd), iv = static_cast<int>(cell / nd);
      const double t = depth(iu), b = depth(iv);
      const MsSlabField field = slab.solve_lit_from_below((1.0 - out.f) * (t + b));
      const std::vector<double> psi = field.moments((1.0 - out.f) * t, CV_MS_SLAB_BELOW_L);
      float* dst = out.below.data() + cell * static_cast<std::size_t>(CV_MS_SLAB_BELOW_STRIDE);
      for (int l = 0; l <= CV_MS_SLAB_BELOW_L; ++l) {
        const double v = (2 * l + 1) * 0.5 * out.chi[static_cast<std::size_t>(l)] * psi[static_cast<std::size_t>(l * (l + 1) / 2)];
        dst[l] = std::isfinite(v) ? static_cast<float>(v) : 0.0f;
      }
      const double down = field.net_flux((1.0 - out.f) * t) + field.up_flux((1.0 - out.f) * t);
      dst[CV_MS_SLAB_BELOW_FLUX_DOWN] = std::isfinite(down) ? static_cast<float>(std::max(down, 0.0)) : 0.0f;
      // The two-stream's I0 per unit of the ground's radiance: linear in it, so from one ground.
      const MsSlabTwoStream lit = ms_slab_two_stream(t, b, 0.5, g_two_stream, 0.5), dark = ms_slab_two_stream(t, b, 0.5, g_two_stream, 0.0);
      const double per = lit.ground_radiance > 0.0 ? (lit.i0 - dark.i0) / lit.ground_radiance : 0.0;
      dst[CV_MS_SLAB_BELOW_TWO_STREAM_I0] = std::isfinite(per) ? static_cast<float>(std::max(per, 0.0)) : 0.0f;
    }
  });
  return out;
}

}  // namespace cv::core
