// The benchmark's pure computations: error metrics of known images, the Pareto front of a known
// point set, the log-log interpolation along it, and the plot's rasterizer.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "bench/metrics.hpp"
#include "bench/plot.hpp"

namespace {
using namespace cv::bench;

TEST(BenchMetrics, ErrorOfAKnownImagePair) {
  // Grey pixels (luminance = the value): reference 1, 1, 2, 4 (mean 2, max 4); test off by +1, -1, 0, +2.
  const std::vector<glm::dvec3> ref = {glm::dvec3(1), glm::dvec3(1), glm::dvec3(2), glm::dvec3(4)};
  const std::vector<glm::dvec3> test = {glm::dvec3(2), glm::dvec3(0), glm::dvec3(2), glm::dvec3(6)};
  const ImageError e = image_error(test, ref);
  const double rmse = std::sqrt((1.0 + 1.0 + 0.0 + 4.0) / 4.0);
  EXPECT_NEAR(e.rmse, rmse, 1e-12);
  EXPECT_NEAR(e.rel_rmse, rmse / 2.0, 1e-12);
  EXPECT_NEAR(e.rel_bias, (1.0 - 1.0 + 0.0 + 2.0) / 4.0 / 2.0, 1e-12);
  EXPECT_NEAR(e.worst, 2.0 / 4.0, 1e-12);
  EXPECT_NEAR(e.psnr_db, 20.0 * std::log10(4.0 / rmse), 1e-9);
  const auto pe = pixel_error(test, ref);
  EXPECT_NEAR(pe[3], 0.5, 1e-12);
  EXPECT_NEAR(pe[2], 0.0, 1e-12);
}

TEST(BenchMetrics, IdenticalImagesHaveNoErrorAndInfinitePsnr) {
  const std::vector<glm::dvec3> ref = {glm::dvec3(0.2, 0.5, 0.1), glm::dvec3(1.0, 0.0, 3.0)};
  const ImageError e = image_error(ref, ref);
  EXPECT_EQ(e.rel_rmse, 0.0);
  EXPECT_EQ(e.worst, 0.0);
  EXPECT_TRUE(std::isinf(e.psnr_db));
}

TEST(BenchMetrics, ABlackReferenceGivesNoRelativeErrorAndMismatchedSizesThrow) {
  const std::vector<glm::dvec3> black(4, glm::dvec3(0.0)), lit(4, glm::dvec3(1.0));
  const ImageError e = image_error(lit, black);
  EXPECT_TRUE(std::isnan(e.rel_rmse));
  EXPECT_NEAR(e.rmse, 1.0, 1e-12);
  EXPECT_THROW(image_error(lit, std::vector<glm::dvec3>(3)), std::invalid_argument);
}

TEST(BenchMetrics, TheReferencesNoiseIsTakenOutOfTheError) {
  // Truth: a ramp; the test image is 5 % off everywhere (relative RMSE 0.05 against the truth); the
  // reference is the truth plus Gaussian noise of a stated variance, 4x the test's error in RMS. The
  // raw figure measures mostly the noise; the corrected one recovers the 5 %.
  const int n = 40000;
  std::mt19937_64 rng(7);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::vector<glm::dvec3> truth(n), test(n), ref(n);
  std::vector<double> var(n);
  double mean_truth = 0.0, mean_var = 0.0;
  for (int i = 0; i < n; ++i) {
    const double t = 1.0 + static_cast<double>(i % 100) / 50.0;  // 1..3, mean ~2
    truth[i] = glm::dvec3(t);
    test[i] = glm::dvec3(t * 1.05);
    const double sd = 0.2 * t;  // 4x the 5 % offset
    var[i] = sd * sd;
    ref[i] = glm::dvec3(t + sd * gauss(rng));
    mean_truth += t / n;
    mean_var += var[i] / n;
  }
  const ImageError against_truth = image_error(test, truth);
  const ImageError raw = image_error(test, ref);
  const ImageError corrected = image_error(test, ref, var);
  EXPECT_NEAR(raw.rel_rmse, raw.rel_rmse_raw, 1e-15);        // no variance given: no correction
  EXPECT_GT(raw.rel_rmse, 3.0 * against_truth.rel_rmse);     // the noise dominates the raw figure
  EXPECT_NEAR(corrected.rel_rmse_raw, raw.rel_rmse, 1e-15);  // the raw figure is still reported
  // Corrected within 10 % of the truth's figure (the estimate's spread at 40 000 pixels is ~3 %).
  EXPECT_NEAR(corrected.rel_rmse, against_truth.rel_rmse, 0.1 * against_truth.rel_rmse);
  const double floor = std::sqrt(mean_var) / mean_truth;
  EXPECT_NEAR(corrected.rel_noise_floor, floor, 0.01 * floor);  // over the noisy reference's mean
  // 40 000 pixels resolve errors well below the floor: for Gaussian noise the corrected mean square's
  // standard error is sqrt(2) var / sqrt(n), so the resolution is ~0.026 here, about half the 5 %.
  EXPECT_GT(corrected.rel_rmse_resolution, 0.0);
  EXPECT_LT(corrected.rel_rmse_resolution, corrected.rel_rmse);
  EXPECT_LT(corrected.rel_rmse_resolution, corrected.rel_noise_floor);
  // An exact copy of the truth: its corrected error is within the resolution of zero.
  const ImageError exact = image_error(truth, ref, var);
  EXPECT_LT(exact.rel_rmse, exact.rel_rmse_resolution);
  EXPECT_THROW(image_error(test, ref, std::vector<double>(3, 0.0)), std::invalid_argument);
}

TEST(BenchMetrics, LuminanceUsesRec709Weights) {
  EXPECT_NEAR(luminance({1.0, 0.0, 0.0}), 0.2126, 1e-12);
  EXPECT_NEAR(luminance({0.0, 1.0, 0.0}), 0.7152, 1e-12);
  EXPECT_NEAR(luminance({1.0, 1.0, 1.0}), 1.0, 1e-12);
}

TEST(BenchMetrics, ParetoFrontOfAKnownPointSet) {
  const std::vector<TimeError> pts = {
      {10, 0.5},  // 0: on (fastest)
      {20, 0.6},  // 1: dominated by 0
      {20, 0.2},  // 2: on
      {40, 0.2},  // 3: dominated by 2 (same error, slower)
      {80, 0.05}, // 4: on
      {50, 0.1},  // 5: on
      {5, NAN},   // 6: not finite: never on
      {60, 0.3},  // 7: dominated
  };
  const std::vector<std::size_t> want = {0, 2, 5, 4};
  EXPECT_EQ(pareto_front(pts), want);
}

TEST(BenchMetrics, InterpolationAlongTheFrontIsLogLogAndNeverExtrapolates) {
  const std::vector<TimeError> front = {{1, 1}, {100, 0.01}};  // error = 1 / time on this segment
  EXPECT_NEAR(front_time_for_error(front, 0.1), 10.0, 1e-9);
  EXPECT_NEAR(front_error_at_time(front, 10.0), 0.1, 1e-12);
  EXPECT_EQ(front_time_for_error(front, 2.0), 1.0);    // the fastest point is already that accurate
  EXPECT_TRUE(std::isnan(front_time_for_error(front, 0.001)));  // never reached
  EXPECT_TRUE(std::isnan(front_error_at_time(front, 0.5)));     // faster than any point
  EXPECT_EQ(front_error_at_time(front, 1000.0), 0.01);
}

TEST(BenchPlot, DrawsAxesPointsAndTheFront) {
  const std::vector<PlotPoint> pts = {{{1.0, 0.5}, 0}, {{10.0, 0.05}, 2}, {{5.0, 1.0}, 1}};
  const Rgb8Image img = plot_error_vs_time(pts, {0, 1}, 200, 150);
  ASSERT_EQ(img.rgb.size(), 200u * 150u * 3u);
  int red = 0, orange = 0, black = 0;
  for (std::size_t i = 0; i < img.rgb.size(); i += 3) {
    const int r = img.rgb[i], g = img.rgb[i + 1], b = img.rgb[i + 2];
    red += r == 220 && g == 30 && b == 30;
    orange += r == 230 && g == 140 && b == 0;
    black += r == 0 && g == 0 && b == 0;
  }
  EXPECT_GT(red, 20);     // the front's line and rings
  EXPECT_GT(orange, 5);   // the seed point
  EXPECT_GT(black, 100);  // axes, ticks, labels
}

}  // namespace
