// Benchmark (not a test): the multiple-scattering models on a plane-parallel slab seen at oblique
// angles, against the Monte Carlo reference on the same imported slab (the slab check of issue 11
// validates that reference against the adding-doubling solver at nadir and, with every azimuthal
// mode, at oblique views; the solver's radiance is printed beside the Monte Carlo's, docs/BENCHMARKS.md,
// "The slab solver at every azimuth"). It separates the models' angular
// error from the 3-D effects of the standard scenes: a deck seen at a grazing angle toward the sun
// (stratocumulus) and a view from inside a cloud are oblique views of a nearly plane-parallel cloud.
//   bench_slab_views [--phase hg|mie|both] [--tau 1,2,...] [--zenith SUN,...] [--view V,...]
//                    [--azimuth A,...] [--spp N] [--seed S] [--max-bounces N]
// --view: view zenith angles at the cloud top (degrees); --azimuth: the camera's heading from the
// sun's azimuth (0: looking toward the sun, the light it sees scattered forward; 180: away).
// Camera 2.5 km up over (0, 0), half a kilometre above the slab (1-2 km up and 666 km across): every
// ray meets its top far from its edges, and even an 85-degree view meets it within 6 km, where the
// Earth's curvature turns the view by 0.06 degrees. (From 10 km up, until the twenty-ninth session,
// an 85-degree view met the top about 100 km off, turned by 0.9 degrees, and the Monte Carlo there
// was 1-10 % below the plane-parallel answer.)
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "bench/bench_args.hpp"
#include "physics/slab_solver.hpp"
#include "reference/monte_carlo.hpp"
#include "reference/raymarcher.hpp"
#include "support/scratch_dir.hpp"
#include "support/slab_case.hpp"

namespace {
using namespace cv::test::slab;

}  // namespace

