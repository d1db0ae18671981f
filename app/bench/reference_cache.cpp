// Reading and writing the benchmark's resumable Monte Carlo references (see reference_cache.hpp).
#include "bench/reference_cache.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <vector>

#include "volume/volume_io.hpp"

namespace cv::bench {

namespace {
constexpr char kMagic[] = "CVREF2\n";
constexpr std::size_t kMagicLen = sizeof kMagic - 1;

void stats_words(const MonteCarloStats& s, std::uint64_t w[7]) {
  w[0] = s.paths, w[1] = s.scatterings, w[2] = s.null_collisions, w[3] = s.shadow_lookups;
  w[4] = s.truncated, w[5] = s.roulette_killed, w[6] = s.majorant_exceeded;
}
}  // namespace

std::uint64_t reference_key_hash(const std::string& text) {
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : text) h = (h ^ c) * 1099511628211ull;
  return h;
}

bool read_reference_cache(const std::string& path, std::uint64_t key, int width, int height, MonteCarloImage& img,
                          std::string* why) {
  auto fail = [&](const std::string& reason) {
    if (why) *why = reason;
    return false;
  };
  std::ifstream f(path, std::ios::binary);
  if (!f) return fail("no file");
  char magic[kMagicLen] = {};
  std::uint64_t file_key = 0, spp = 0, words[7] = {};
  std::int32_t dims[2] = {};
  f.read(magic, kMagicLen);
  f.read(reinterpret_cast<char*>(&file_key), sizeof file_key);
  f.read(reinterpret_cast<char*>(dims), sizeof dims);
  f.read(reinterpret_cast<char*>(&spp), sizeof spp);
  f.read(reinterpret_cast<char*>(words), sizeof words);
  if (!f || std::string(magic, kMagicLen) != kMagic) return fail("not a CVREF2 file");
  if (file_key != key) return fail("made for other settings (key differs)");
  if (dims[0] != width || dims[1] != height) {
    return fail("of size " + std::to_string(dims[0]) + "x" + std::to_string(dims[1]) + ", expected " +
                std::to_string(width) + "x" + std::to_string(height));
  }
  const std::size_t n = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  MonteCarloImage out;
  out.width = width, out.height = height, out.spp = spp;
  out.sum.resize(n), out.sum_sq.resize(n), out.lum_sum.resize(n), out.lum_sq.resize(n);
  f.read(reinterpret_cast<char*>(out.sum.data()), static_cast<std::streamsize>(n * sizeof(glm::dvec3)));
  f.read(reinterpret_cast<char*>(out.sum_sq.data()), static_cast<std::streamsize>(n * sizeof(glm::dvec3)));
  f.read(reinterpret_cast<char*>(out.lum_sum.data()), static_cast<std::streamsize>(n * sizeof(double)));
  f.read(reinterpret_cast<char*>(out.lum_sq.data()), static_cast<std::streamsize>(n * sizeof(double)));
  if (!f) return fail("cut short");
  if (f.peek() != std::char_traits<char>::eof()) return fail("longer than its header says");
  auto& s = out.stats;
  s.paths = words[0], s.scatterings = words[1], s.null_collisions = words[2], s.shadow_lookups = words[3];
  s.truncated = words[4], s.roulette_killed = words[5], s.majorant_exceeded = words[6];
  img = std::move(out);
  return true;
}

void write_reference_cache(const std::string& path, std::uint64_t key, const MonteCarloImage& img) {
  const std::size_t n = static_cast<std::size_t>(img.width) * static_cast<std::size_t>(img.height);
  if (img.sum.size() != n || img.sum_sq.size() != n || img.lum_sum.size() != n || img.lum_sq.size() != n) {
    throw std::invalid_argument("write_reference_cache: " + path + ": the image's sums do not match its size");
  }
  write_file_atomically(path, [&](std::FILE* f) {
    const std::int32_t dims[2] = {img.width, img.height};
    const std::uint64_t spp = img.spp;
    std::uint64_t words[7];
    stats_words(img.stats, words);
    std::fwrite(kMagic, 1, kMagicLen, f);
    std::fwrite(&key, sizeof key, 1, f);
    std::fwrite(dims, sizeof dims, 1, f);
    std::fwrite(&spp, sizeof spp, 1, f);
    std::fwrite(words, sizeof words, 1, f);
    std::fwrite(img.sum.data(), sizeof(glm::dvec3), n, f);
    std::fwrite(img.sum_sq.data(), sizeof(glm::dvec3), n, f);
    std::fwrite(img.lum_sum.data(), sizeof(double), n, f);
    std::fwrite(img.lum_sq.data(), sizeof(double), n, f);
  });
}

