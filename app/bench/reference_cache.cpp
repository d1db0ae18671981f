// Reading and writing the benchmark's resumable Monte Carlo references (see reference_cache.hpp).
#include "bench/reference_cache.hpp"

#include <cstdio>
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

}  // namespace cv::bench