int main(int argc, char** argv) {
  std::string phases = "mie";
  std::vector<double> taus{2, 5, 20}, zeniths{30}, views{0, 45, 70, 85}, azimuths{0, 90, 180};
  int spp = 20000, max_bounces = 1000000;
  std::uint64_t seed = 5;
  int exact_streams = 32;
  bool delta_scaled = false;
  std::vector<double> delta_f;  // the truncated share; empty: g^2 (delta-Eddington)
  namespace ba = cv::bench_args;
  const int code = ba::parse(
      "bench_slab_views",
      "usage: bench_slab_views [--phase hg|mie|both] [--tau 1,2,...] [--zenith SUN,...] [--view V,...]\n"
      "                        [--azimuth A,...] [--spp N] [--seed S] [--max-bounces N] [--delta-scaled [--delta-f F]]\n"
      "                        [--exact-streams N]\n"
      "  the octave sum and the two-stream source (its diffuse light linear, and slab-shaped) against the Monte Carlo on a slab seen obliquely\n"
      "  (view zenith V at the cloud top, heading A from the sun's azimuth: 0 toward the sun), and the\n"
      "  adding-doubling solver's radiance there (every azimuthal mode, N streams per hemisphere, 32 by\n"
      "  default) with the Monte Carlo against it;\n"
      "  --max-bounces cuts the Monte Carlo's paths (the light of the first N orders of scattering);\n"
      "  --delta-scaled (HG only) also solves the delta-Eddington problem the two-stream's diffuse path\n"
      "  assumes (extinction (1 - g^2) sigma, HG g / (1 + g)) by the same Monte Carlo: the error that\n"
      "  scaling keeps even when its transport is solved exactly; --delta-f F truncates the share F\n"
      "  instead of g^2 (extinction (1 - F) sigma, HG (g - F) / (1 - F))\n",
      argc, argv,
      {ba::one_of("--phase", phases, {"hg", "mie", "both"}), ba::numbers("--tau", taus), ba::numbers("--zenith", zeniths),
       ba::numbers("--view", views), ba::numbers("--azimuth", azimuths), ba::integer("--spp", spp),
       ba::integer("--max-bounces", max_bounces), ba::seed("--seed", seed), ba::flag("--delta-scaled", delta_scaled),
       ba::numbers("--delta-f", delta_f), ba::integer("--exact-streams", exact_streams)});
  if (code >= 0) return code;
  if (!delta_f.empty() && (!delta_scaled || delta_f.size() != 1 || !(delta_f[0] >= 0.0 && delta_f[0] < 0.85))) {
    std::fprintf(stderr, "bench_slab_views: --delta-f: expected one share from 0 to below 0.85 (the slab's g), with --delta-scaled\n");
    return 2;
  }
  if (exact_streams < 2 || exact_streams > 256) {
    std::fprintf(stderr, "bench_slab_views: --exact-streams: found %d, expected 2 to 256 streams per hemisphere\n", exact_streams);
    return 2;
  }
  if (delta_scaled && phases != "hg") {
    std::fprintf(stderr, "bench_slab_views: --delta-scaled: found --phase %s, expected --phase hg (the droplets' phase has no free mean cosine to scale)\n",
                 phases.c_str());
    return 2;
  }
  // The process's own folder (removed at exit): two runs at once never share a file.
  const std::filesystem::path dir = cv::test_support::scratch_dir();
  std::vector<SlabPhase> which;
  if (phases == "hg" || phases == "both") which.push_back(SlabPhase::HG085);
  if (phases == "mie" || phases == "both") which.push_back(SlabPhase::Mie);
  std::printf("| phase | tau | sun zenith | view zenith | heading from sun | Monte Carlo I/E | adding-doubling I/E (MC against it) | octaves | linear | slab |%s\n"
              "|---|---|---|---|---|---|---|---|---|---|%s\n",
              delta_scaled ? " delta-scaled problem, exact |" : "", delta_scaled ? "---|" : "");
  for (SlabPhase ph : which) {
    for (double tau : taus) {
      const std::string path = (dir / "slab.nc").string();
      write_slab_file(path, tau, ph);
      const ImportedSlab s = import_slab(path, ph);
      const cv::core::MarchSettings m = march_for(ph, s);
      // The same slab by adding-doubling, every azimuthal mode (tests/physics/slab_solver).
      slabcheck::SlabProblem prob;
      prob.tau = tau;
      prob.phase = ph == SlabPhase::HG085 ? slabcheck::henyey_greenstein_phase(0.85) : slabcheck::approximate_mie_phase(20.0);
      for (double z : zeniths) prob.mu_extra.push_back(std::cos(z * M_PI / 180.0));
      for (double v : views) prob.mu_extra.push_back(std::cos(v * M_PI / 180.0));
      slabcheck::SlabOptions so;
      so.streams = exact_streams;
      so.azimuth_modes = 0;
      const slabcheck::SlabSolution exact = slabcheck::solve_slab(prob, so);
      for (double z : zeniths) {
        const cv::core::Sun sun = sun_at_zenith_angle(z);
        for (double v : views) {
          for (double az : azimuths) {
            if (v == 0.0 && az != azimuths.front()) continue;  // nadir has no azimuth
            const cv::core::Camera cam = oblique_camera(v, az);
            cv::core::MarchSettings mm = m;
            mm.quality.anti_alias = false;
            // The mean radiance over the pixels and its standard error.
            auto monte_carlo = [&](const cv::core::GridMeanExtinction& medium, const cv::core::MarchSettings& settings, double& se) {
              const Estimate e = mc_view_radiance(s, medium, settings, cam, z, spp, seed, max_bounces);
              se = e.se;
              return e.mean;
            };
            double se = 0.0;
            const double ref = monte_carlo(s.medium, mm, se);
            double model[3];  // the octave sum, the two-stream's diffuse light linear in angle, shaped by the slab tables
            for (int two = 0; two < 3; ++two) {
              cv::core::MarchSettings r = mm;
              r.medium.ms_two_stream = two >= 1;
              r.medium.ms_slab = two == 2;
              r.quality.octaves = 4;  // the octave sum at the scene defaults (gate on)
              r.quality.view_step_m = 5.0;
              r.quality.sun_steps = 256;
              model[two] = cv::core::render_reference(s.grid, s.medium, cam, sun, r).radiance[0].y;
            }
            const double ad = exact.radiance(std::cos(v * M_PI / 180.0), std::cos(z * M_PI / 180.0), az * M_PI / 180.0);
            std::printf("| %s | %g | %g | %g | %g | %.5f +- %.5f | %.5f (%+.1f %% +- %.1f %%) | %+.1f %% | %+.1f %% | %+.1f %% |", phase_name(ph), tau, z,
                        v, az, ref, se, ad, 100.0 * (ref / ad - 1.0), 100.0 * se / ad, 100.0 * (model[0] / ref - 1.0),
                        100.0 * (model[1] / ref - 1.0), 100.0 * (model[2] / ref - 1.0));
            if (delta_scaled) {  // the slab's HG phase is its ice (support/slab_case.hpp)
              const double g = mm.medium.ice_g, f = delta_f.empty() ? g * g : delta_f[0];
              cv::core::GridMeanExtinction scaled = s.medium;
              for (float& x : scaled.ice_per_m) x = static_cast<float>(x * (1.0 - f));
              cv::core::MarchSettings ms = mm;
              ms.medium.ice_g = (g - f) / (1.0 - f);
              double se_scaled = 0.0;
              const double l = monte_carlo(scaled, ms, se_scaled);
              std::printf(" %+.1f %% +- %.1f %% |", 100.0 * (l / ref - 1.0), 100.0 * std::hypot(se_scaled / ref, l * se / (ref * ref)));
            }
            std::printf("\n");
            std::fflush(stdout);
          }
        }
      }
    }
  }
  return 0;
}
