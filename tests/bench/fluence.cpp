// The two-stream source's light per node against a Monte Carlo's, on the standard scenes: a local
// truth for the source (the march's image error mixes the source with the slab's shape and the
// view). The quantity is the fluence per unit irradiance, phi / E: the model's is its delta-scaled
// beam plus 4 pi I0 (delta scaling keeps the total fluence, beam and diffuse together, of the true
// problem to its order), the Monte Carlo's counts every photon, unscattered or not, by the collision
// estimator of delta tracking in the grid's trilinear medium, the droplets and ice as Henyey-
// Greenstein phases of the source's own g (the source knows no more of the phase than g). Photons
// enter through the grid's top (uniform in area, weighted by the sun's cosine there), so a sun low
// enough to light the grid through its sides is not measured; clouds only (no ground, no air).
// usage: bench_fluence [--photons N] [--levels] [--columns] [--box F] [SCENE...]
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include "bench/bench_args.hpp"
#include "bench/standard_scenes.hpp"
#include "geo/geodesy.hpp"
#include "kernel/ms_source.hpp"
#include "kernel/prepared_volume.hpp"
#include "volume/grid_mean.hpp"

namespace {
constexpr double kPi = 3.14159265358979323846;

// splitmix64 (a fixed sequence per photon, whatever the thread count).
struct Rng {
  std::uint64_t s;
  double uniform() {
    std::uint64_t z = (s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return (static_cast<double>((z ^ (z >> 31)) >> 11) + 0.5) * 0x1.0p-53;
  }
};

// A direction from the Henyey-Greenstein phase of g about d.
glm::dvec3 scatter_hg(const glm::dvec3& d, double g, Rng& rng) {
  const double u = rng.uniform();
  double mu;
  if (std::abs(g) < 1e-6) {
    mu = 2.0 * u - 1.0;
  } else {
    const double s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u);
    mu = std::clamp((1.0 + g * g - s * s) / (2.0 * g), -1.0, 1.0);
  }
  const double phi = 2.0 * kPi * rng.uniform(), sn = std::sqrt(std::max(1.0 - mu * mu, 0.0));
  const glm::dvec3 a = std::abs(d.x) < 0.9 ? glm::dvec3(1.0, 0.0, 0.0) : glm::dvec3(0.0, 1.0, 0.0);
  const glm::dvec3 t1 = glm::normalize(glm::cross(d, a)), t2 = glm::cross(d, t1);
  return glm::normalize(mu * d + sn * (std::cos(phi) * t1 + std::sin(phi) * t2));
}
}  // namespace

