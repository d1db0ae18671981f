// Issue 11, item 2: the Monte Carlo reference against an independent solution of the same problem.
// A horizontally uniform, flat-topped slab is written as a CF NetCDF file, imported through the
// normal path (importers::import_file, grid_mean_extinction) and traced by core::MonteCarloRenderer
// with the sun at the zenith angles; the adding-doubling solver (tests/physics/slab_solver,
// which shares no code with the reference) solves the plane-parallel slab. Compared: the reflected
// radiance at nadir (the renderer's pixels), the plane albedo (analog paths from the sun), and the
// reflected radiance at oblique views toward, across and away from the sun's azimuth.
// Bounds: 4 Monte Carlo standard errors plus the solver's quadrature error (its change from N to
// 2N streams); the seeds are fixed, so a pass is reproducible, and at 4 standard errors a correct
// estimator fails one comparison in ~16 000 when the sampling changes. docs/physics.md,
// "Plane-parallel slab check"; the full sweep is tests/bench/slab_sweep.cpp (docs/BENCHMARKS.md).
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "physics/physics.hpp"
#include "physics/slab_solver.hpp"
#include "support/slab_case.hpp"

namespace {
using namespace cv::test::slab;
constexpr double kPi = 3.14159265358979323846;
constexpr double kSigmas = 4.0;

class SlabCheck : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = cv::test::temp_dir(::testing::UnitTest::GetInstance()->current_test_info()->name()); }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  ImportedSlab slab(double tau, SlabPhase phase) {
    const std::string path = (dir_ / "slab.nc").string();
    write_slab_file(path, tau, phase);
    return import_slab(path, phase);
  }
  std::filesystem::path dir_;
};

slabcheck::PhaseFunction solver_phase(SlabPhase p) {
  return p == SlabPhase::HG085 ? slabcheck::henyey_greenstein_phase(0.85) : slabcheck::approximate_mie_phase(20.0);
}

// The solver's answer at one sun angle, with its uncertainty (N against 2N streams).
struct Reference {
  double radiance, radiance_err, albedo, albedo_err, transmission;
};
Reference solve(double tau, SlabPhase phase, double theta0_deg) {
  const double mu0 = std::cos(theta0_deg * kPi / 180.0);
  slabcheck::SlabProblem p;
  p.tau = tau;
  p.phase = solver_phase(phase);
  p.mu_extra = {1.0, mu0};
  slabcheck::SlabOptions o1, o2;
  o1.streams = phase == SlabPhase::HG085 ? 32 : 64;
  o2.streams = 2 * o1.streams;
  const slabcheck::SlabSolution a = solve_slab(p, o1), b = solve_slab(p, o2);
  return {b.nadir_radiance(mu0), std::abs(a.nadir_radiance(mu0) - b.nadir_radiance(mu0)), b.plane_albedo(mu0),
          std::abs(a.plane_albedo(mu0) - b.plane_albedo(mu0)), b.total_transmission(mu0)};
}

TEST_F(SlabCheck, TheImportedSlabHasTheOpticalDepthItWasWrittenWith) {
  // The comparison is only as good as the optical depth the Monte Carlo sees: the column of the
  // imported medium (trapezoid over its altitude nodes, exact for the kernel's linear interpolation)
  // must be the one the file was written for, in every column, for both water phases.
  for (SlabPhase phase : {SlabPhase::HG085, SlabPhase::Mie}) {
    for (double tau : {1.0, 100.0}) {
      const ImportedSlab s = slab(tau, phase);
      std::printf("%s tau %g: imported column optical depth %.7f, largest column difference %.1e, %zu warnings\n",
                  phase_name(phase), tau, s.column_tau, s.column_spread, s.warnings.size());
      for (const auto& w : s.warnings) std::printf("  warning: %s\n", w.c_str());
      EXPECT_NEAR(s.column_tau / tau, 1.0, 1e-6) << phase_name(phase);
      EXPECT_LT(s.column_spread, 1e-6);
      // The other water phase is absent.
      const auto& other = phase == SlabPhase::HG085 ? s.medium.liquid_per_m : s.medium.ice_per_m;
      for (float v : other) ASSERT_EQ(v, 0.0f);
      EXPECT_DOUBLE_EQ(s.liquid_r_eff_um, 10.0);
    }
  }
}

