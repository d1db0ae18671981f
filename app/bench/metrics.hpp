// The benchmark's pure computations: error of an image against a reference (relative RMSE, bias,
// worst pixel, PSNR on luminance), the Pareto front of (time, error) points and the interpolation
// along it that turns two configurations into the ratios the benchmark reports.
#pragma once

#include <cstddef>
#include <vector>

#include <glm/vec3.hpp>

namespace cv::core {}

namespace cv::bench {
// The bench works on core's types throughout (it was core::bench before it moved up to app/).
using namespace cv::core;

// Rec. 709 luminance of linear rgb radiance.
double luminance(const glm::dvec3& rgb);

// Error of a test image against a reference of the same size, on luminance. All relative figures
// are NaN when the reference is black everywhere (nothing to be relative to).
struct ImageError {
  // sqrt(mean (L - L_ref)^2) / mean L_ref; with the reference's variance given, the noise-corrected
  // sqrt(max(0, mean ((L - L_ref)^2 - var L_ref))) / mean L_ref (see image_error).
  double rel_rmse = 0.0;
  double rel_rmse_raw = 0.0;     // sqrt(mean (L - L_ref)^2) / mean L_ref, noise of the reference included
  double rel_noise_floor = 0.0;  // sqrt(mean var L_ref) / mean L_ref: the reference's own noise (0 if not given)
  // The smallest rel_rmse the corrected estimate tells from zero: sqrt(2 standard errors of the
  // corrected mean square) / mean L_ref, from the spread over pixels (0 when no variance is given).
  // A rel_rmse below it means "not resolved by this reference", not "this small".
  double rel_rmse_resolution = 0.0;
  double rel_bias = 0.0;   // mean (L - L_ref) / mean L_ref (signed: > 0 the test is too bright)
  double worst = 0.0;      // max |L - L_ref| / max L_ref
  double psnr_db = 0.0;    // 20 log10(max L_ref / rmse); +inf for identical images
  double rmse = 0.0;       // absolute, in the images' radiance units
  double ref_mean = 0.0, ref_max = 0.0;
};
// Throws std::invalid_argument when the sizes differ or are 0.
// `ref_lum_variance`, when not empty, is the variance of each reference pixel's luminance (the
// squared standard error of a Monte Carlo mean). A noisy reference adds its variance to every
// squared difference: E[(L - L_ref)^2] = (L - L_true)^2 + var L_ref for an unbiased L_ref. Taking the
// variance out gives an unbiased estimate of the test image's squared error against the true image,
// so configurations can be ranked with a reference that has not fully converged, as long as their
// error stands above rel_noise_floor. Bias and worst pixel are not corrected (the bias needs no
// correction: the noise averages out of the mean).
ImageError image_error(const std::vector<glm::dvec3>& test, const std::vector<glm::dvec3>& ref,
                       const std::vector<double>& ref_lum_variance = {});

// Per-pixel |L - L_ref| / max L_ref (0 where the reference is black everywhere), for error images.
std::vector<double> pixel_error(const std::vector<glm::dvec3>& test, const std::vector<glm::dvec3>& ref);


struct TimeError {
  double time = 0.0, error = 0.0;
};

// Indices of the points on the Pareto front (no other point is at least as fast and at least as
// accurate while strictly better in one), sorted by time ascending (hence error descending).
// Points with a non-finite or non-positive coordinate are never on it.
std::vector<std::size_t> pareto_front(const std::vector<TimeError>& pts);

// Along a front (sorted by time, error falling), interpolated linearly in log(time)-log(error)
// between neighbouring points; never extrapolated.
// The time the front needs to reach `error`: its fastest point's time when even that point is at
// least as accurate (an upper bound then), NaN when no point on it is that accurate.
double front_time_for_error(const std::vector<TimeError>& front, double error);
// The front's error at `time` (NaN when time is below its fastest point; the last point's error
// when time is beyond its slowest: waiting longer does not make that front worse).
double front_error_at_time(const std::vector<TimeError>& front, double time);

}  // namespace cv::bench