std::string reference_key(const StandardScene& sc, const GridMeanExtinction& medium, const MarchSettings& m,
                          const MonteCarloSettings& mc) {
  double sum = 0.0;
  for (std::size_t i = 0; i < medium.liquid_per_m.size(); ++i) sum += medium.liquid_per_m[i] * (1.0 + 1e-3 * static_cast<double>(i % 977));
  for (std::size_t i = 0; i < medium.ice_per_m.size(); ++i) sum += medium.ice_per_m[i] * (2.0 + 1e-3 * static_cast<double>(i % 983));
  const auto& g = sc.grid;
  const auto& c = sc.camera;
  char b[1024];
  std::snprintf(b, sizeof b,
                "v3 grid %d %d %d %.17g %.17g %.17g %.17g %.17g %.17g %.17g data %.17g cam %.17g %.17g %.17g %.17g %.17g "
                "%.17g %d %d sun %.17g %.17g %.17g %.17g %.17g march d%.17g hg%d ice%.17g noise%.17g mc %d %d %llu peak%d",
                g.lon_deg.count, g.lat_deg.count, g.alt_m.count, g.lon_deg.start, g.lon_deg.step, g.lat_deg.start,
                g.lat_deg.step, g.alt_m.start, g.alt_m.step, g.earth_radius_m, sum, c.lat_deg, c.lon_deg, c.alt_m,
                c.heading_deg, c.pitch_deg, c.fov_deg, c.width, c.height, sc.sun.subsolar_lat_deg, sc.sun.subsolar_lon_deg,
                sc.sun.irradiance.x, sc.sun.irradiance.y, sc.sun.irradiance.z, m.medium.droplet_diameter_um,
                m.medium.liquid_phase_hg ? 1 : 0, m.medium.ice_g, m.medium.noise_amount, mc.max_bounces, mc.roulette_after,
                static_cast<unsigned long long>(mc.seed), mc.peak_mis ? 1 : 0);
  std::string key = b;
  if (m.medium.modelled) {  // the modelled cloud's own density (data-mode keys stay as they were)
    char d[160];
    std::snprintf(d, sizeof d, " modelled detail%.17g scale%.17g fraction%zu", m.medium.detail_amount, m.medium.detail_scale_m,
                  medium.fraction.size());
    key += d;
  }
  return key;
}

ExtendedReference extend_reference(const std::string& dir, const std::string& name, const StandardScene& sc,
                                   const GridMeanExtinction& medium, const MarchSettings& m,
                                   const MonteCarloSettings& mc, int spp, double ref_error,
                                   const ErosionNoise* noise, std::FILE* log) {
  using clock = std::chrono::steady_clock;
  auto seconds_since = [](clock::time_point t) { return std::chrono::duration<double>(clock::now() - t).count(); };
  const int w = sc.camera.width, h = sc.camera.height;
  const std::uint64_t key = reference_key_hash(reference_key(sc, medium, m, mc));
  char hash[20];
  std::snprintf(hash, sizeof hash, "%016llx", static_cast<unsigned long long>(key));
  ExtendedReference out;
  out.path = (std::filesystem::path(dir) /
              ("ref_" + name + "_" + std::to_string(w) + "x" + std::to_string(h) + "_" + hash + ".cvref"))
                 .string();
  const MonteCarloRenderer mcr(sc.grid, medium, sc.camera, sc.sun, m, mc, noise);
  out.img = mcr.start();
  MonteCarloImage& img = out.img;
  std::string why;
  if (read_reference_cache(out.path, key, w, h, img, &why)) {
    std::fprintf(log, "%s: reference %s holds %llu spp (mean relative standard error %.3g)\n", name.c_str(),
                 out.path.c_str(), static_cast<unsigned long long>(img.spp), img.mean_relative_standard_error());
  } else if (why != "no file") {
    std::fprintf(log, "%s: not using %s (%s): rendering it afresh\n", name.c_str(), out.path.c_str(), why.c_str());
  }
  out.cached_spp = img.spp;
  const std::uint64_t target = static_cast<std::uint64_t>(std::max(spp, 0));
  auto converged = [&] {
    return img.spp >= target || (ref_error > 0.0 && img.spp >= 16 && img.mean_relative_standard_error() <= ref_error);
  };
  const auto t0 = clock::now();
  int chunk = 1;  // grows so that each chunk takes about 10 s; every chunk is saved
  while (!converged()) {
    const int n = static_cast<int>(std::min<std::uint64_t>(static_cast<std::uint64_t>(chunk), target - img.spp));
    const auto tc = clock::now();
    mcr.add_samples(img, n);
    const double dt = seconds_since(tc);
    write_reference_cache(out.path, key, img);
    const double per_spp = dt / n;
    chunk = static_cast<int>(std::clamp(10.0 / std::max(per_spp, 1e-6), 1.0, 4.0 * n));
    std::fprintf(log, "\r%s: Monte Carlo reference %llu/%d spp, mean rel. s.e. %.3g, %.0f s, about %.0f s to go   ",
                 name.c_str(), static_cast<unsigned long long>(img.spp), spp, img.mean_relative_standard_error(),
                 seconds_since(t0), per_spp * static_cast<double>(target - img.spp));
    std::fflush(log);
  }
  if (img.spp > out.cached_spp) {
    out.seconds = seconds_since(t0);
    std::fprintf(log, "\n%s: reference at %llu spp (%llu new, %.1f s), mean relative standard error %.3g, saved in %s\n",
                 name.c_str(), static_cast<unsigned long long>(img.spp),
                 static_cast<unsigned long long>(img.spp - out.cached_spp), out.seconds,
                 img.mean_relative_standard_error(), out.path.c_str());
  }
  return out;
}

}  // namespace cv::bench
