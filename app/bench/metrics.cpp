// Image error metrics, the Pareto front and log-log interpolation along it (see metrics.hpp).
#include "bench/metrics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>

namespace cv::bench {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

void check_sizes(const std::vector<glm::dvec3>& test, const std::vector<glm::dvec3>& ref) {
  if (test.empty() || test.size() != ref.size()) {
    throw std::invalid_argument("image_error: images of " + std::to_string(test.size()) + " and " +
                                std::to_string(ref.size()) + " pixels, expected the same non-zero size");
  }
}

// Log-log interpolation between two positive points at x (in the first coordinate).
double loglog(double x0, double y0, double x1, double y1, double x) {
  if (x1 == x0) return std::min(y0, y1);
  const double f = (std::log(x) - std::log(x0)) / (std::log(x1) - std::log(x0));
  return std::exp(std::log(y0) + f * (std::log(y1) - std::log(y0)));
}
}  // namespace

double luminance(const glm::dvec3& c) { return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z; }

ImageError image_error(const std::vector<glm::dvec3>& test, const std::vector<glm::dvec3>& ref,
                       const std::vector<double>& ref_lum_variance) {
  check_sizes(test, ref);
  if (!ref_lum_variance.empty() && ref_lum_variance.size() != ref.size()) {
    throw std::invalid_argument("image_error: " + std::to_string(ref_lum_variance.size()) + " variances for " +
                                std::to_string(ref.size()) + " reference pixels, expected one per pixel");
  }
  const double n = static_cast<double>(ref.size());
  double sum_ref = 0.0, max_ref = 0.0, sum_d = 0.0, sum_d2 = 0.0, max_d = 0.0, sum_var = 0.0;
  double sum_x2 = 0.0;  // of x = d^2 - var per pixel, for the spread of the corrected mean square
  for (std::size_t i = 0; i < ref.size(); ++i) {
    const double lr = luminance(ref[i]), d = luminance(test[i]) - lr;
    const double var = ref_lum_variance.empty() ? 0.0 : std::max(ref_lum_variance[i], 0.0);
    sum_var += var;
    sum_x2 += (d * d - var) * (d * d - var);
    sum_ref += lr;
    max_ref = std::max(max_ref, lr);
    sum_d += d;
    sum_d2 += d * d;
    max_d = std::max(max_d, std::abs(d));
  }
  ImageError e;
  e.ref_mean = sum_ref / n;
  e.ref_max = max_ref;
  e.rmse = std::sqrt(sum_d2 / n);
  if (!(e.ref_mean > 0.0)) {
    e.rel_rmse = e.rel_rmse_raw = e.rel_noise_floor = e.rel_rmse_resolution = e.rel_bias = e.worst = e.psnr_db = kNaN;
    return e;
  }
  e.rel_rmse_raw = e.rmse / e.ref_mean;
  e.rel_noise_floor = std::sqrt(sum_var / n) / e.ref_mean;
  e.rel_rmse = std::sqrt(std::max(sum_d2 - sum_var, 0.0) / n) / e.ref_mean;
  if (!ref_lum_variance.empty() && n > 1.0) {
    // The corrected mean square is a mean over pixels of x = d^2 - var; its standard error, from the
    // pixels' own spread of x, says how small an error this reference can tell from zero.
    const double mean_x = (sum_d2 - sum_var) / n;
    const double se_x = std::sqrt(std::max(sum_x2 / n - mean_x * mean_x, 0.0) / (n - 1.0));
    e.rel_rmse_resolution = std::sqrt(2.0 * se_x) / e.ref_mean;
  }
  e.rel_bias = sum_d / n / e.ref_mean;
  e.worst = max_d / max_ref;
  e.psnr_db = e.rmse > 0.0 ? 20.0 * std::log10(max_ref / e.rmse) : std::numeric_limits<double>::infinity();
  return e;
}

std::vector<double> pixel_error(const std::vector<glm::dvec3>& test, const std::vector<glm::dvec3>& ref) {
  check_sizes(test, ref);
  double max_ref = 0.0;
  for (const auto& c : ref) max_ref = std::max(max_ref, luminance(c));
  std::vector<double> out(ref.size(), 0.0);
  if (!(max_ref > 0.0)) return out;
  for (std::size_t i = 0; i < ref.size(); ++i) out[i] = std::abs(luminance(test[i]) - luminance(ref[i])) / max_ref;
  return out;
}

std::vector<std::size_t> pareto_front(const std::vector<TimeError>& pts) {
  std::vector<std::size_t> idx;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const auto& p = pts[i];
    if (std::isfinite(p.time) && std::isfinite(p.error) && p.time > 0.0 && p.error > 0.0) idx.push_back(i);
  }
  // By time, ties by error: a sweep keeps each point that beats the best error seen so far.
  std::sort(idx.begin(), idx.end(), [&](std::size_t a, std::size_t b) {
    return pts[a].time != pts[b].time ? pts[a].time < pts[b].time : pts[a].error < pts[b].error;
  });
  std::vector<std::size_t> front;
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i : idx) {
    if (pts[i].error < best) {
      front.push_back(i);
      best = pts[i].error;
    }
  }
  return front;
}

double front_time_for_error(const std::vector<TimeError>& front, double error) {
  if (front.empty() || !(error > 0.0)) return kNaN;
  if (error >= front.front().error) return front.front().time;
  for (std::size_t i = 1; i < front.size(); ++i) {
    if (front[i].error <= error) {
      return loglog(front[i - 1].error, front[i - 1].time, front[i].error, front[i].time, error);
    }
  }
  return kNaN;
}

double front_error_at_time(const std::vector<TimeError>& front, double time) {
  if (front.empty() || !(time >= front.front().time)) return kNaN;
  for (std::size_t i = 1; i < front.size(); ++i) {
    if (front[i].time >= time) return loglog(front[i - 1].time, front[i - 1].error, front[i].time, front[i].error, time);
  }
  return front.back().error;
}

}  // namespace cv::bench
