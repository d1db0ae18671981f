// The plane-parallel slab sweep of issue 11 (a benchmark, not a test): for each optical depth, sun
// zenith angle and phase, the slab written as a NetCDF file, imported and traced by the Monte Carlo
// reference, against the independent adding-doubling solver (tests/physics/slab_solver.hpp).
// docs/BENCHMARKS.md ("Plane-parallel slab check (issue 11)") holds a measured table and the command.
//
//   bench_slab_sweep [--spp N] [--paths N] [--phase hg|mie|both] [--tau 1,2,...] [--zenith 0,30,...]
//                    [--seed S]
//
// --spp: camera samples for the nadir radiance (2 pixels, one per thread); --paths: beams for the
// analog plane albedo. Both are scaled down by 10 / tau above tau 10, so each row costs about the same.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "bench/bench_args.hpp"
#include "physics/slab_solver.hpp"
#include "support/scratch_dir.hpp"
#include "support/slab_case.hpp"

namespace {
using namespace cv::test::slab;
constexpr double kPi = 3.14159265358979323846;

}  // namespace

int main(int argc, char** argv) {
  int spp = 100000, paths = 100000;
  std::uint64_t seed = 11;
  std::string phases = "both";
  std::vector<double> taus{1, 2, 5, 10, 20, 50, 100}, zeniths{0, 30, 60, 75};
  namespace ba = cv::bench_args;
  const int code = ba::parse("bench_slab_sweep",
                             "usage: bench_slab_sweep [--spp N] [--paths N] [--phase hg|mie|both] [--tau 1,2,...] [--zenith 0,30,...]\n"
                             "                        [--seed S]\n"
                             "  the Monte Carlo on the imported slab against the adding-doubling solver: nadir radiance\n"
                             "  (--spp camera samples) and plane albedo (--paths beams), both fewer by 10 / tau above tau 10\n",
                             argc, argv,
                             {ba::integer("--spp", spp), ba::integer("--paths", paths), ba::one_of("--phase", phases, {"hg", "mie", "both"}),
                              ba::numbers("--tau", taus), ba::numbers("--zenith", zeniths), ba::seed("--seed", seed)});
  if (code >= 0) return code;
  // The process's own folder (removed at exit): two runs at once never share a file.
  const std::filesystem::path dir = cv::test_support::scratch_dir();
  std::vector<SlabPhase> which;
  if (phases == "hg" || phases == "both") which.push_back(SlabPhase::HG085);
  if (phases == "mie" || phases == "both") which.push_back(SlabPhase::Mie);
  std::printf("| phase | tau | sun zenith | solver I/E at nadir | Monte Carlo I/E | z | solver plane albedo | Monte Carlo plane albedo | z | MC R + T | MC s |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (SlabPhase ph : which) {
    const slabcheck::PhaseFunction phase =
        ph == SlabPhase::HG085 ? slabcheck::henyey_greenstein_phase(0.85) : slabcheck::approximate_mie_phase(20.0);
    // The solver at N and 2N streams per hemisphere: the difference is its stated uncertainty.
    const int n1 = ph == SlabPhase::HG085 ? 32 : 128;
    for (double tau : taus) {
      const std::string path = (dir / "slab.nc").string();
      write_slab_file(path, tau, ph);
      const ImportedSlab s = import_slab(path, ph);
      const cv::core::MarchSettings m = march_for(ph, s);
      slabcheck::SlabProblem p;
      p.tau = tau;
      p.phase = phase;
      p.mu_extra = {1.0};
      for (double z : zeniths) p.mu_extra.push_back(std::cos(z * kPi / 180.0));
      slabcheck::SlabOptions o1, o2;
      o1.streams = n1;
      o2.streams = 2 * n1;
      const slabcheck::SlabSolution a = solve_slab(p, o1), b = solve_slab(p, o2);
      const double scale = tau > 10.0 ? 10.0 / tau : 1.0;
      for (double z : zeniths) {
        const double mu0 = std::cos(z * kPi / 180.0);
        const double i_sol = a.nadir_radiance(mu0), i_err = std::abs(a.nadir_radiance(mu0) - b.nadir_radiance(mu0));
        const double a_sol = a.plane_albedo(mu0), a_err = std::abs(a.plane_albedo(mu0) - b.plane_albedo(mu0));
        const Estimate e = mc_nadir_radiance(s, m, z, std::max(1000, static_cast<int>(spp * scale)), seed);
        const AnalogFluxes f = mc_analog_fluxes(s, m, z, std::max(1000, static_cast<int>(paths * scale)), seed + 1);
        std::printf("| %s | %g | %g | %.5f +- %.1e | %.5f +- %.5f | %+.2f | %.5f +- %.1e | %.5f +- %.5f | %+.2f | %.6f (%llu lost) | %.1f |\n",
                    phase_name(ph), tau, z, i_sol, i_err, e.mean, e.se, (e.mean - i_sol) / std::hypot(e.se, i_err), a_sol, a_err,
                    f.albedo(), f.albedo_se(), (f.albedo() - a_sol) / std::hypot(f.albedo_se(), a_err),
                    f.albedo() + f.transmission(), static_cast<unsigned long long>(f.lost), e.seconds + f.seconds);
        std::fflush(stdout);
      }
    }
  }
  return 0;
}
