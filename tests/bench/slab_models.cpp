// Benchmark (not a test): the raymarcher's multiple-scattering models on the plane-parallel slabs of
// issue 11, against the independent adding-doubling solver (tests/physics/slab_solver.hpp): nadir
// reflected radiance per unit irradiance from the CPU kernel (the GPU runs the same kernel), the
// octave sum at the scene defaults (4 octaves, gate on) and the two-stream source, as the relative
// error against the solver. The slab is written as NetCDF and imported as in the slab check.
// --ground-albedo A puts a Lambertian ground of albedo A under the slab (the globe drawn, no air): the
// solver's radiance then takes the ground's light by the adding of a Lambertian surface
// (SlabSolution::nadir_radiance_over_ground). --ground-map A draws the globe's ground from a uniform
// map of albedo A (all land) while the scene's constant ground_albedo, which the two-stream column
// takes for its ground, stays at --ground-albedo's value (else the scene default): the renderer's
// case of a map whose ground differs from the constant. The solver's ground is then A.
//   bench_slab_models [--phase hg|mie|both] [--tau 1,2,...] [--zenith 0,30,...] [--octaves N] [--ground-albedo A]
//                     [--ground-map A]
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
  std::string phases = "both";
  int octaves = 4;
  std::vector<double> grounds{0.0}, maps;
  std::vector<double> taus{1, 2, 5, 10, 20, 50, 100}, zeniths{0, 30, 60};
  namespace ba = cv::bench_args;
  const int code = ba::parse("bench_slab_models",
                             "usage: bench_slab_models [--phase hg|mie|both] [--tau 1,2,...] [--zenith 0,30,...] [--octaves N] [--ground-albedo A]\n"
                             "                         [--ground-map A]\n"
                             "  the octave sum and the two-stream source against the adding-doubling solver at nadir\n",
                             argc, argv,
                             {ba::one_of("--phase", phases, {"hg", "mie", "both"}), ba::numbers("--tau", taus),
                              ba::numbers("--zenith", zeniths), ba::integer("--octaves", octaves),
                              ba::numbers("--ground-albedo", grounds), ba::numbers("--ground-map", maps)});
  if (code >= 0) return code;
  if (grounds.size() != 1 || !(grounds[0] >= 0.0 && grounds[0] < 1.0)) {
    std::fprintf(stderr, "bench_slab_models: --ground-albedo: expected one albedo in 0..1 (below 1)\n");
    return 2;
  }
  if (maps.size() > 1 || (maps.size() == 1 && !(maps[0] >= 0.0 && maps[0] < 1.0))) {
    std::fprintf(stderr, "bench_slab_models: --ground-map: expected one albedo in 0..1 (below 1)\n");
    return 2;
  }
  const bool mapped = !maps.empty();
  // The constant the column takes: --ground-albedo's, else (with a map) the scene default.
  const double constant = grounds[0] > 0.0 || !mapped ? grounds[0] : cv::core::MarchSettings{}.medium.ground_albedo.y;
  const double ground = mapped ? maps[0] : grounds[0];  // what the solver's ground is
  cv::core::AlbedoMap map;
  if (mapped) {
    map.width = 4, map.height = 2;
    map.rgba.assign(4 * 4 * 2, static_cast<float>(maps[0]));
    for (std::size_t i = 3; i < map.rgba.size(); i += 4) map.rgba[i] = 0.0f;  // all land
    std::printf("ground: a uniform map of albedo %g; the scene's constant (the column's ground) %g\n\n", maps[0], constant);
  }
  // The process's own folder (removed at exit): two runs at once never share a file.
  const std::filesystem::path dir = cv::test_support::scratch_dir();
  std::vector<SlabPhase> which;
  if (phases == "hg" || phases == "both") which.push_back(SlabPhase::HG085);
  if (phases == "mie" || phases == "both") which.push_back(SlabPhase::Mie);
  std::printf("| phase | tau | sun zenith | solver I/E at nadir | octaves (%d, gate) | two-stream linear | two-stream slab |\n|---|---|---|---|---|---|---|\n",
              octaves);
  for (SlabPhase ph : which) {
    const slabcheck::PhaseFunction phase =
        ph == SlabPhase::HG085 ? slabcheck::henyey_greenstein_phase(0.85) : slabcheck::approximate_mie_phase(20.0);
    for (double tau : taus) {
      const std::string path = (dir / "slab.nc").string();
      write_slab_file(path, tau, ph);
      const ImportedSlab s = import_slab(path, ph);
      cv::core::MarchSettings m = march_for(ph, s);
      m.quality.octaves = octaves;
      if (constant > 0.0 || mapped) {
        m.features.globe = true;
        m.medium.ground_albedo = glm::dvec3(constant);
      }
      slabcheck::SlabProblem p;
      p.tau = tau;
      p.phase = phase;
      p.mu_extra = {1.0};
      for (double z : zeniths) p.mu_extra.push_back(std::cos(z * kPi / 180.0));
      slabcheck::SlabOptions o;
      o.streams = ph == SlabPhase::HG085 ? 32 : 128;
      const slabcheck::SlabSolution sol = solve_slab(p, o);
      for (double z : zeniths) {
        const double mu0 = std::cos(z * kPi / 180.0);
        const double ref = sol.nadir_radiance_over_ground(mu0, ground);
        cv::core::MarchSettings two = m, slab = m;
        two.medium.ms_two_stream = slab.medium.ms_two_stream = true;
        two.medium.ms_slab = false;
        slab.medium.ms_slab = true;
        const cv::core::AlbedoMap* on = mapped ? &map : nullptr;
        const double a = march_nadir_radiance(s, m, z, on), b = march_nadir_radiance(s, two, z, on), c = march_nadir_radiance(s, slab, z, on);
        std::printf("| %s | %g | %g | %.5f | %+.1f %% | %+.1f %% | %+.1f %% |\n", phase_name(ph), tau, z, ref, 100.0 * (a / ref - 1.0),
                    100.0 * (b / ref - 1.0), 100.0 * (c / ref - 1.0));
        std::fflush(stdout);
      }
    }
  }
  return 0;
}
