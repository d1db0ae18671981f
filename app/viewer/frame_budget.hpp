// The viewer's frame budget: the candidate list (the cached measured front or the preset ladder),
// the stepper that walks it from the viewer's own frame times, and what the quality panel shows.
// No GL here: the main loop hands in frame times and applies the settings returned.
#pragma once

#include <cstddef>
#include <string>

#include "bench/budget_stepper.hpp"
#include "bench/quality_front.hpp"
#include "scene/scene.hpp"

namespace cv::viewer {

class FrameBudget {
 public:
  // Candidates from the per-user cache when it was measured on `machine`, else the preset ladder.
  explicit FrameBudget(const std::string& machine);

  // Called once per frame with the scene's render settings and the wall time of the previous frame
  // (marched: whether that frame marched; frames that only redraw the finished mean cost nothing
  // and say nothing about the settings). When the budget is on (render.budget_ms > 0) and the
  // stepper moves, or the budget has just been switched on, the candidate's view step, sun steps,
  // octaves, adaptive stepping and resolution scale are written into `render` (the accumulation
  // target stays the viewer's: it refines a still image, it does not slow a frame). dz_m: the
  // grid's vertical spacing. Returns true when `render` was changed.
  // The candidates are ranked on the measurements of the cloud model `render` draws
  // (bench::FrontModel); when the model changes, they are ranked again and the stepper starts over.
  bool update(core::RenderSettings& render, double dz_m, double last_frame_ms, bool marched);

  bool on() const { return on_; }
  std::size_t current() const { return stepper_.current(); }
  const bench::FrontConfig& candidate() const { return source_.candidates[stepper_.current()]; }
  // "default (2 of 3), last 41.3 ms" and where the candidates came from, for the panel.
  std::string status() const;
  const std::string& source() const { return source_.source; }
  const std::string& warning() const { return source_.warning; }

 private:
  std::string machine_;
  bench::FrontModel model_ = bench::FrontModel::Data;
  bench::CandidateSource source_;
  bench::BudgetStepper stepper_;
  bool on_ = false;
};

}  // namespace cv::viewer
