// How well each interpolation between forecast steps reproduces a held-back step of real model
// output: steps k and k + g stand in for a coarser file, every step between them is the truth.
// Plain C++ on cv_core (no GL): the `time-error` command and its test run it.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "volume/cloud_volume.hpp"
#include "volume/time_interpolation.hpp"

namespace cv::bench {

// Scales of the fraction skill score, in grid cells (the side of the square neighbourhood).
inline constexpr std::array<int, 3> kFssScales = {1, 3, 5};

// Errors of one interpolation method at one gap, pooled over every held-back step.
struct TimeErrorRow {
  double gap_h = 0.0;
  core::TimeInterpolation method = core::TimeInterpolation::Linear;
  int cases = 0;                  // held-back steps compared
  double rmse_extinction_per_km = 0.0;  // grid-mean extinction (liquid + ice), every node
  double rmse_column_tau = 0.0;         // column optical depth, every column
  double rmse_cover = 0.0;              // per-column opaque cover 1 - exp(-tau)
  std::array<double, kFssScales.size()> fss{};  // at the truth's upper-quartile column tau (own quartile for the estimate)
  double ms_per_instant = 0.0;          // mean wall time of one interpolation
};

struct TimeErrorOptions {
  std::vector<double> gaps_h = {2.0, 3.0, 6.0};
  std::vector<core::TimeInterpolation> methods = {core::TimeInterpolation::Nearest, core::TimeInterpolation::Linear,
                                                  core::TimeInterpolation::Advected};
};

// The volume's steps must be evenly spaced in time (std::invalid_argument naming `source`
// otherwise); a gap that is not a whole number of steps of at least 2, or longer than the file, is
// left out. Every step of the file is loaded once.
std::vector<TimeErrorRow> measure_time_error(core::CloudVolume& volume, const std::string& source, const TimeErrorOptions& options);

// The rows as a Markdown table.
std::string time_error_table(const std::vector<TimeErrorRow>& rows);

// Fraction skill score of two fields on an nx x ny grid at a square neighbourhood of side `scale`
// cells (Roberts and Lean 2008), each thresholded at its own upper quartile; also accumulates the
// score's numerator and denominator into num/den so cases can be pooled.
double fraction_skill_score(const std::vector<float>& truth, const std::vector<float>& estimate, int nx, int ny, int scale,
                            double* num = nullptr, double* den = nullptr);

}  // namespace cv::bench