TEST(SlabCheckPhase, TheSolversPhaseFunctionsAreTheOnesTheMonteCarloSamples) {
  // The solver re-implements HG and the approximate Mie blend from the published formulas; the
  // reference evaluates shaders/common's. Both must describe the same scattering, or the comparison
  // measures a different problem. (The solver does not call the project's functions; this test does.)
  namespace p64 = cv::physics::f64;
  const auto mie = p64::mie_params(20.0);
  const slabcheck::PhaseFunction ours_mie = slabcheck::approximate_mie_phase(20.0), ours_hg = slabcheck::henyey_greenstein_phase(0.85);
  double worst_mie = 0.0, worst_hg = 0.0;
  for (int i = 0; i <= 4000; ++i) {
    // Dense near the forward peak: mu = 1 - 2 (i / 4000)^4.
    const double u = i / 4000.0, mu = 1.0 - 2.0 * u * u * u * u;
    worst_mie = std::max(worst_mie, std::abs(ours_mie.value(mu) / p64::phase_mie(mu, mie) - 1.0));
    worst_hg = std::max(worst_hg, std::abs(ours_hg.value(mu) / p64::phase_hg(mu, 0.85) - 1.0));
  }
  std::printf("largest relative difference over mu: Mie %.1e, HG %.1e\n", worst_mie, worst_hg);
  EXPECT_LT(worst_mie, 1e-12);
  EXPECT_LT(worst_hg, 1e-12);
}

struct McCase {
  double tau, theta0;
  int spp, paths;
};

// The Monte Carlo's nadir radiance (spp > 0) and analog plane albedo at one case, the solver's, and
// the checks: the radiance within 4 standard errors plus the solver's error when `hard_radiance`,
// the albedo always. The standard errors must be below the limits given, so that the bounds have
// power (a relative one for the radiance, an absolute one for the albedo).
struct McResult {
  Estimate radiance;
  AnalogFluxes fluxes;
  Reference ref;
};
McResult compare(const ImportedSlab& s, SlabPhase phase, const McCase& c, bool hard_radiance, double max_rel_se_radiance,
                 double max_se_albedo) {
  McResult r;
  r.ref = solve(c.tau, phase, c.theta0);
  const Reference& ref = r.ref;
  const cv::core::MarchSettings m = march_for(phase, s);
  const std::uint64_t key = static_cast<std::uint64_t>(c.tau * 10 + c.theta0);
  std::printf("%s tau %5.1f sun %2.0f:", phase_name(phase), c.tau, c.theta0);
  if (c.spp > 0) {
    const Estimate& e = r.radiance = mc_nadir_radiance(s, m, c.theta0, c.spp, 101 + key);
    std::printf(" nadir I/E solver %.5f +- %.1e, MC %.5f +- %.5f (%.1f %%, z %+.2f, %d spp, %.1f s, %llu cut);", ref.radiance,
                ref.radiance_err, e.mean, e.se, 100.0 * e.se / e.mean, (e.mean - ref.radiance) / e.se, c.spp, e.seconds,
                static_cast<unsigned long long>(e.truncated));
    EXPECT_EQ(e.truncated, 0u);
    if (hard_radiance) {
      EXPECT_LT(e.se / e.mean, max_rel_se_radiance);
      EXPECT_LT(std::abs(e.mean - ref.radiance), kSigmas * e.se + ref.radiance_err) << c.tau << " " << c.theta0;
    }
  }
  const AnalogFluxes& f = r.fluxes = mc_analog_fluxes(s, m, c.theta0, c.paths, 202 + key);
  std::printf(" plane albedo solver %.5f +- %.1e, MC %.5f +- %.5f (z %+.2f, %d paths, %.1f s); MC R + T %.6f, lost %llu\n",
              ref.albedo, ref.albedo_err, f.albedo(), f.albedo_se(), (f.albedo() - ref.albedo) / f.albedo_se(), c.paths, f.seconds,
              f.albedo() + f.transmission(), static_cast<unsigned long long>(f.lost));
  // The Monte Carlo's own bookkeeping: nothing cut short, every path reflected or transmitted.
  EXPECT_EQ(f.lost, 0u);
  EXPECT_EQ(f.reflected + f.transmitted, f.paths);
  EXPECT_LT(f.albedo_se(), max_se_albedo);
  EXPECT_LT(std::abs(f.albedo() - ref.albedo), kSigmas * f.albedo_se() + ref.albedo_err) << c.tau << " " << c.theta0;
  return r;
}

