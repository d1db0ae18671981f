// Numerical helpers for tests: adaptive quadrature over the sphere and a chi-square test.
#pragma once

#include <cmath>
#include <functional>
#include <vector>

namespace cv::test {

// Adaptive Simpson on [a, b] to absolute tolerance tol; handles the narrow forward peaks of phase
// functions with |g| up to 0.99 by subdividing where they are.
// The first few levels always subdivide, so a peak that falls between the first five samples is
// never taken for a smooth function.
inline double adaptive_simpson(const std::function<double(double)>& f, double a, double b, double tol,
                               int max_depth = 60) {
  constexpr int kMinLevels = 5;
  struct Rec {
    static double run(const std::function<double(double)>& f, double a, double b, double fa, double fm,
                      double fb, double whole, double tol, int depth, int level) {
      const double m = 0.5 * (a + b);
      const double lm = 0.5 * (a + m), rm = 0.5 * (m + b);
      const double flm = f(lm), frm = f(rm);
      const double left = (m - a) / 6.0 * (fa + 4.0 * flm + fm);
      const double right = (b - m) / 6.0 * (fm + 4.0 * frm + fb);
      const double delta = left + right - whole;
      if (depth <= 0 || (level >= kMinLevels && std::abs(delta) <= 15.0 * tol)) return left + right + delta / 15.0;
      return run(f, a, m, fa, flm, fm, left, 0.5 * tol, depth - 1, level + 1) +
             run(f, m, b, fm, frm, fb, right, 0.5 * tol, depth - 1, level + 1);
    }
  };
  const double fa = f(a), fb = f(b), fm = f(0.5 * (a + b));
  const double whole = (b - a) / 6.0 * (fa + 4.0 * fm + fb);
  return Rec::run(f, a, b, fa, fm, fb, whole, tol, max_depth, 0);
}

// Integral over the sphere of an azimuthally symmetric function of mu: 2 pi int_{-1}^{1} f dmu.
// The interval is split at several points near mu = +-1 so a narrow peak is never stepped over.
inline double sphere_integral(const std::function<double(double)>& f, double tol = 1e-11) {
  const std::vector<double> knots = {-1.0, -0.9999, -0.999, -0.99, -0.9, 0.0, 0.9, 0.99, 0.999, 0.9999, 1.0};
  double sum = 0.0;
  for (size_t i = 0; i + 1 < knots.size(); ++i) sum += adaptive_simpson(f, knots[i], knots[i + 1], tol);
  return 2.0 * 3.14159265358979323846 * sum;
}

// Critical chi-square value for dof degrees of freedom at upper-tail probability given by z, the
// standard normal quantile (Wilson-Hilferty; z = 3.719 is p = 1e-4).
inline double chi2_critical(int dof, double z) {
  const double k = dof;
  const double t = 1.0 - 2.0 / (9.0 * k) + z * std::sqrt(2.0 / (9.0 * k));
  return k * t * t * t;
}

struct Chi2Result {
  double statistic = 0.0;
  int dof = 0;
  double critical = 0.0;
  bool pass() const { return statistic <= critical; }
};

// Pearson's test of observed counts against expected counts; bins expecting fewer than 5 are
// pooled with their neighbours, as the test requires.
inline Chi2Result chi2_test(const std::vector<double>& observed, const std::vector<double>& expected,
                            double z = 3.719) {
  Chi2Result r;
  double o = 0.0, e = 0.0;
  int bins = 0;
  for (size_t i = 0; i < observed.size(); ++i) {
    o += observed[i];
    e += expected[i];
    if (e >= 5.0 || i + 1 == observed.size()) {
      if (e > 0.0) {
        r.statistic += (o - e) * (o - e) / e;
        ++bins;
      }
      o = e = 0.0;
    }
  }
  r.dof = bins - 1;
  r.critical = chi2_critical(r.dof, z);
  return r;
}

}  // namespace cv::test
