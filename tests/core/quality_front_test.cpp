// The quality front file (round trip, strict reading), its ranking across scenes, the choice under a
// budget from given times, and the viewer's frame-budget state machine: all without GL or timing.
#include <type_traits>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>

#include <unistd.h>

#include "bench/budget_stepper.hpp"
#include "bench/quality_front.hpp"
#include "scene/quality.hpp"

namespace cv::bench {
namespace {

FrontConfig config(const std::string& name, const std::string& kind, std::vector<FrontScene> scenes) {
  FrontConfig c;
  c.name = name, c.kind = kind, c.scenes = std::move(scenes);
  return c;
}

// Two scenes, five configurations: "fine" and "coarse" on both fronts, "mid" on one, "slow_bad"
// on neither (dominated), "seed" on a front but a seed preset.
QualityFront sample_front() {
  QualityFront f;
  f.machine = "llvmpipe (LLVM 15.0.6, 256 bits) by Mesa (4.5 (Core Profile) Mesa 22.3.6)";
  f.width = 96, f.height = 54, f.command = "cloudviewer bench --size 96x54";
  f.configs.push_back(config("coarse", "sweep", {{"a", 1000, 10, 0.08, true}, {"b", 400, 12, 0.02, true}}));
  f.configs.push_back(config("fine", "preset", {{"a", 250, 40, 0.01, true}, {"b", 100, 48, 0.005, true}}));
  f.configs.push_back(config("mid", "sweep", {{"a", 500, 20, 0.04, true}, {"b", 200, 25, 0.01, false}}));
  f.configs.push_back(
      config("slow_bad", "sweep", {{"a", 500, 60, 0.09, false}, {"b", 200, 70, 0.03, false}}));
  f.configs.push_back(config("seed", "seed", {{"a", 100, 30, 0.005, true}, {"b", 50, 30, 0.004, true}}));
  f.configs[1].knobs.view_step_dz = 0.5, f.configs[1].knobs.view_step_min_m = 25.0, f.configs[1].knobs.sun_steps = 32;
  f.configs[1].knobs.octaves = 8, f.configs[1].knobs.accumulate = 4;
  f.configs[0].knobs.resolution_scale = 0.5, f.configs[0].knobs.adaptive = true;
  f.configs[4].phase_hg = true;
  return f;
}

TEST(QualityFront, RankingByGeometricMeanErrorAndCandidates) {
  QualityFront f = sample_front();
  rank_front(f);
  ASSERT_EQ(f.configs.size(), 5u);
  // Sorted by the geometric mean error: seed (sqrt(0.005*0.004)), fine, mid, coarse, slow_bad.
  EXPECT_EQ(f.configs[0].name, "seed");
  EXPECT_EQ(f.configs[1].name, "fine");
  EXPECT_EQ(f.configs[2].name, "mid");
  EXPECT_EQ(f.configs[3].name, "coarse");
  EXPECT_EQ(f.configs[4].name, "slow_bad");
  EXPECT_NEAR(f.configs[1].error, std::sqrt(0.01 * 0.005), 1e-15);
  EXPECT_NEAR(f.configs[1].ms, std::sqrt(40.0 * 48.0), 1e-12);
  const auto c = front_candidates(f);
  ASSERT_EQ(c.size(), 3u);  // the seed changes the physics, slow_bad is on no front
  EXPECT_EQ(c[0].name, "fine");
  EXPECT_EQ(c[1].name, "mid");
  EXPECT_EQ(c[2].name, "coarse");
}

TEST(QualityFront, DominatedAcrossScenesIsNoCandidate) {
  QualityFront f;
  // "b" is on scene y's front but slower and worse than "a" in the geometric means.
  f.configs.push_back(config("a", "sweep", {{"x", 1, 10, 0.01, true}, {"y", 1, 10, 0.01, true}}));
  f.configs.push_back(config("b", "sweep", {{"x", 1, 30, 0.03, false}, {"y", 1, 12, 0.012, true}}));
  rank_front(f);
  const auto c = front_candidates(f);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].name, "a");
}

