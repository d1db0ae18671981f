// The viewer's frame budget: starts at the fastest candidate when switched on (a first frame at the
// most accurate settings can take seconds on a software renderer) and lets the stepper climb.
#include "viewer/frame_budget.hpp"

#include <cmath>
#include <cstdio>
#include <vector>

namespace cv::viewer {

FrameBudget::FrameBudget(const std::string& machine)
    : machine_(machine),
      source_(bench::budget_candidates("", machine, model_)),
      stepper_(source_.candidates.size(), source_.candidates.size() - 1) {}

bool FrameBudget::update(core::RenderSettings& render, double dz_m, double last_frame_ms, bool marched) {
  const bool want = render.budget_ms > 0.0;
  if (!want) {
    on_ = false;
    return false;
  }
  const bench::FrontModel model = render.march.medium.modelled ? bench::FrontModel::Modelled : bench::FrontModel::Data;
  if (model != model_) {  // the other cloud model: its own figures rank the candidates, from the start
    model_ = model;
    source_ = bench::budget_candidates("", machine_, model_);
    on_ = false;
  }
  bool apply = false;
  if (!on_) {  // just switched on: from the fastest, with nothing known
    on_ = true;
    stepper_ = bench::BudgetStepper(source_.candidates.size(), source_.candidates.size() - 1);
    // The bench's times per marched frame predict the ratios between candidates (the viewer
    // accumulates frames progressively, so a candidate's accumulate does not slow a frame).
    std::vector<double> costs;
    for (const auto& c : source_.candidates) costs.push_back(c.ms / c.knobs.accumulate);
    stepper_.set_predicted_costs(costs);
    apply = true;
  } else if (marched) {
    apply = stepper_.observe(last_frame_ms, render.budget_ms);
  }
  if (!apply) return false;
  const bench::FrontConfig& c = candidate();
  const int accumulate = render.accumulate;  // the viewer accumulates progressively, not by the knob
  core::apply_knobs(c.knobs, dz_m, render);
  render.accumulate = accumulate;
  render.quality = "custom";
  return true;
}

std::string FrameBudget::status() const {
  char b[160];
  const double last = stepper_.last_ms(stepper_.current());
  std::snprintf(b, sizeof b, "%s (%zu of %zu)", candidate().name.c_str(), stepper_.current() + 1,
                stepper_.size());
  std::string out = b;
  if (std::isfinite(last)) {
    std::snprintf(b, sizeof b, ", frames %.1f ms", last);
    out += b;
  }
  return out;
}

}  // namespace cv::viewer
