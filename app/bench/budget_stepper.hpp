// The viewer's frame budget as a pure state machine: from the measured times of its own frames it
// steps along a candidate list (most accurate first) so that frames stay within the budget, with
// hysteresis so that it does not flicker between two settings.
#pragma once

#include <cstddef>
#include <vector>

namespace cv::core {}

namespace cv::bench {
// The bench works on core's types throughout (it was core::bench before it moved up to app/).
using namespace cv::core;

class BudgetStepper {
 public:
  // Frames observed after a change before the next decision (the first frames after a change pay
  // for shader variants and restarted accumulation, and are not typical).
  static constexpr int kSettleFrames = 4;
  // Step up only when the more accurate candidate's last time is at most this fraction of the
  // budget: a candidate just over the line would otherwise be left and taken again every few frames.
  static constexpr double kUpMargin = 0.8;
  // With no time known or predicted for the more accurate candidate, try it only with this much
  // headroom.
  static constexpr double kProbeMargin = 0.5;
  // A candidate's last time is forgotten after this many frames (the view changes what frames cost).
  static constexpr int kForgetFrames = 300;

  // n candidates, most accurate first; starts at `start` (clamped).
  explicit BudgetStepper(std::size_t n, std::size_t start = 0);

  // One frame of the current candidate took frame_ms. Returns true when the current candidate
  // changed. The decision uses the median of the frames since the last change (so one slow frame,
  // e.g. a window resize, does not move it): over budget_ms, one step to the faster candidate;
  // under it, one step to the more accurate one when its last time fits with margin (or, unknown,
  // when the current time leaves kProbeMargin headroom). budget_ms <= 0 is off: nothing changes.
  bool observe(double frame_ms, double budget_ms);

  std::size_t current() const { return current_; }
  std::size_t size() const { return last_ms_.size(); }
  // The last settled time of candidate i in ms, or NaN when unknown (never measured, or forgotten).
  double last_ms(std::size_t i) const;
  // Forgets what was measured (on a change of scene or window: old times no longer apply).
  void reset_times();
  // Relative frame costs of the candidates (the bench's times; NaN where unknown). With both known,
  // a more accurate candidate not yet measured is predicted as the current frame time scaled by
  // their ratio, and taken when that fits with kUpMargin, instead of probing at kProbeMargin.
  void set_predicted_costs(std::vector<double> costs);

 private:
  std::size_t current_;
  std::vector<double> last_ms_;
  std::vector<long long> last_frame_;  // frame counter when last_ms_ was measured
  std::vector<double> since_change_;   // frame times since the last change
  std::vector<double> costs_;          // relative frame costs, or empty
  long long frame_ = 0;
};

}  // namespace cv::bench