int main(int argc, char** argv) {
  int photons = 400000;
  std::vector<double> boxes{1.0};
  bool levels = false, by_column = false;
  std::vector<std::string> scenes;
  namespace ba = cv::bench_args;
  const int code = ba::parse("bench_fluence",
                             "usage: bench_fluence [--photons N] [--levels] [--columns] [--box F] [SCENE...]\n"
                             "  the two-stream source's fluence per node (its scaled beam plus 4 pi I0) against a Monte\n"
                             "  Carlo's (collision estimator, Henyey-Greenstein phases of the source's g), clouds only\n"
                             "  --photons N  photons per scene (default 400000)\n"
                             "  --levels     print each level's sums, not only the scene's\n"
                             "  --columns    and the sums over columns in bins of their optical depth\n"
                             "  --box F      count the collisions within F of a cell around each node (0 < F <= 1, default 1):\n"
                             "               a smaller box measures nearer the node where the light curves across a cell\n",
                             argc, argv, {ba::integer("--photons", photons), ba::flag("--levels", levels), ba::flag("--columns", by_column), ba::numbers("--box", boxes)}, &scenes);
  if (code >= 0) return code;
  if (boxes.size() != 1 || !(boxes[0] > 0.0 && boxes[0] <= 1.0)) {
    std::fprintf(stderr, "bench_fluence: --box: expected one fraction of a cell in (0, 1]\n");
    return 2;
  }
  const double box = boxes[0];
  if (photons < 1000) {
    std::fprintf(stderr, "bench_fluence: --photons: found %d, expected at least 1000\n", photons);
    return 2;
  }
  if (scenes.empty()) {
    for (const auto& n : cv::bench::standard_scene_names()) if (n != "clear_sky") scenes.push_back(n);
  }
  const std::vector<std::string> known = cv::bench::standard_scene_names();
  for (const std::string& name : scenes) {
    if (std::find(known.begin(), known.end(), name) == known.end()) {
      std::string list;
      for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
      std::fprintf(stderr, "bench_fluence: unknown scene '%s', expected one of: %s\n", name.c_str(), list.c_str());
      return 2;
    }
  }
  std::printf("%-14s %9s | %-34s | %-34s\n", "scene", "photons", "all cloudy nodes: MC  model  ratio", "sigma-weighted: MC  model  ratio");
  for (const std::string& name : scenes) {
    cv::bench::StandardScene sc;
    try {
      sc = cv::bench::standard_scene(name, 32, 18);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "bench_fluence: %s\n", e.what());
      return 2;
    }
    const cv::core::VolumeGrid& g = sc.grid;
    const cv::core::GridMeanExtinction ext = cv::core::grid_mean_extinction(g, sc.data);
    cv::core::MarchSettings m = sc.march;
    m.features.atmosphere = m.features.globe = false;
    m.medium.ambient = 0.0, m.medium.noise_amount = 0.0;
    m.medium.ms_two_stream = m.medium.ms_slab = true;
    if (!(m.medium.droplet_diameter_um > 0.0)) m.medium.droplet_diameter_um = 20.0;
    const glm::dvec3 to_sun = glm::normalize(cv::geo::sphere_to_ecef({sc.sun.subsolar_lat_deg, sc.sun.subsolar_lon_deg, 0.0}, 1.0));
    const cv::core::MsSourceKey key = cv::core::ms_source_key(m, to_sun);
    const cv::core::MsSource src = cv::core::build_ms_source(cv::core::prepare_volume(g, ext), key);
    const int nx = g.lon_deg.count, ny = g.lat_deg.count, nz = g.alt_m.count;
    const std::size_t n = g.points();
    auto liquid = [&](std::size_t a) { return ext.liquid_per_m.empty() ? 0.0 : std::max(double(ext.liquid_per_m[a]), 0.0); };
    auto ice = [&](std::size_t a) { return ext.ice_per_m.empty() ? 0.0 : std::max(double(ext.ice_per_m[a]), 0.0); };
    std::vector<float> scaled(n);
    double majorant = 0.0;
    for (std::size_t a = 0; a < n; ++a) {
      scaled[a] = static_cast<float>(liquid(a) * (1.0 - key.liquid_g * key.liquid_g) + ice(a) * (1.0 - key.ice_g * key.ice_g));
      majorant = std::max(majorant, liquid(a) + ice(a));
    }
    const std::vector<float> beam = cv::core::sun_beam_field(g, scaled, to_sun, nz - 1);
    if (!(majorant > 0.0)) continue;
    // The medium at (lon, lat, alt): trilinear in index space, clear outside (longitudes wrap on a
    // global grid).
    const bool wraps = g.wraps_lon();
    auto index_of = [&](double lon, double lat, double alt, double& fi, double& fj, double& fk) {
      double dl = std::fmod(lon - g.lon_deg.start, 360.0);  // east of the grid's first longitude, 0..360
      if (dl < 0.0) dl += 360.0;
      if (g.lon_deg.step < 0.0) dl -= 360.0;
      fi = dl / g.lon_deg.step;
      if (wraps) {
        fi = std::fmod(fi, double(nx));
        if (fi < 0.0) fi += nx;
      }
      fj = (lat - g.lat_deg.start) / g.lat_deg.step;
      fk = (alt - g.alt_m.start) / g.alt_m.step;
      return (wraps || (fi >= 0.0 && fi <= nx - 1)) && fj >= 0.0 && fj <= ny - 1 && fk >= 0.0 && fk <= nz - 1;
    };
    auto medium = [&](double fi, double fj, double fk, double& sl, double& si) {
      const int i0 = std::min(static_cast<int>(fi), nx - 1), j0 = std::min(static_cast<int>(fj), ny - 1), k0 = std::min(static_cast<int>(fk), nz - 1);
      const int i1 = wraps ? (i0 + 1) % nx : std::min(i0 + 1, nx - 1), j1 = std::min(j0 + 1, ny - 1), k1 = std::min(k0 + 1, nz - 1);
      const double wi = fi - i0, wj = fj - j0, wk = fk - k0;
      sl = si = 0.0;
      for (int c = 0; c < 8; ++c) {
        const int i = c & 1 ? i1 : i0, j = c & 2 ? j1 : j0, k = c & 4 ? k1 : k0;
        const double w = (c & 1 ? wi : 1.0 - wi) * (c & 2 ? wj : 1.0 - wj) * (c & 4 ? wk : 1.0 - wk);
        const std::size_t a = g.index(i, j, k);
        sl += w * liquid(a), si += w * ice(a);
      }
    };
    // Launch: uniform over the grid's top surface (lon uniform, sin(lat) uniform), weight mu0 there
    // times the surface's area over the photons: a tally is then the power per unit irradiance.
    const double R = g.earth_radius_m, top = g.alt_m.at(nz - 1), r_top = R + top;
    const double d2r = kPi / 180.0;
    const double lon0 = g.lon_deg.start, lon_span = wraps ? 360.0 : g.lon_deg.step * (nx - 1);
    const double lat_lo = std::min(g.lat_deg.at(0), g.lat_deg.at(ny - 1)), lat_hi = std::max(g.lat_deg.at(0), g.lat_deg.at(ny - 1));
    const double s_lo = std::sin(lat_lo * d2r), s_hi = std::sin(lat_hi * d2r);
    const double area = r_top * r_top * lon_span * d2r * (s_hi - s_lo);
    const unsigned threads = std::max(1u, std::min(8u, std::thread::hardware_concurrency()));
    std::vector<std::vector<double>> tallies(threads, std::vector<double>(n, 0.0));
    std::atomic<long long> next{0};
    const long long total = photons;
    auto work = [&](unsigned t) {
      std::vector<double>& tally = tallies[t];
      for (;;) {
        const long long p0 = next.fetch_add(4096);
        if (p0 >= total) break;
        for (long long p = p0; p < std::min(total, p0 + 4096); ++p) {
          Rng rng{0x5EEDull * 1000003ull + static_cast<std::uint64_t>(p) * 0x9E3779B97F4A7C15ull};
          const double lon = lon0 + lon_span * rng.uniform(), lat = std::asin(s_lo + (s_hi - s_lo) * rng.uniform()) / d2r;
          glm::dvec3 x = cv::geo::sphere_to_ecef({lat, lon, top}, R);
          const double mu0 = glm::dot(glm::normalize(x), to_sun);
          if (!(mu0 > 0.0)) continue;
          const double w = mu0 * area / double(photons);
          glm::dvec3 d = -to_sun;
          for (int events = 0; events < 100000; ++events) {
            x += d * (-std::log(rng.uniform()) / majorant);
            const cv::geo::Geodetic q = cv::geo::ecef_to_sphere(x, R);
            if (q.alt_m > top || q.alt_m < 0.0) break;  // out through the top, or to the (black) ground
            double fi, fj, fk;
            if (!index_of(q.lon_deg, q.lat_deg, q.alt_m, fi, fj, fk)) {
              if (q.alt_m < g.alt_m.at(0) && !(fj < 0.0 || fj > ny - 1 || (!wraps && (fi < 0.0 || fi > nx - 1)))) continue;  // below the grid
              break;  // out through a side: clear air beyond
            }
            const std::size_t a = g.index(std::clamp(static_cast<int>(std::lround(fi)) % nx, 0, nx - 1), std::clamp(static_cast<int>(std::lround(fj)), 0, ny - 1),
                                          std::clamp(static_cast<int>(std::lround(fk)), 0, nz - 1));
            if (std::abs(fi - std::round(fi)) <= 0.5 * box && std::abs(fj - std::round(fj)) <= 0.5 * box && std::abs(fk - std::round(fk)) <= 0.5 * box) tally[a] += w;
            double sl, si;
            medium(fi, fj, fk, sl, si);
            if (rng.uniform() * majorant >= sl + si) continue;  // a null collision
            d = scatter_hg(d, rng.uniform() * (sl + si) < sl ? key.liquid_g : key.ice_g, rng);
          }
        }
      }
    };
    std::vector<std::thread> pool;
    for (unsigned t = 0; t < threads; ++t) pool.emplace_back(work, t);
    for (auto& th : pool) th.join();
    // Per node: the Monte Carlo's fluence per unit irradiance, its tallies over majorant x the
    // node's cell volume; the model's, beam + 4 pi I0. Sums over nodes with cloud, per level and
    // all, plain and weighted by the extinction (what the march's in-scatter weighs).
    double all[4] = {0.0, 0.0, 0.0, 0.0};
    for (int k = 0; k < nz; ++k) {
      double lv[4] = {0.0, 0.0, 0.0, 0.0};
      const double r = R + g.alt_m.at(k);
      for (int j = 0; j < ny; ++j) {
        const double vol = r * r * std::cos(g.lat_deg.at(j) * d2r) * std::abs(g.lon_deg.step * d2r) * std::abs(g.lat_deg.step * d2r) *
                           std::abs(g.alt_m.step) * ((k == 0 || k == nz - 1) ? 0.5 : 1.0) * ((j == 0 || j == ny - 1) ? 0.5 : 1.0);
        for (int i = 0; i < nx; ++i) {
          const std::size_t a = g.index(i, j, k);
          const double s = liquid(a) + ice(a);
          if (!(s > 0.0)) continue;
          double mc = 0.0;
          for (const auto& tl : tallies) mc += tl[a];
          mc /= majorant * vol * box * box * box * ((!wraps && (i == 0 || i == nx - 1)) ? 0.5 : 1.0);
          const double model = double(beam[a]) + 4.0 * kPi * double(src.i0[a]);
          lv[0] += mc, lv[1] += model, lv[2] += s * mc, lv[3] += s * model;
        }
      }
      for (int q = 0; q < 4; ++q) all[q] += lv[q];
      if (levels && lv[0] + lv[1] > 0.0) {
        std::printf("  level %2d (%6.0f m): %11.4g %11.4g %6.3f | %11.4g %11.4g %6.3f\n", k, g.alt_m.at(k), lv[0], lv[1], lv[1] / lv[0], lv[2], lv[3],
                    lv[3] / lv[2]);
      }
    }
    if (!(all[0] > 0.0)) {
      std::printf("%-14s %9d | no photon reached the cloud through the grid's top (a sun low enough to light it through its sides)\n",
                  name.c_str(), photons);
      continue;
    }
    std::printf("%-14s %9d | %11.4g %11.4g %6.3f | %11.4g %11.4g %6.3f\n", name.c_str(), photons, all[0], all[1], all[1] / all[0], all[2], all[3],
                all[3] / all[2]);
    if (by_column) {
      // The same sums over the nodes of columns in bins of their optical depth.
      const double edges[] = {0.0, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 1e30};
      double bins[8][4] = {};
      for (int j = 0; j < ny; ++j) {
        for (int i = 0; i < nx; ++i) {
          double tau = 0.0;
          for (int k = 0; k + 1 < nz; ++k)
            tau += 0.5 * (liquid(g.index(i, j, k)) + ice(g.index(i, j, k)) + liquid(g.index(i, j, k + 1)) + ice(g.index(i, j, k + 1))) * std::abs(g.alt_m.step);
          int b = 0;
          while (b < 7 && tau >= edges[b + 1]) ++b;
          for (int k = 0; k < nz; ++k) {
            const std::size_t a = g.index(i, j, k);
            const double s = liquid(a) + ice(a);
            if (!(s > 0.0)) continue;
            const double r = R + g.alt_m.at(k);
            const double vol = r * r * std::cos(g.lat_deg.at(j) * d2r) * std::abs(g.lon_deg.step * d2r) * std::abs(g.lat_deg.step * d2r) *
                               std::abs(g.alt_m.step) * ((k == 0 || k == nz - 1) ? 0.5 : 1.0) * ((j == 0 || j == ny - 1) ? 0.5 : 1.0) *
                               ((!wraps && (i == 0 || i == nx - 1)) ? 0.5 : 1.0);
            double mc = 0.0;
            for (const auto& tl : tallies) mc += tl[a];
            mc /= majorant * vol * box * box * box;
            const double model = double(beam[a]) + 4.0 * kPi * double(src.i0[a]);
            bins[b][0] += mc, bins[b][1] += model, bins[b][2] += s * mc, bins[b][3] += s * model;
          }
        }
      }
      for (int b = 0; b < 8; ++b) {
        if (!(bins[b][0] > 0.0)) continue;
        std::printf("  columns %5.1f-%5.1f: %11.4g %11.4g %6.3f | %11.4g %11.4g %6.3f\n", edges[b], b == 7 ? 1e3 : edges[b + 1], bins[b][0], bins[b][1],
                    bins[b][1] / bins[b][0], bins[b][2], bins[b][3], bins[b][3] / bins[b][2]);
      }
    }
    std::fflush(stdout);
  }
  return 0;
}