// A front measured on both cloud models ranks for one model on that model's scenes: "careful" is
// more accurate on the data but slower and worse on the modelled cloud, so a budget for the modelled
// cloud never chooses it; a front with no modelled scene ranks on all of its scenes for either.
TEST(QualityFront, EachCloudModelIsRankedOnItsOwnScenes) {
  QualityFront f;
  f.configs.push_back(config("fast", "sweep", {{"a", 1, 10, 0.02, true}, {"b", 1, 10, 0.02, true},
                                               {"a+modelled", 1, 20, 0.05, true}, {"b+modelled", 1, 20, 0.05, true}}));
  f.configs.push_back(config("careful", "sweep", {{"a", 1, 40, 0.01, true}, {"b", 1, 40, 0.01, true},
                                                  {"a+modelled", 1, 80, 0.06, false}, {"b+modelled", 1, 80, 0.06, false}}));
  EXPECT_TRUE(modelled_scene("a+modelled"));
  EXPECT_FALSE(modelled_scene("a"));
  EXPECT_FALSE(modelled_scene("+modelled"));
  QualityFront data = f, modelled = f, all = f;
  rank_front(data, FrontModel::Data);
  rank_front(modelled, FrontModel::Modelled);
  rank_front(all);
  auto names = [](const QualityFront& q) {
    std::string out;
    for (const FrontConfig& c : front_candidates(q)) out += c.name + " ";
    return out;
  };
  EXPECT_EQ(names(data), "careful fast ");
  EXPECT_EQ(names(modelled), "fast ");
  EXPECT_DOUBLE_EQ(modelled.configs[0].ms, 20.0);
  EXPECT_DOUBLE_EQ(modelled.configs[0].error, 0.05);
  EXPECT_DOUBLE_EQ(data.configs[1].ms, 10.0);  // "fast", second by error
  EXPECT_NEAR(all.configs[1].ms, std::sqrt(10.0 * 20.0), 1e-12);
  // Without modelled scenes, the modelled ranking is the whole front's.
  QualityFront plain = sample_front(), plain_modelled = sample_front();
  EXPECT_FALSE(front_measures(plain, FrontModel::Modelled));
  EXPECT_TRUE(front_measures(plain, FrontModel::Data));
  rank_front(plain);
  rank_front(plain_modelled, FrontModel::Modelled);
  EXPECT_EQ(names(plain), names(plain_modelled));
}

TEST(QualityFront, UnmeasurableErrorsAreLeftOutOfTheMeans) {
  QualityFront f;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  f.configs.push_back(config("a", "sweep", {{"clear_sky", 1, 5, nan, true}, {"y", 1, 10, 0.02, true}}));
  rank_front(f);
  EXPECT_DOUBLE_EQ(f.configs[0].error, 0.02);
  EXPECT_DOUBLE_EQ(f.configs[0].ms, 10.0);
  EXPECT_TRUE(f.configs[0].candidate);
}

TEST(QualityFront, JsonRoundTrip) {
  QualityFront f = sample_front();
  f.configs[0].scenes[0].rel_rmse = std::numeric_limits<double>::quiet_NaN();  // written as null
  rank_front(f);
  const QualityFront g = front_from_json(front_to_json(f), "t.json");
  EXPECT_EQ(g.machine, f.machine);
  EXPECT_EQ(g.width, 96);
  EXPECT_EQ(g.height, 54);
  EXPECT_EQ(g.command, f.command);
  ASSERT_EQ(g.configs.size(), f.configs.size());
  for (std::size_t i = 0; i < f.configs.size(); ++i) {
    const FrontConfig &a = f.configs[i], &b = g.configs[i];
    EXPECT_EQ(a.name, b.name);
    EXPECT_EQ(a.kind, b.kind);
    EXPECT_EQ(a.knobs, b.knobs) << describe_knobs(a.knobs) << " against " << describe_knobs(b.knobs);
    EXPECT_EQ(a.phase_hg, b.phase_hg);
    EXPECT_EQ(a.candidate, b.candidate);
    EXPECT_EQ(a.error, b.error);
    ASSERT_EQ(a.scenes.size(), b.scenes.size());
    for (std::size_t k = 0; k < a.scenes.size(); ++k) {
      EXPECT_EQ(a.scenes[k].scene, b.scenes[k].scene);
      EXPECT_EQ(a.scenes[k].view_step_m, b.scenes[k].view_step_m);
      EXPECT_EQ(a.scenes[k].wall_ms, b.scenes[k].wall_ms);
      EXPECT_EQ(std::isnan(a.scenes[k].rel_rmse), std::isnan(b.scenes[k].rel_rmse));
      if (!std::isnan(a.scenes[k].rel_rmse)) {
        EXPECT_EQ(a.scenes[k].rel_rmse, b.scenes[k].rel_rmse);
      }
      EXPECT_EQ(a.scenes[k].pareto, b.scenes[k].pareto);
    }
  }
}

