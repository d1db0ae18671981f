// The frame-budget state machine: median of the frames since the last change, one step at a time,
// asymmetric thresholds (over the budget: down; well under it: up).
#include "bench/budget_stepper.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace cv::bench {

BudgetStepper::BudgetStepper(std::size_t n, std::size_t start)
    : current_(n == 0 ? 0 : std::min(start, n - 1)),
      last_ms_(n, std::numeric_limits<double>::quiet_NaN()),
      last_frame_(n, 0) {}

double BudgetStepper::last_ms(std::size_t i) const {
  if (i >= last_ms_.size()) return std::numeric_limits<double>::quiet_NaN();
  if (frame_ - last_frame_[i] > kForgetFrames) return std::numeric_limits<double>::quiet_NaN();
  return last_ms_[i];
}

void BudgetStepper::reset_times() {
  std::fill(last_ms_.begin(), last_ms_.end(), std::numeric_limits<double>::quiet_NaN());
  since_change_.clear();
}

void BudgetStepper::set_predicted_costs(std::vector<double> costs) {
  costs_ = std::move(costs);
  costs_.resize(last_ms_.size(), std::numeric_limits<double>::quiet_NaN());
}

bool BudgetStepper::observe(double frame_ms, double budget_ms) {
  ++frame_;
  if (last_ms_.empty() || !(budget_ms > 0.0) || !std::isfinite(frame_ms) || frame_ms < 0.0) return false;
  since_change_.push_back(frame_ms);
  if (static_cast<int>(since_change_.size()) < kSettleFrames) return false;
  // The median of the settled frames: robust to one slow frame.
  std::vector<double> sorted = since_change_;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2),
                   sorted.end());
  const double typical = sorted[sorted.size() / 2];
  last_ms_[current_] = typical;
  last_frame_[current_] = frame_;
  if (since_change_.size() > 4 * static_cast<std::size_t>(kSettleFrames)) {  // keep a recent window
    since_change_.erase(since_change_.begin());
  }
  std::size_t next = current_;
  if (typical > budget_ms) {
    if (current_ + 1 < last_ms_.size()) next = current_ + 1;
  } else if (current_ > 0) {
    const double up = last_ms(current_ - 1);
    const bool predicted = !costs_.empty() && std::isfinite(costs_[current_ - 1]) &&
                           std::isfinite(costs_[current_]) && costs_[current_] > 0.0;
    bool fits = false;
    if (std::isfinite(up))
      fits = up <= kUpMargin * budget_ms;
    else if (predicted)
      fits = typical * costs_[current_ - 1] / costs_[current_] <= kUpMargin * budget_ms;
    else
      fits = typical <= kProbeMargin * budget_ms;
    if (fits) next = current_ - 1;
  }
  if (next == current_) return false;
  current_ = next;
  since_change_.clear();
  return true;
}

}  // namespace cv::bench
