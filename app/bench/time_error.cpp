// Interpolation error against held-back steps of real model output.
#include "bench/time_error.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "volume/column_depth.hpp"
#include "volume/grid_mean.hpp"

namespace cv::bench {
namespace {

std::vector<float> total_extinction(const core::GridMeanExtinction& e, std::size_t n) {
  std::vector<float> t(n, 0.0f);
  for (const auto* f : {&e.liquid_per_m, &e.ice_per_m})
    if (!f->empty())
      for (std::size_t p = 0; p < n; ++p) t[p] += (*f)[p];
  return t;
}

// The upper-quartile value (the 75th percentile by nearest rank).
double upper_quartile(std::vector<float> v) {
  if (v.empty()) return 0.0;
  const std::size_t k = std::min(v.size() - 1, static_cast<std::size_t>(0.75 * double(v.size())));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

// The fraction of cells above `threshold` in each square neighbourhood of side `scale` (clipped at the edges).
std::vector<double> fractions(const std::vector<float>& f, int nx, int ny, int scale, double threshold) {
  std::vector<double> out(std::size_t(nx) * std::size_t(ny), 0.0);
  const int h = scale / 2;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      int in = 0, n = 0;
      for (int b = std::max(0, j - h); b <= std::min(ny - 1, j + h); ++b)
        for (int a = std::max(0, i - h); a <= std::min(nx - 1, i + h); ++a) {
          ++n;
          in += f[std::size_t(b) * std::size_t(nx) + std::size_t(a)] > threshold ? 1 : 0;
        }
      out[std::size_t(j) * std::size_t(nx) + std::size_t(i)] = double(in) / double(n);
    }
  return out;
}

}  // namespace

double fraction_skill_score(const std::vector<float>& truth, const std::vector<float>& estimate, int nx, int ny, int scale,
                            double* num, double* den) {
  const std::vector<double> o = fractions(truth, nx, ny, scale, upper_quartile(truth));
  const std::vector<double> m = fractions(estimate, nx, ny, scale, upper_quartile(estimate));
  double n = 0.0, d = 0.0;
  for (std::size_t p = 0; p < o.size(); ++p) {
    n += (o[p] - m[p]) * (o[p] - m[p]);
    d += o[p] * o[p] + m[p] * m[p];
  }
  if (num) *num += n;
  if (den) *den += d;
  return d > 0.0 ? 1.0 - n / d : 1.0;
}

std::vector<TimeErrorRow> measure_time_error(core::CloudVolume& volume, const std::string& source, const TimeErrorOptions& options) {
  const auto& times = volume.times;
  const std::size_t n = times.size();
  if (n < 3) throw std::invalid_argument(source + ": found " + std::to_string(n) + " time step(s), expected at least 3 (two neighbours and a step between)");
  const std::int64_t dt = times[1].unix_s - times[0].unix_s;
  for (std::size_t i = 1; i < n; ++i) {
    if (times[i].unix_s - times[i - 1].unix_s != dt || dt <= 0) {
      throw std::invalid_argument(source + ": steps " + std::to_string(i - 1) + " (" + times[i - 1].iso_utc + ") and " +
                                  std::to_string(i) + " (" + times[i].iso_utc + ") are not " + std::to_string(dt) +
                                  " s apart, expected evenly spaced ascending times");
    }
  }
  const core::VolumeGrid& g = volume.grid;
  std::vector<core::GridMeanExtinction> ext(n);
  std::vector<core::StepWinds> winds(n);
  std::vector<std::vector<float>> tau(n);
  for (std::size_t i = 0; i < n; ++i) {
    const core::TimeStepData& d = volume.step(i);
    ext[i] = core::grid_mean_extinction(g, d);
    winds[i] = core::step_winds(d);
    tau[i] = core::column_depth(g, ext[i].liquid_per_m, ext[i].ice_per_m).tau;
  }
  std::vector<TimeErrorRow> rows;
  for (double gap_h : options.gaps_h) {
    const double steps_d = gap_h * 3600.0 / double(dt);
    const int gs = static_cast<int>(std::lround(steps_d));
    if (std::abs(steps_d - gs) > 1e-9 || gs < 2 || static_cast<std::size_t>(gs) >= n) continue;
    for (core::TimeInterpolation method : options.methods) {
      TimeErrorRow row;
      row.gap_h = gap_h;
      row.method = method;
      double se_ext = 0.0, se_tau = 0.0, se_cover = 0.0, ms = 0.0;
      std::size_t nodes = 0, cols = 0;
      std::array<double, kFssScales.size()> num{}, den{};
      for (std::size_t k = 0; k + static_cast<std::size_t>(gs) < n; ++k) {
        const std::size_t k1 = k + static_cast<std::size_t>(gs);
        for (std::size_t m = k + 1; m < k1; ++m) {
          const double fraction = double(m - k) / double(gs);
          core::TimeInterpolationReport r;
          const core::GridMeanExtinction est = core::interpolate_extinction(g, ext[k], ext[k1], winds[k], winds[k1],
                                                                            double(gs) * double(dt), fraction, method, &r);
          ms += r.cost_ms;
          const std::vector<float> a = total_extinction(ext[m], g.points()), b = total_extinction(est, g.points());
          for (std::size_t p = 0; p < a.size(); ++p) se_ext += (double(a[p]) - b[p]) * (double(a[p]) - b[p]);
          nodes += a.size();
          const std::vector<float> t_est = core::column_depth(g, est.liquid_per_m, est.ice_per_m).tau;
          const std::vector<float>& t_true = tau[m];
          for (std::size_t c = 0; c < t_true.size(); ++c) {
            const double d = double(t_true[c]) - t_est[c];
            se_tau += d * d;
            const double dc = std::exp(-double(t_est[c])) - std::exp(-double(t_true[c]));
            se_cover += dc * dc;
          }
          cols += t_true.size();
          for (std::size_t s = 0; s < kFssScales.size(); ++s) {
            fraction_skill_score(t_true, t_est, g.lon_deg.count, g.lat_deg.count, kFssScales[s], &num[s], &den[s]);
          }
          ++row.cases;
        }
      }
      if (row.cases == 0) continue;
      row.rmse_extinction_per_km = std::sqrt(se_ext / double(nodes)) * 1e3;
      row.rmse_column_tau = std::sqrt(se_tau / double(cols));
      row.rmse_cover = std::sqrt(se_cover / double(cols));
      for (std::size_t s = 0; s < kFssScales.size(); ++s) row.fss[s] = den[s] > 0.0 ? 1.0 - num[s] / den[s] : 1.0;
      row.ms_per_instant = ms / row.cases;
      rows.push_back(row);
    }
  }
  return rows;
}

std::string time_error_table(const std::vector<TimeErrorRow>& rows) {
  std::string t = "| gap | method | held-back steps | RMSE extinction (1/km) | RMSE column tau | RMSE cover | FSS 1 | FSS 3 | FSS 5 | ms per instant |\n"
                  "|---|---|---|---|---|---|---|---|---|---|\n";
  char buf[320];
  for (const TimeErrorRow& r : rows) {
    std::snprintf(buf, sizeof buf, "| %g h | %s | %d | %.4g | %.4g | %.4g | %.3f | %.3f | %.3f | %.2f |\n", r.gap_h,
                  core::time_interpolation_name(r.method), r.cases, r.rmse_extinction_per_km, r.rmse_column_tau, r.rmse_cover,
                  r.fss[0], r.fss[1], r.fss[2], r.ms_per_instant);
    t += buf;
  }
  return t;
}

}  // namespace cv::bench