// The message of the FrontError for `text`, or "" when it parses.
std::string error_of(const std::string& text) {
  try {
    front_from_json(text, "front.json");
  } catch (const FrontError& e) {
    return e.what();
  }
  return "";
}

TEST(QualityFront, BadFilesNameFileAndKeyOnOneLine) {
  const std::string good = front_to_json(sample_front());
  auto with = [&](const std::string& from, const std::string& to) {
    const auto at = good.find(from);
    if (at == std::string::npos) {
      ADD_FAILURE() << "not in the file: " << from;
      return good;
    }
    return good.substr(0, at) + to + good.substr(at + from.size());
  };
  struct Case {
    std::string text, expect;
  } cases[] = {
      {"{ not json", "front.json: not valid JSON"},
      {"[1, 2]", "front.json: found [1,2] at the top, expected a JSON object"},
      {with("\"cloudviewer-quality-front\"", "\"something-else\""),
       "front.json: format: found \"something-else\""},
      {with("\"version\": 1", "\"version\": 7"), "front.json: version: found 7, expected an integer 1..1"},
      {with("\"machine\"", "\"machina\""),
       "front.json: machine: found nothing, expected the renderer string"},
      {with("\"sun_steps\": 16", "\"sun_steps\": \"x\""),
       "front.json: configs[0].sun_steps: found \"x\", expected an integer 1..1024"},
      {with("\"kind\": \"sweep\"", "\"kind\": \"fast\""),
       "front.json: configs[0].kind: found \"fast\", expected \"sweep\", \"preset\" or \"seed\""},
      {with("\"wall_ms\": 10.0", "\"wall_ms\": -3"),
       "front.json: configs[0].scenes[0].wall_ms: found -3, expected a time in ms"},
      {with("\"resolution_scale\": 0.5", "\"resolution_scale\": 2"),
       "front.json: configs[0].resolution_scale: found 2, expected"},
  };
  for (const auto& c : cases) {
    const std::string e = error_of(c.text);
    EXPECT_EQ(e.rfind(c.expect, 0), 0u) << "got: " << e << "\nwanted it to start with: " << c.expect;
    EXPECT_EQ(e.find('\n'), std::string::npos) << e;
  }
  EXPECT_EQ(error_of(good), "");
}

TEST(QualityFront, OtherMachineIsRejectedByName) {
  const QualityFront f = sample_front();
  EXPECT_NO_THROW(check_machine(f, f.machine, "front.json"));
  try {
    check_machine(f, "NVIDIA H100 by NVIDIA Corporation (4.5.0 NVIDIA 550)", "front.json");
    FAIL() << "a front from another machine was accepted";
  } catch (const FrontError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("front.json: machine: found \"llvmpipe", 0), 0u) << e.what();
  }
}

