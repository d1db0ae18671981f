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
  if (!(tau >= 0.0) || !std::isfinite(tau)) throw std::invalid_argument("MsSlab::solve: optical depth " + std::to_string(tau) + " is not >= 0");
  if (!(mu0 > 0.0 && mu0 <= 1.0)) throw std::invalid_argument("MsSlab::solve: mu0 " + std::to_string(mu0) + " outside (0, 1]");
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
      rhs(i) = -qp * scale;
      rhs(n + i) = qm * scale;
      qmax = std::max({qmax, std::abs(qp), std::abs(qm)});
    }
    if (qmax == 0.0) {  // no light in this mode (an overhead sun's modes m >= 1)
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
    const Eigen::VectorXd z = big.fullPivLu().solve(rhs);
    for (int i = 0; i < n; ++i) {
      ms.zp[static_cast<std::size_t>(i)] = z(i);
      ms.zm[static_cast<std::size_t>(i)] = z(n + i);
    }
    // The boundaries: no diffuse light comes down at the top, none up from the black ground.
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
      r(n + i) = -ms.zm[static_cast<std::size_t>(i)] * beam_bottom;
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
  double f = mu0_ * std::exp(-std::clamp(t, 0.0, tau_) / mu0_);
  for (int i = 0; i < s.n_; ++i)
    f += 2.0 * kPi * s.w_[static_cast<std::size_t>(i)] * s.mu_[static_cast<std::size_t>(i)] * (radiance(0, i, t) - radiance(0, s.n_ + i, t));
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

}  // namespace cv::core
