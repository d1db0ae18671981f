// The measured quality front as a file (quality_front.json, written by `cloudviewer bench`), its
// ranking across scenes, and the choice of settings under a frame-time budget, all without GL so
// that `render --budget-ms` and the viewer's frame budget share one tested rule.
#pragma once

#include <cstddef>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "io/input_file.hpp"
#include "settings/quality_knobs.hpp"

namespace cv::core {}

namespace cv::bench {
// The bench works on core's types throughout (it was core::bench before it moved up to app/).
using namespace cv::core;

// A quality front that cannot be used. One line: the file, the key, what was found and expected,
// e.g. "quality_front.json: configs[2].sun_steps: found "x", expected an integer 1..1024".
class FrontError : public core::InputError {
 public:
  using core::InputError::InputError;
};

// What one configuration measured on one scene.
struct FrontScene {
  std::string scene;
  double view_step_m = 0.0;  // the step it marched with on that scene's grid
  double wall_ms = 0.0;      // median wall time per output image (all accumulated frames)
  double rel_rmse = 0.0;     // relative RMSE of luminance against the scene's reference
  bool pareto = false;       // on that scene's front of (wall ms, rel. RMSE)
};

// A configuration: the quality knobs of MarchSettings/RenderSettings it sets, and its measurements.
struct FrontConfig {
  std::string name;
  std::string kind = "sweep";  // "sweep", "preset" or "seed" (a seed document's method)
  // The quality knobs it sets (core/settings/quality_knobs.def): the view step as a multiple of
  // the grid's vertical spacing dz (the geometric mean over the scenes it was measured on), sun
  // steps, octaves, frames, resolution scale, adaptive steps.
  QualityKnobs knobs;
  bool phase_hg = false;  // Henyey-Greenstein for liquid: a change of physics, not of quality
  std::vector<FrontScene> scenes;
  // From rank_front:
  double error = 0.0;  // geometric mean of rel_rmse over the scenes with a finite error (NaN: none)
  double ms = 0.0;     // geometric mean of wall_ms over the same scenes (NaN: none)
  bool candidate = false;  // may be chosen under a budget (see rank_front)
};

struct QualityFront {
  static constexpr int kVersion = 1;
  std::string machine;               // GL renderer, vendor and version that measured it
  int width = 0, height = 0;         // the bench's image size, pixels
  std::string command;               // the bench command line
  std::vector<FrontConfig> configs;  // after rank_front: most accurate first
};

// Computes error, ms and candidate for every configuration and sorts them by error (ties: the
// faster first, then by name). A candidate is on some scene's Pareto front, keeps the physics (not
// a seed preset: those change the phase function or the droplet size), has a finite error, and is
// not dominated across scenes by another such configuration (another one at most as slow and at
// most as wrong in the geometric means, better in one): a dominated configuration would only cost a
// calibration frame in the budget choice and never be picked over the one that dominates it.
//
// `model` ranks on one cloud model's own measurements: the modelled cloud's scenes (named
// "<scene>+modelled", `bench --cloud-model modelled|both`) or the data mode's (the others), when the
// front measured any scene of that model; else on all of them (front_measures says which). The two
// models cost differently (the modelled cloud's table lookups) and err differently, so a budget
// chooses for the model the frame draws from the figures of that model.
enum class FrontModel { All, Data, Modelled };
void rank_front(QualityFront& front, FrontModel model = FrontModel::All);
// Whether a scene of the front is the modelled cloud's ("<scene>+modelled").
bool modelled_scene(const std::string& scene);
// Whether the front measured any scene of that model (All: any scene at all).
bool front_measures(const QualityFront& front, FrontModel model);

// The candidates in order of error, most accurate first.
std::vector<FrontConfig> front_candidates(const QualityFront& front);

// The presets high > default > low as candidates, most accurate first: the refinement ladder used
// when no measured front exists (each is the previous one's steps halved, so its error is lower by
// construction). error and ms are NaN (not measured).
std::vector<FrontConfig> preset_ladder();

std::string front_to_json(const QualityFront& front);
// Parses and validates; `source` names the file in messages. Throws FrontError.
QualityFront front_from_json(const std::string& text, const std::string& source);
QualityFront load_front(const std::string& path);
// Written atomically; creates the folder. Throws std::runtime_error naming the path.
void save_front(const QualityFront& front, const std::string& path);

// Throws FrontError ("<source>: machine: found "...", expected "..." (this machine): run cloudviewer
// bench here") when the front was measured on another machine: times do not carry over.
void check_machine(const QualityFront& front, const std::string& machine, const std::string& source);

// $XDG_CACHE_HOME/cloudviewer/quality_front.json, else $HOME/.cache/cloudviewer/quality_front.json;
// empty when neither variable is set.
std::string front_cache_path();

// Where the candidates come from: front_file when given (FrontError when it is bad or from another
// machine); else the per-user cache when it exists (when bad or from another machine, `warning`
// says why in one line and the preset ladder is used); else the preset ladder. `source` says which,
// for the one line the commands print.
struct CandidateSource {
  std::vector<FrontConfig> candidates;  // most accurate first
  std::string source, warning;
};
// `model`: the cloud model the frames draw (rank_front); a front that never measured it ranks on all
// its scenes, and `source` says so.
CandidateSource budget_candidates(const std::string& front_file, const std::string& machine,
                                  FrontModel model = FrontModel::All);

// The budget choice. Candidates are ordered most accurate first; measure_ms(i) renders candidate i
// and returns its time; the most accurate whose time fits (ms <= budget_ms) is chosen.
// With a measured front (FrontConfig::ms set): candidates are measured from the most accurate down
// until one fits. Once one has been measured, the front's times scaled by measured / predicted
// predict the rest, and a candidate predicted above twice the budget is skipped without rendering,
// except the one predicted fastest, which is always measured when nothing fitted.
// Without predictions (the preset ladder, whose cost rises with accuracy by construction): from the
// fastest up, stopping at the first that does not fit.
// When none fits, the fastest measured is chosen and `met` is false.
struct BudgetTrial {
  std::size_t index = 0;
  double ms = 0.0;
};
struct BudgetChoice {
  std::size_t index = 0;
  double ms = 0.0;
  bool met = false;
  std::vector<BudgetTrial> trials;  // in the order measured
};
// Throws std::invalid_argument when there are no candidates or the budget is not > 0.
BudgetChoice choose_under_budget(const std::vector<FrontConfig>& by_accuracy, double budget_ms,
                                 const std::function<double(std::size_t)>& measure_ms);

// "view step 1.00 dz (>= 50 m), 16 sun steps, 4 octaves, 1 frame(s), scale 1, adaptive off"
std::string describe_config(const FrontConfig& c);

}  // namespace cv::bench