TEST(QualityFront, CandidatesFromFileCacheOrLadder) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("cv_front_test_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  ::setenv("XDG_CACHE_HOME", dir.c_str(), 1);
  EXPECT_EQ(front_cache_path(), (dir / "cloudviewer" / "quality_front.json").string());
  const QualityFront f = sample_front();
  // No cache: the ladder, most accurate first.
  CandidateSource s = budget_candidates("", f.machine);
  ASSERT_EQ(s.candidates.size(), 3u);
  EXPECT_EQ(s.candidates[0].name, "high");
  EXPECT_EQ(s.candidates[2].name, "low");
  EXPECT_NE(s.source.find("preset ladder"), std::string::npos);
  // A cache from this machine is used; one from another machine gives one line and the ladder.
  save_front(f, front_cache_path());
  s = budget_candidates("", f.machine);
  ASSERT_EQ(s.candidates.size(), 3u);
  EXPECT_EQ(s.candidates[0].name, "fine");
  EXPECT_TRUE(s.warning.empty());
  s = budget_candidates("", f.machine, FrontModel::Modelled);  // it measured no modelled scene
  ASSERT_EQ(s.candidates.size(), 3u);
  EXPECT_NE(s.source.find("ranked on all its scenes: it measured no modelled scene"), std::string::npos) << s.source;
  s = budget_candidates("", f.machine, FrontModel::Data);
  EXPECT_NE(s.source.find("ranked on its data scenes"), std::string::npos) << s.source;
  s = budget_candidates("", "another GPU");
  EXPECT_EQ(s.candidates[0].name, "high");
  EXPECT_EQ(s.warning.rfind(front_cache_path() + ": machine: found", 0), 0u) << s.warning;
  // A named file from another machine, or missing, is an error.
  EXPECT_THROW(budget_candidates(front_cache_path(), "another GPU"), FrontError);
  EXPECT_THROW(budget_candidates((dir / "missing.json").string(), f.machine), FrontError);
  ::unsetenv("XDG_CACHE_HOME");
  fs::remove_all(dir);
}

TEST(QualityFront, ViewStepFromTheGrid) {
  QualityKnobs k;
  k.view_step_dz = 0.5, k.view_step_min_m = 25.0;
  EXPECT_DOUBLE_EQ(k.view_step_m(500.0), 250.0);
  EXPECT_DOUBLE_EQ(k.view_step_m(-500.0), 250.0);  // descending altitude axes have a negative step
  EXPECT_DOUBLE_EQ(k.view_step_m(20.0), 25.0);
}

// Every knob of the table is written and read back: a configuration whose every knob differs from
// the default round-trips exactly (a knob the writer dropped would come back as its default).
TEST(QualityFront, EveryKnobRoundTrips) {
  QualityKnobs k;
  for_each_quality_knob(k, [](const KnobRow& row, auto& v) {
    using T = std::decay_t<decltype(v)>;
    if constexpr (std::is_same_v<T, bool>) v = !v;
    else if constexpr (std::is_same_v<T, int>) v = v + 1 <= row.row.hi ? v + 1 : v - 1;
    else v = v * 0.75 + 0.25 * (row.row.lo + row.row.hi) / 2.0;  // inside lo..hi, not the default
  });
  for_each_quality_knob(k, [&](const KnobRow& row, const auto& v) {
    QualityKnobs d;
    bool differs = true;
    for_each_quality_knob(d, [&](const KnobRow& r2, const auto& w) {
      if (std::string(r2.row.key) == row.row.key) {
        if constexpr (std::is_same_v<std::decay_t<decltype(w)>, std::decay_t<decltype(v)>>) differs = !(w == v);
      }
    });
    EXPECT_TRUE(differs) << row.row.key << " was left at its default";
    EXPECT_TRUE(row.row.kind == SettingKind::Bool || in_range(row.row, static_cast<double>(v))) << row.row.key;
  });
  QualityFront f;
  f.machine = "m", f.width = 8, f.height = 8, f.command = "c";
  FrontConfig c;
  c.name = "all", c.knobs = k;
  c.scenes.push_back({"s", 100.0, 1.0, 0.1, true});
  f.configs.push_back(c);
  const QualityFront g = front_from_json(front_to_json(f), "front.json");
  ASSERT_EQ(g.configs.size(), 1u);
  EXPECT_EQ(g.configs[0].knobs, k) << describe_knobs(g.configs[0].knobs) << " against " << describe_knobs(k);
}