TEST_F(SlabCheck, HenyeyGreensteinSlabMatchesTheSolver) {
  // HG g = 0.85 (the reference's ice phase). Thin and thick, sun high and low: the nadir radiance's
  // standard error is held below 3 % and the plane albedo's below 0.003, so the bounds (4 of them)
  // resolve ~10 % and ~0.012. The full sweep is the benchmark.
  const McCase cases[] = {{1, 75, 200000, 100000}, {2, 0, 100000, 100000}, {10, 30, 60000, 100000},
                          {20, 60, 30000, 40000},  {100, 0, 8000, 15000}};
  const auto t0 = std::chrono::steady_clock::now();
  for (const McCase& c : cases) {
    const ImportedSlab s = slab(c.tau, SlabPhase::HG085);
    compare(s, SlabPhase::HG085, c, true, 0.03, 0.003);
  }
  std::printf("HG cases: %.1f s\n", std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
}

TEST_F(SlabCheck, DropletSlabPlaneAlbedoMatchesTheSolver) {
  // The approximate Mie phase at 20 um. The analog albedo draws directions from the phase and never
  // evaluates it toward the sun, so the forward peak does not make it heavy-tailed: a hard check.
  const McCase cases[] = {{2, 0, 0, 100000}, {10, 60, 0, 60000}, {50, 30, 0, 20000}};
  for (const McCase& c : cases) {
    const ImportedSlab s = slab(c.tau, SlabPhase::Mie);
    compare(s, SlabPhase::Mie, c, false, 0.0, 0.003);  // the radiance is the next test's
  }
}

// Whether the reference's nadir radiance converges on droplet clouds. It did not before the
// reference's forward-peak technique (MonteCarloSettings::peak_mis, docs/physics.md "A reference
// that converges"): next-event estimation met the droplets' forward peak (g_HG 0.9946, up to
// ~2.7e3 /sr) whenever a path pointed near the sun, and 10 of 12 batches below excluded the solver.
// With it, the bound below holds (measured 0.01811 +- 0.00040 against 0.01861, z -1.2; 2 of 12
// batches outside 3 of their standard errors, their mean 0.2 % off: a mild tail remains).
constexpr bool kDropletRadianceConverges = true;

// Independent batches of the nadir radiance (seeds seed0, seed0 + 1, ...): how many put the solver's
// value outside 3 of their own standard errors, and the median of their z. For an estimator whose
// standard error is right that is 0.3 % of the batches and a median near 0 (HG at 1e4 samples comes
// close: 60 batches at tau 2 gave mean z^2 1.34 and one |z| above 3, a mild skew that larger
// batches lose; printed, not asserted).
struct Batches {
  int count = 0, excluding = 0;
  double median_z = 0.0, mean = 0.0;
};
Batches nadir_batches(const ImportedSlab& s, SlabPhase phase, double theta0, double solver, int spp, int count,
                      std::uint64_t seed0) {
  Batches b;
  b.count = count;
  std::vector<double> z;
  for (int k = 0; k < count; ++k) {
    const Estimate e = mc_nadir_radiance(s, march_for(phase, s), theta0, spp, seed0 + static_cast<std::uint64_t>(k));
    z.push_back((e.mean - solver) / e.se);
    b.excluding += std::abs(z.back()) > 3.0;
    b.mean += e.mean / count;
  }
  std::sort(z.begin(), z.end());
  b.median_z = z[z.size() / 2];
  return b;
}

TEST_F(SlabCheck, DropletSlabNadirRadianceMatchesTheSolver) {
  // A thin slab shows it best: most of the radiance is single and double scattering, and the part
  // that went through the forward peak reaches the estimator only when a path happens to point
  // within a fraction of a degree of the sun. In most runs the mean misses much of it while the
  // standard error from the same samples stays small (the sweep's run here: 0.0145 +- 0.0004
  // against 0.0186); in a few, a sample catches it and the standard error balloons. With 8e6
  // samples at tau 1 the mean comes within 1.5 standard errors (docs/physics.md).
  // 4e5 samples: at 1e5 the realised standard error still swung between 2.2 % and 5.1 % of the mean
  // with the same seed when a change of the grid's top moved where the paths start (a heavy tail).
  const McCase c{2, 30, 400000, 30000};
  const ImportedSlab s = slab(c.tau, SlabPhase::Mie);
  const McResult r = compare(s, SlabPhase::Mie, c, false, 0.0, 0.003);
  // What it looks like, against HG 0.85 on the same slab: 12 batches of 1e4 samples each.
  const ImportedSlab hg = slab(c.tau, SlabPhase::HG085);
  const Batches bm = nadir_batches(s, SlabPhase::Mie, c.theta0, r.ref.radiance, 10000, 12, 500);
  const Batches bh = nadir_batches(hg, SlabPhase::HG085, c.theta0, solve(c.tau, SlabPhase::HG085, c.theta0).radiance, 10000, 12, 500);
  std::printf("nadir radiance, tau 2, sun 30, 12 batches of 1e4 samples: %d of 12 put the solver outside 3 of their own "
              "standard errors with the Mie phase (median z %+.1f, mean of the batches %.1f %% off), %d of 12 with HG 0.85 "
              "(median z %+.1f)\n",
              bm.excluding, bm.median_z, 100.0 * (bm.mean / r.ref.radiance - 1.0), bh.excluding, bh.median_z);
  if (!kDropletRadianceConverges) {
    GTEST_SKIP() << "the Monte Carlo's nadir radiance does not converge on droplet clouds (next-event estimation against "
                    "the forward peak; docs/physics.md): measured "
                 << r.radiance.mean << " +- " << r.radiance.se << " against the solver's " << r.ref.radiance
                 << "; the plane albedo above is held";
  }
  EXPECT_LT(r.radiance.se / r.radiance.mean, 0.03);
  EXPECT_LT(std::abs(r.radiance.mean - r.ref.radiance), kSigmas * r.radiance.se + r.ref.radiance_err);
}

// Off nadir: the renderer's pixels of a camera that sees the slab's top obliquely, toward, across and
// away from the sun's azimuth, against the solver's reflection at that azimuth (every Fourier mode).
// The radiance there depends strongly on the azimuth (toward the sun it is several times that away
// from it at these angles), so a wrong phase convention or a Monte Carlo that loses the forward
// lobe's light on its way out shows. Bounds as above; the solver's uncertainty is its change from
// N / 2 to N streams.
TEST_F(SlabCheck, ObliqueViewsMatchTheSolverAtEveryAzimuth) {
  struct View {
    SlabPhase phase;
    double tau, theta0, view, heading;
    int spp;
  };
  const View views[] = {{SlabPhase::HG085, 5, 60, 70, 0, 40000},   {SlabPhase::HG085, 5, 60, 70, 90, 40000},
                        {SlabPhase::HG085, 5, 60, 70, 180, 40000}, {SlabPhase::HG085, 5, 60, 85, 0, 40000},
                        {SlabPhase::HG085, 5, 60, 85, 180, 40000}, {SlabPhase::Mie, 5, 30, 70, 0, 40000},
                        {SlabPhase::Mie, 5, 30, 70, 180, 40000}};
  double toward = 0.0, away = 0.0;
  for (SlabPhase phase : {SlabPhase::HG085, SlabPhase::Mie}) {
    const ImportedSlab s = slab(5, phase);
    cv::core::MarchSettings m = march_for(phase, s);
    m.quality.anti_alias = false;
    slabcheck::SlabProblem p;
    p.tau = 5;
    p.phase = solver_phase(phase);
    for (const View& v : views) {
      if (v.phase != phase) continue;
      p.mu_extra.push_back(std::cos(v.theta0 * kPi / 180.0));
      p.mu_extra.push_back(std::cos(v.view * kPi / 180.0));
    }
    slabcheck::SlabOptions fine, coarse;
    fine.streams = phase == SlabPhase::HG085 ? 32 : 64;
    coarse.streams = fine.streams / 2;
    fine.azimuth_modes = coarse.azimuth_modes = 0;
    const slabcheck::SlabSolution a = solve_slab(p, fine), b = solve_slab(p, coarse);
    std::uint64_t seed = 900;
    for (const View& v : views) {
      if (v.phase != phase) continue;
      const double mu0 = std::cos(v.theta0 * kPi / 180.0), mu = std::cos(v.view * kPi / 180.0), dphi = v.heading * kPi / 180.0;
      const double ref = a.radiance(mu, mu0, dphi), err = std::abs(ref - b.radiance(mu, mu0, dphi));
      const Estimate e = mc_view_radiance(s, s.medium, m, oblique_camera(v.view, v.heading), v.theta0, v.spp, seed++);
      std::printf("%s tau 5, sun %g, view %g, heading %g: Monte Carlo %.5f +- %.5f, solver %.5f +- %.5f (z %+.1f)\n",
                  phase == SlabPhase::HG085 ? "HG 0.85" : "Mie 20 um", v.theta0, v.view, v.heading, e.mean, e.se, ref, err,
                  (e.mean - ref) / e.se);
      EXPECT_LT(e.se / e.mean, 0.03);
      EXPECT_LT(std::abs(e.mean - ref), kSigmas * e.se + err) << v.view << " " << v.heading;
      if (phase == SlabPhase::HG085 && v.view == 70.0 && v.heading == 0.0) toward = ref;
      if (phase == SlabPhase::HG085 && v.view == 70.0 && v.heading == 180.0) away = ref;
    }
  }
  EXPECT_GT(toward, 3.0 * away);  // the azimuth matters at these angles: the check has something to see
}

// Issue 11, item 3 on the slabs, for the renderer's model rather than the reference: the march
// kernel (CPU) with the two-stream source and its diffuse light shaped by the slab tables
// (diffuse_shape "slab", the default) against the adding-doubling solver, at nadir (the issue's
// bound, 5 %) and obliquely toward and away from the sun's azimuth (8 %). The same cases with the
// light linear in angle fail: a thin HG slab under a 60-degree sun is 15 % dark at nadir, and the
// oblique views 20-40 % off (docs/BENCHMARKS.md).
TEST_F(SlabCheck, TheSlabShapedSourceMatchesTheSolverAtNadirAndObliquely) {
  for (SlabPhase phase : {SlabPhase::HG085, SlabPhase::Mie}) {
    for (double tau : {1.0, 5.0, 20.0}) {
      const ImportedSlab s = slab(tau, phase);
      cv::core::MarchSettings m = march_for(phase, s);
      m.medium.ms_two_stream = true;
      ASSERT_TRUE(m.medium.ms_slab);  // the default
      m.quality.anti_alias = false;
      slabcheck::SlabProblem p;
      p.tau = tau;
      p.phase = solver_phase(phase);
      p.mu_extra = {1.0, 0.5, std::cos(70.0 * kPi / 180.0)};
      slabcheck::SlabOptions o;
      o.streams = phase == SlabPhase::HG085 ? 32 : 64;
      o.azimuth_modes = 0;
      const slabcheck::SlabSolution sol = solve_slab(p, o);
      for (double theta0 : {0.0, 60.0}) {
        const double mu0 = std::cos(theta0 * kPi / 180.0);
        const double ref = sol.nadir_radiance(mu0), got = march_nadir_radiance(s, m, theta0);
        EXPECT_NEAR(got / ref, 1.0, 0.05) << phase_name(phase) << " tau " << tau << " sun " << theta0 << " at nadir";
        cv::core::MarchSettings linear = m;
        linear.medium.ms_slab = false;
        const double old = march_nadir_radiance(s, linear, theta0);
        std::printf("%s tau %g sun %g nadir: solver %.5f, slab %+.1f %%, linear %+.1f %%\n", phase_name(phase), tau, theta0, ref,
                    100.0 * (got / ref - 1.0), 100.0 * (old / ref - 1.0));
      }
      // Seventy degrees from the zenith toward and away from a sun at 60 degrees.
      for (double heading : {0.0, 180.0}) {
        const double ref = sol.radiance(std::cos(70.0 * kPi / 180.0), 0.5, heading * kPi / 180.0);
        cv::core::MarchSettings mm = m;
        mm.quality.view_step_m = 5.0;
        mm.quality.sun_steps = 256;
        const double got =
            cv::core::render_reference(s.grid, s.medium, oblique_camera(70.0, heading, 1), sun_at_zenith_angle(60.0), mm).radiance[0].y;
        std::printf("%s tau %g sun 60, view 70, heading %g: solver %.5f, slab %+.1f %%\n", phase_name(phase), tau, heading, ref,
                    100.0 * (got / ref - 1.0));
        EXPECT_NEAR(got / ref, 1.0, 0.08) << phase_name(phase) << " tau " << tau << " heading " << heading;
      }
    }
  }
}

TEST_F(SlabCheck, ReflectedPlusTransmittedIsTheIncidentOnAThickConservativeSlab) {
  // The "never", for the reference: on the thickest slab (paths of hundreds of scatterings),
  // with either phase and the sun low, every path ends reflected or transmitted (none cut at
  // max_bounces or ended by roulette), and the transmitted share is the solver's.
  for (SlabPhase phase : {SlabPhase::HG085, SlabPhase::Mie}) {
    const ImportedSlab s = slab(100.0, phase);
    const double theta0 = 75.0;
    const AnalogFluxes f = mc_analog_fluxes(s, march_for(phase, s), theta0, 5000, 303);
    const Reference ref = solve(100.0, phase, theta0);
    const double se_t = std::sqrt(f.transmission() * (1.0 - f.transmission()) / double(f.paths));
    std::printf("%s tau 100, sun 75: R %.4f + T %.4f = %.6f of %llu paths (lost %llu, %.1f scatterings each); solver R %.4f + T %.4f\n",
                phase_name(phase), f.albedo(), f.transmission(), f.albedo() + f.transmission(),
                static_cast<unsigned long long>(f.paths), static_cast<unsigned long long>(f.lost),
                double(f.scatterings) / double(f.paths), ref.albedo, ref.transmission);
    EXPECT_EQ(f.lost, 0u);
    EXPECT_EQ(f.reflected + f.transmitted, f.paths);
    EXPECT_LT(std::abs(f.transmission() - ref.transmission), kSigmas * se_t + ref.albedo_err);
  }
}

// A Lambertian ground of albedo 0.3 under the slab (the globe drawn with its constant ground
// albedo, no air): the Monte Carlo's paths bounce off it, the solver adds it as a Lambertian surface
// (SlabSolution::nadir_radiance_over_ground). This checks that adding on the reference before the
// march is measured against it (below). HG 0.85, whose nadir radiance converges fastest.
TEST_F(SlabCheck, AGroundUnderTheSlabMatchesTheSolversLambertianSurface) {
  constexpr double kGround = 0.3;
  const double tau = 2.0, theta0 = 30.0, mu0 = std::cos(theta0 * kPi / 180.0);
  const ImportedSlab s = slab(tau, SlabPhase::HG085);
  cv::core::MarchSettings m = march_for(SlabPhase::HG085, s);
  m.features.globe = true;
  m.medium.ground_albedo = glm::dvec3(kGround);
  slabcheck::SlabProblem p;
  p.tau = tau;
  p.phase = solver_phase(SlabPhase::HG085);
  p.mu_extra = {1.0, mu0};
  slabcheck::SlabOptions o1, o2;
  o1.streams = 32;
  o2.streams = 64;
  const slabcheck::SlabSolution a = solve_slab(p, o1), b = solve_slab(p, o2);
  const double ref = b.nadir_radiance_over_ground(mu0, kGround);
  const double ref_err = std::abs(a.nadir_radiance_over_ground(mu0, kGround) - ref);
  const Estimate e = mc_nadir_radiance(s, m, theta0, 100000, 404);
  std::printf("HG tau 2, sun 30, ground 0.3: nadir I/E solver %.5f +- %.1e (%.5f without the ground), MC %.5f +- %.5f (z %+.2f, %.1f s)\n",
              ref, ref_err, b.nadir_radiance(mu0), e.mean, e.se, (e.mean - ref) / e.se, e.seconds);
  EXPECT_GT(ref, 1.5 * b.nadir_radiance(mu0));  // the ground's light is most of it: the check has power
  EXPECT_LT(e.se / e.mean, 0.03);
  EXPECT_LT(std::abs(e.mean - ref), kSigmas * e.se + ref_err);
}

// The two-stream march over that ground (issue 11, items 3 and 8): the ground under a cloud takes
// the delta-scaled beam, the column's diffuse light and the sky's through the column, and the light
// behind the cloud comes through its delta-scaled transmittance. Lit by the true beam alone and seen
// through the true transmittance, droplet slabs of optical depth 1-5 over land of albedo 0.3 were
// 50-68 % dark at nadir (docs/BENCHMARKS.md, "The ground under the clouds"); a bright plateau under
// thin cloud rendered the cloud as a dark blot.
// The two-stream march at nadir over a droplet slab with a Lambertian ground, against the solver's
// Lambertian surface of albedo `ground`, optical depth tau, suns 0 and 60 degrees, within 5 %. The
// scene's constant ground albedo is `constant`; with `map` the globe draws its ground from it.
void expect_ground_case(const ImportedSlab& s, double tau, double ground, double constant, const cv::core::AlbedoMap* map) {
  cv::core::MarchSettings m = march_for(SlabPhase::Mie, s);
  m.medium.ms_two_stream = true;
  m.features.globe = true;
  m.medium.ground_albedo = glm::dvec3(constant);
  slabcheck::SlabProblem p;
  p.tau = tau;
  p.phase = solver_phase(SlabPhase::Mie);
  p.mu_extra = {1.0, std::cos(60.0 * kPi / 180.0)};
  slabcheck::SlabOptions o;
  o.streams = 128;
  const slabcheck::SlabSolution sol = solve_slab(p, o);
  for (double theta0 : {0.0, 60.0}) {
    const double ref = sol.nadir_radiance_over_ground(std::cos(theta0 * kPi / 180.0), ground);
    const double got = march_nadir_radiance(s, m, theta0, map);
    std::printf("Mie tau %g, sun %g, ground %g (%s, constant %g): nadir I/E solver %.5f, two-stream march %.5f (%+.1f %%)\n", tau, theta0,
                ground, map ? "a map" : "no map", constant, ref, got, 100.0 * (got / ref - 1.0));
    EXPECT_NEAR(got / ref, 1.0, 0.05) << "tau " << tau << ", sun " << theta0 << ", ground " << ground << (map ? " (map)" : "");
  }
}

TEST_F(SlabCheck, TheTwoStreamMarchLightsTheGroundUnderTheCloud) {
  constexpr double kGround = 0.3;
  for (double tau : {1.0, 2.0, 5.0, 20.0}) expect_ground_case(slab(tau, SlabPhase::Mie), tau, kGround, kGround, nullptr);
}

TEST_F(SlabCheck, EachColumnsGroundTakesTheGroundMapsAlbedo) {
  // The scene's constant ground albedo (0.12) against a ground map of its own (uniform: 0.05, about
  // the sea's, and 0.8, snow). The two-stream column's ground takes the map's albedo under it
  // (column_ground_albedo), so the light the ground reflects into the cloud and the cloud returns is
  // the solver's Lambertian surface of the map's albedo. With the constant in the column it was
  // +9 to +16 % (0.05) and -24 to -51 % (0.8) off.
  for (double map_albedo : {0.05, 0.8}) {
    cv::core::AlbedoMap ground;
    ground.width = 4;
    ground.height = 2;
    ground.rgba.assign(4 * 4 * 2, static_cast<float>(map_albedo));
    for (std::size_t i = 3; i < ground.rgba.size(); i += 4) ground.rgba[i] = 0.0f;  // all land
    for (double tau : {2.0, 5.0, 20.0}) expect_ground_case(slab(tau, SlabPhase::Mie), tau, map_albedo, 0.12, &ground);
  }
}

// The phases the renderer uses for ice (HG) and droplets (the Mie fit, its mean cosine as the march
// takes it), and a slab's spherical albedo for one of them from the adding-doubling solver.
struct SkyCase {
  const char* name;
  slabcheck::PhaseFunction phase;
  double g;
};
std::vector<SkyCase> sky_cases() {
  namespace p64 = cv::physics::f64;
  return {{"HG 0.75", slabcheck::henyey_greenstein_phase(0.75), 0.75},
          {"HG 0.85", slabcheck::henyey_greenstein_phase(0.85), 0.85},
          {"Mie 10 um", slabcheck::approximate_mie_phase(10.0), p64::mie_mean_cosine(p64::mie_params(10.0))},
          {"Mie 20 um", slabcheck::approximate_mie_phase(20.0), p64::mie_mean_cosine(p64::mie_params(20.0))}};
}
double sky_case_spherical_albedo(const SkyCase& c, double tau) {
  slabcheck::SlabProblem p;
  p.tau = tau;
  p.phase = c.phase;
  p.mu_extra = {1.0};
  return solve_slab(p).spherical_albedo();
}

TEST(SlabCheckSky, TheSkysLightThroughACloudIsTheSlabsSphericalTransmittance) {
  // The two-stream march lights the ground under a cloud with the sky's irradiance times
  // sky_through_cloud(tau, g) (docs/physics.md, "The ground under the clouds"). For an isotropic
  // sky over a conservative slab and a black ground the exact share is the slab's spherical
  // transmittance, 1 - s (s its spherical albedo), which the adding-doubling solver gives without
  // any of the renderer's code. The phases the renderer uses for ice (HG) and droplets (the Mie fit,
  // its mean cosine as the march takes it), optical depths from thin to opaque.
  namespace p64 = cv::physics::f64;
  for (const SkyCase& c : sky_cases()) {
    for (double tau : {0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0}) {
      const double exact = 1.0 - sky_case_spherical_albedo(c, tau);
      const double got = p64::sky_through_cloud(tau, c.g);
      std::printf("%-9s (g %.4f) tau %5.1f: spherical transmittance %.4f, sky_through_cloud %.4f (%+.1f %%)\n", c.name, c.g, tau, exact, got,
                  100.0 * (got / exact - 1.0));
      EXPECT_NEAR(got / exact, 1.0, 0.05) << c.name << ", tau " << tau;
    }
  }
  // No optical depth or mean cosine gives more than the sky or a negative share.
  for (double tau : {0.0, 1e-30, 1e30, -1.0}) {
    for (double g : {-1.0, 0.0, 0.99, 1.0}) {
      const double t = p64::sky_through_cloud(tau, g);
      EXPECT_TRUE(t >= 0.0 && t <= 1.0) << tau << " " << g;
    }
  }
}

TEST(SlabCheckSky, TheSkysLightOnTheGroundUnderACloudIncludesWhatTheCloudReturns) {
  // Over a Lambertian ground of albedo A the ground under a conservative slab lit by an isotropic
  // sky receives t / (1 - A s) of the sky's irradiance: what reaches it through the slab (t = 1 - s),
  // and what it reflects, which the slab returns in its spherical albedo from below (s; the same
  // as from above for a homogeneous slab) again and again. s here is the adding-doubling solver's,
  // no renderer code; the march's sky_through_cloud_to_ground must be within 5 % of it from the sea
  // to fresh snow. Leaving the returned light out (the black ground's t) gives snow (0.8) under
  // optical depth 20 less than half of it, and 0.95 under 100 an eighth.
  namespace p64 = cv::physics::f64;
  double most_missed = 1.0;
  for (const SkyCase& c : sky_cases()) {
    for (double tau : {1.0, 5.0, 20.0, 100.0}) {
      const double s = sky_case_spherical_albedo(c, tau);
      for (double a : {0.07, 0.3, 0.8, 0.95}) {
        const double exact = (1.0 - s) / (1.0 - a * s);
        const glm::dvec3 got = p64::sky_through_cloud_to_ground(tau, c.g, glm::dvec3(a));
        std::printf("%-9s tau %5.1f ground %.2f: exact %.4f, march %.4f (%+.1f %%), black ground's share %.4f\n", c.name, tau, a, exact,
                    got.y, 100.0 * (got.y / exact - 1.0), p64::sky_through_cloud(tau, c.g));
        EXPECT_NEAR(got.x / exact, 1.0, 0.05) << c.name << ", tau " << tau << ", ground " << a;
        EXPECT_EQ(got.x, got.z);  // a grey ground: the same in every channel
        most_missed = std::min(most_missed, p64::sky_through_cloud(tau, c.g) / exact);
      }
    }
  }
  // The term this adds is not small over snow: without it the ground got less than half.
  EXPECT_LT(most_missed, 0.5);
  // The ground's channels are independent, and no albedo (even out of range) gives a share above
  // what a white ground's endless exchange allows or below the black ground's.
  const glm::dvec3 mixed = p64::sky_through_cloud_to_ground(10.0, 0.85, glm::dvec3(0.0, 0.5, 0.9));
  EXPECT_DOUBLE_EQ(mixed.x, p64::sky_through_cloud(10.0, 0.85));
  EXPECT_LT(mixed.y, mixed.z);
  for (double tau : {0.0, 1e-30, 1.0, 1e30, -1.0}) {
    for (double a : {-1.0, 0.0, 1.0, 2.0}) {
      const double t = p64::sky_through_cloud(tau, 0.85);
      const double v = p64::sky_through_cloud_to_ground(tau, 0.85, glm::dvec3(a)).x;
      EXPECT_TRUE(std::isfinite(v) && v >= t && v <= 100.0 * t + 1e-300) << tau << " " << a;
    }
  }
}

TEST(SlabCheckSky, TheGroundsDiffuseAlbedoIsLandOrWaterByTheWaterFraction) {
  namespace p64 = cv::physics::f64;
  const glm::dvec3 land(0.2, 0.3, 0.4);
  EXPECT_EQ(p64::ground_diffuse_albedo(land, 0.0), land);
  const glm::dvec3 sea = p64::ground_diffuse_albedo(land, 1.0);
  // Open water under diffuse light: the surface's 6.6 % plus a little from the water body, 6-9 %.
  for (int c = 0; c < 3; ++c) EXPECT_TRUE(sea[c] > 0.06 && sea[c] < 0.09) << c;
  const glm::dvec3 half = p64::ground_diffuse_albedo(land, 0.5);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(half[c], 0.5 * (land[c] + sea[c]), 1e-15);
}

}  // namespace
