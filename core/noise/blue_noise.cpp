// Void and cluster (R. Ulichney, "The void-and-cluster method for dither array generation",
// Proc. SPIE 1913, 1993): ranks placed one at a time where the filtered point pattern is tightest
// (removing) or emptiest (adding), so every threshold of the mask is a blue-noise point set.
#include "noise/blue_noise.hpp"

#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

namespace cv::core {
namespace {

// The filtered pattern: energy[p] = sum over points q of the wrapped Gaussian of |p - q|.
// Adding or removing a point updates every pixel (O(n^2)); the kernel is tabulated once.
class Energy {
 public:
  Energy(int n, double sigma_px)
      : n_(n), kernel_(static_cast<std::size_t>(n) * n), energy_(kernel_.size(), 0.0) {
    for (int dy = 0; dy < n; ++dy)
      for (int dx = 0; dx < n; ++dx) {
        // Toroidal distance: the mask must tile, so the pattern repels across its edges too.
        const double wx = std::min(dx, n - dx), wy = std::min(dy, n - dy);
        kernel_[static_cast<std::size_t>(dy) * n + dx] =
            std::exp(-(wx * wx + wy * wy) / (2.0 * sigma_px * sigma_px));
      }
  }
  void add(int p, double sign) {
    const int px = p % n_, py = p / n_;
    for (int y = 0; y < n_; ++y) {
      const double* k = &kernel_[static_cast<std::size_t>((y - py + n_) % n_) * n_];
      double* e = &energy_[static_cast<std::size_t>(y) * n_];
      for (int x = 0; x < n_; ++x) e[x] += sign * k[(x - px + n_) % n_];
    }
  }
  // The point (is_one) with the highest energy: the tightest cluster; or the empty pixel with the
  // lowest: the largest void. Ties go to the lowest index, so the result is deterministic.
  int tightest_cluster(const std::vector<char>& is_one) const { return extreme(is_one, true); }
  int largest_void(const std::vector<char>& is_one) const { return extreme(is_one, false); }

 private:
  int extreme(const std::vector<char>& is_one, bool ones_max) const {
    int best = -1;
    for (std::size_t i = 0; i < energy_.size(); ++i) {
      if (static_cast<bool>(is_one[i]) != ones_max) continue;
      if (best < 0 || (ones_max ? energy_[i] > energy_[static_cast<std::size_t>(best)]
                                : energy_[i] < energy_[static_cast<std::size_t>(best)]))
        best = static_cast<int>(i);
    }
    return best;
  }
  int n_;
  std::vector<double> kernel_, energy_;
};

}  // namespace

BlueNoiseMask make_blue_noise(int n, std::uint32_t seed, double sigma_px) {
  if (n < 4 || n > 4096)
    throw std::invalid_argument("blue-noise mask size " + std::to_string(n) + ": expected 4 .. 4096");
  if (!(sigma_px > 0.0)) throw std::invalid_argument("blue-noise filter width must be > 0 pixels");
  const int total = n * n;
  std::vector<char> pattern(static_cast<std::size_t>(total), 0);
  Energy energy(n, sigma_px);
  // The initial binary pattern: a tenth of the pixels, at random (mt19937 is the same everywhere).
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> pick(0, total - 1);
  const int ones = std::max(1, total / 10);
  for (int placed = 0; placed < ones;) {
    const int p = pick(rng);
    if (pattern[static_cast<std::size_t>(p)]) continue;
    pattern[static_cast<std::size_t>(p)] = 1;
    energy.add(p, 1.0);
    ++placed;
  }
  // Even it out: move the tightest cluster's point into the largest void until that point is
  // itself the largest void (every point is then where the filter wants it).
  for (int moves = 0; moves < 100 * total; ++moves) {
    const int c = energy.tightest_cluster(pattern);
    pattern[static_cast<std::size_t>(c)] = 0;
    energy.add(c, -1.0);
    const int v = energy.largest_void(pattern);
    pattern[static_cast<std::size_t>(v)] = 1;
    energy.add(v, 1.0);
    if (v == c) break;
  }
  std::vector<int> rank(static_cast<std::size_t>(total), -1);
  // Phase 1: ranks below the initial count, removing the tightest clusters from a copy.
  {
    std::vector<char> p1 = pattern;
    Energy e1 = energy;
    for (int r = ones - 1; r >= 0; --r) {
      const int c = e1.tightest_cluster(p1);
      p1[static_cast<std::size_t>(c)] = 0;
      e1.add(c, -1.0);
      rank[static_cast<std::size_t>(c)] = r;
    }
  }
  // Phases 2 and 3: the remaining ranks fill the largest voids. Past half full, Ulichney takes the
  // tightest cluster of the empty pixels; with a fixed total filter mass that is the same pixel as
  // the lowest energy of the points, so one loop does both.
  for (int r = ones; r < total; ++r) {
    const int v = energy.largest_void(pattern);
    pattern[static_cast<std::size_t>(v)] = 1;
    energy.add(v, 1.0);
    rank[static_cast<std::size_t>(v)] = r;
  }
  BlueNoiseMask m;
  m.n = n;
  m.values.resize(static_cast<std::size_t>(total));
  const double scale = 1.0 / static_cast<double>(total);
  for (std::size_t i = 0; i < m.values.size(); ++i) m.values[i] = static_cast<float>(rank[i] * scale);
  return m;
}

const BlueNoiseMask& step_jitter_mask() {
  static const BlueNoiseMask mask = make_blue_noise(64, 1);
  return mask;
}

}  // namespace cv::core