// apply_knobs writes each knob where the table says; a preset sets only its rows and leaves the
// resolution scale and adaptive steps as the scene gave them.
TEST(QualityFront, KnobsApplyWhereTheTableSays) {
  QualityKnobs k;
  k.view_step_dz = 2.0, k.view_step_min_m = 10.0, k.sun_steps = 7, k.octaves = 3, k.accumulate = 5;
  k.resolution_scale = 0.25, k.adaptive = true;
  RenderSettings r;
  apply_knobs(k, 400.0, r);
  EXPECT_DOUBLE_EQ(r.march.quality.view_step_m, 800.0);
  EXPECT_EQ(r.march.quality.sun_steps, 7);
  EXPECT_EQ(r.march.quality.octaves, 3);
  EXPECT_EQ(r.accumulate, 5);
  EXPECT_DOUBLE_EQ(r.resolution_scale, 0.25);
  EXPECT_TRUE(r.march.features.adaptive_steps);
  EXPECT_EQ(knobs_of(r, 800.0, 400.0).sun_steps, 7);
  EXPECT_DOUBLE_EQ(knobs_of(r, 800.0, 400.0).view_step_dz, 2.0);

  RenderSettings p;
  p.resolution_scale = 0.5, p.march.features.adaptive_steps = true;
  apply_quality("low", p);
  EXPECT_EQ(p.quality, "low");
  EXPECT_EQ(p.march.quality.view_step_m, 0.0);  // from the grid
  EXPECT_EQ(p.march.quality.sun_steps, find_quality("low")->knobs.sun_steps);
  EXPECT_DOUBLE_EQ(p.resolution_scale, 0.5);
  EXPECT_TRUE(p.march.features.adaptive_steps);
}

// Candidates with given front times, most accurate first.
std::vector<FrontConfig> ladder_with_ms(std::vector<double> predicted) {
  std::vector<FrontConfig> out;
  for (std::size_t i = 0; i < predicted.size(); ++i) {
    FrontConfig c;
    c.name = std::to_string(i);
    c.name.insert(0, 1, 'c');  // not "c" + ...: GCC 12 warns falsely (-Wrestrict) on that
    c.ms = predicted[i];
    out.push_back(c);
  }
  return out;
}

TEST(BudgetChoice, MostAccurateThatFits) {
  const auto cands = ladder_with_ms({40, 20, 10, 5});
  const std::vector<double> here = {80, 40, 20, 10};  // this scene costs twice the bench's
  std::vector<std::size_t> asked;
  const BudgetChoice c = choose_under_budget(cands, 45.0, [&](std::size_t i) {
    asked.push_back(i);
    return here[i];
  });
  EXPECT_TRUE(c.met);
  EXPECT_EQ(c.index, 1u);
  EXPECT_EQ(c.ms, 40.0);
  EXPECT_EQ(asked, (std::vector<std::size_t>{0, 1}));  // stops once one fits
}

TEST(BudgetChoice, ExactlyTheBudgetFits) {
  const auto cands = ladder_with_ms({40, 20});
  const BudgetChoice c = choose_under_budget(cands, 40.0, [](std::size_t i) { return i == 0 ? 40.0 : 20.0; });
  EXPECT_TRUE(c.met);
  EXPECT_EQ(c.index, 0u);
}

TEST(BudgetChoice, NoneFitsTakesTheFastestAndSaysSo) {
  const auto cands = ladder_with_ms({40, 20, 10});
  const std::vector<double> here = {400, 200, 100};
  const BudgetChoice c = choose_under_budget(cands, 50.0, [&](std::size_t i) { return here[i]; });
  EXPECT_FALSE(c.met);
  EXPECT_EQ(c.index, 2u);
  EXPECT_EQ(c.ms, 100.0);
  // After the first, c1 is predicted at 200 > 2 x 50 and skipped; c2, the fastest, is measured.
  ASSERT_EQ(c.trials.size(), 2u);
  EXPECT_EQ(c.trials[1].index, 2u);
}

TEST(BudgetChoice, PredictionSkipsHopelessCandidates) {
  const auto cands = ladder_with_ms({100, 90, 12, 10});
  std::vector<std::size_t> asked;
  const std::vector<double> here = {100, 90, 12, 10};
  const BudgetChoice c = choose_under_budget(cands, 15.0, [&](std::size_t i) {
    asked.push_back(i);
    return here[i];
  });
  EXPECT_TRUE(c.met);
  EXPECT_EQ(c.index, 2u);
  EXPECT_EQ(asked, (std::vector<std::size_t>{0, 2}));  // c1 predicted at 90 > 30: not rendered
}

TEST(BudgetChoice, LadderIsClimbedFromTheFastestUntilOneDoesNotFit) {
  const auto cands = preset_ladder();  // high, default, low; errors and times unknown
  const std::vector<double> here = {50.0, 4.0, 2.0};
  std::vector<std::size_t> asked;
  auto measure = [&](std::size_t i) {
    asked.push_back(i);
    return here[i];
  };
  BudgetChoice c = choose_under_budget(cands, 10.0, measure);
  EXPECT_TRUE(c.met);
  EXPECT_EQ(cands[c.index].name, "default");
  EXPECT_EQ(c.ms, 4.0);
  EXPECT_EQ(asked, (std::vector<std::size_t>{2, 1, 0}));
  asked.clear();
  c = choose_under_budget(cands, 1000.0, measure);
  EXPECT_EQ(cands[c.index].name, "high");
  asked.clear();
  c = choose_under_budget(cands, 1.0, measure);  // not even low fits: high is never timed
  EXPECT_FALSE(c.met);
  EXPECT_EQ(cands[c.index].name, "low");
  EXPECT_EQ(c.ms, 2.0);
  EXPECT_EQ(asked, (std::vector<std::size_t>{2}));
}

TEST(BudgetChoice, TiesInErrorGoToTheFasterAndTiesInTimeToTheMoreAccurate) {
  // Equal errors: the ranking puts the faster first, so it is tried (and chosen) first.
  QualityFront f;
  f.configs.push_back(config("slow", "sweep", {{"x", 1, 20, 0.01, true}}));
  f.configs.push_back(config("fast", "sweep", {{"x", 1, 10, 0.01, true}}));
  rank_front(f);
  ASSERT_EQ(f.configs[0].name, "fast");
  // Equal measured times over the budget: the first (more accurate) of the fastest is chosen.
  const auto cands = ladder_with_ms({5.0, 5.0});
  const BudgetChoice c = choose_under_budget(cands, 1.0, [](std::size_t) { return 3.0; });
  EXPECT_FALSE(c.met);
  EXPECT_EQ(c.index, 0u);
}

TEST(BudgetChoice, RejectsNoCandidatesAndBadBudgets) {
  EXPECT_THROW(choose_under_budget({}, 10.0, [](std::size_t) { return 1.0; }), std::invalid_argument);
  EXPECT_THROW(choose_under_budget(ladder_with_ms({1}), 0.0, [](std::size_t) { return 1.0; }),
               std::invalid_argument);
  EXPECT_THROW(choose_under_budget(ladder_with_ms({1}), -5.0, [](std::size_t) { return 1.0; }),
               std::invalid_argument);
}

// Feeds `n` frames of `ms` each; returns how many changes happened.
int feed(BudgetStepper& s, int n, double ms, double budget) {
  int changes = 0;
  for (int i = 0; i < n; ++i) changes += s.observe(ms, budget) ? 1 : 0;
  return changes;
}

TEST(BudgetStepper, StepsDownWhenOverAndSettlesFirst) {
  BudgetStepper s(3);
  for (int i = 0; i < BudgetStepper::kSettleFrames - 1; ++i) EXPECT_FALSE(s.observe(50.0, 20.0));
  EXPECT_TRUE(s.observe(50.0, 20.0));
  EXPECT_EQ(s.current(), 1u);
  EXPECT_EQ(s.last_ms(0), 50.0);
  feed(s, BudgetStepper::kSettleFrames, 30.0, 20.0);
  EXPECT_EQ(s.current(), 2u);
  EXPECT_EQ(feed(s, 20, 30.0, 20.0), 0);  // the fastest: nowhere further down
  EXPECT_EQ(s.current(), 2u);
}

TEST(BudgetStepper, OneSlowFrameDoesNotMoveIt) {
  BudgetStepper s(2);
  s.observe(10.0, 20.0), s.observe(500.0, 20.0), s.observe(10.0, 20.0), s.observe(10.0, 20.0);
  EXPECT_EQ(s.current(), 0u);
}

TEST(BudgetStepper, HysteresisNoFlicker) {
  // Budget 20 ms. Candidate 1 costs 8 ms: with 50 % headroom it probes 0, which costs 19 ms and
  // fits, so it stays there. A slow spell (25 ms) drops it to 1; 0's last time is then over the
  // 80 % margin, so it does not go back up each time 1 runs fast.
  BudgetStepper s(2, 1);
  EXPECT_EQ(feed(s, BudgetStepper::kSettleFrames, 8.0, 20.0), 1);
  EXPECT_EQ(s.current(), 0u);
  EXPECT_EQ(feed(s, 100, 19.0, 20.0), 0);
  EXPECT_EQ(feed(s, 2, 25.0, 20.0), 0);  // two slow frames among many at 19 ms: the median holds
  EXPECT_EQ(feed(s, 100, 25.0, 20.0), 1);
  EXPECT_EQ(s.current(), 1u);
  EXPECT_EQ(feed(s, 100, 8.0, 20.0), 0);
  EXPECT_EQ(s.current(), 1u);
}

TEST(BudgetStepper, StepsUpWhenTheMoreAccurateFitsWithMargin) {
  BudgetStepper s(3, 2);  // start at the fastest, nothing known: probe up with 50 % headroom
  EXPECT_EQ(feed(s, BudgetStepper::kSettleFrames, 4.0, 20.0), 1);
  EXPECT_EQ(s.current(), 1u);
  feed(s, BudgetStepper::kSettleFrames, 12.0, 20.0);  // 12 > 10: no probe further up
  EXPECT_EQ(s.current(), 1u);
  // Over budget on 1 for a while (the camera moved into the cloud), down to 2, and back up once 1's
  // time is forgotten and 2 leaves headroom again.
  feed(s, BudgetStepper::kSettleFrames, 30.0, 20.0);
  EXPECT_EQ(s.current(), 2u);
  EXPECT_EQ(feed(s, BudgetStepper::kForgetFrames, 4.0, 20.0), 0);  // 1 took 30 ms not long ago
  EXPECT_EQ(feed(s, 1, 4.0, 20.0), 1);
  EXPECT_EQ(s.current(), 1u);
}

TEST(BudgetStepper, PredictedCostsDecideWhetherToTryTheMoreAccurate) {
  // Candidate 0 is predicted at 3x candidate 1. At 4 ms a frame, 0 is predicted at 12 ms, within
  // 80 % of 20 ms: taken. At 6 ms it is predicted at 18 ms: not taken, although 6 ms leaves the
  // 50 % headroom that probing without a prediction asks for.
  BudgetStepper a(2, 1);
  a.set_predicted_costs({30.0, 10.0});
  EXPECT_EQ(feed(a, BudgetStepper::kSettleFrames, 4.0, 20.0), 1);
  BudgetStepper b(2, 1);
  b.set_predicted_costs({30.0, 10.0});
  EXPECT_EQ(feed(b, 50, 6.0, 20.0), 0);
  BudgetStepper c(2, 1);  // the same without predictions probes
  EXPECT_EQ(feed(c, BudgetStepper::kSettleFrames, 6.0, 20.0), 1);
}

TEST(BudgetStepper, OffDoesNothing) {
  BudgetStepper s(3);
  EXPECT_EQ(feed(s, 50, 1000.0, 0.0), 0);
  EXPECT_EQ(s.current(), 0u);
  BudgetStepper empty(0);
  EXPECT_FALSE(empty.observe(10.0, 5.0));
}

}  // namespace
}  // namespace cv::bench
