// Times the importer alone (open, then load and convert every time step) without writing output,
// to separate conversion cost from the cost of writing the volume.
//
//   bench_import_only FILE.nc [--half] [--rounds N]
//
// --half holds the steps as half floats, as `cloudviewer import` does for its default float16
// output; --rounds converts every step N times and prints the least time per step of each round,
// which on a noisy machine compares builds better than one wall time.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>

#include "importer.hpp"

int main(int argc, char** argv) {
  const char* path = nullptr;
  bool half = false;
  int rounds = 1;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--half") == 0) half = true;
    else if (std::strcmp(argv[i], "--rounds") == 0 && i + 1 < argc) rounds = std::atoi(argv[++i]);
    else if (!path && argv[i][0] != '-') path = argv[i];
    else path = nullptr, rounds = 0;
  }
  if (!path || rounds < 1) {
    std::fprintf(stderr, "usage: bench_import_only FILE.nc [--half] [--rounds N]\n");
    return 2;
  }
  using clock = std::chrono::steady_clock;
  const auto t0 = clock::now();
  cv::importers::ImportOptions o;
  o.cache_steps = 1;
  o.half_fields = half;
  auto vol = cv::importers::import_file(path, o);
  const double open_s = std::chrono::duration<double>(clock::now() - t0).count();
  double steps_s = 0, least = std::numeric_limits<double>::infinity();
  for (int r = 0; r < rounds; ++r) {
    double round_least = std::numeric_limits<double>::infinity();
    for (std::size_t t = 0; t < vol.times.size(); ++t) {
      // With one step cached, asking for a step other than the last one loaded converts it again.
      const auto a = clock::now();
      vol.step(t);
      const double s = std::chrono::duration<double>(clock::now() - a).count();
      steps_s += s;
      if (r > 0 || t > 0) round_least = std::min(round_least, s);  // the first step's fresh pages apart
    }
    least = std::min(least, round_least);
    if (rounds > 1 && vol.times.size() > 1) std::printf("round %d: least %.3f s per step\n", r + 1, round_least);
  }
  const double n = static_cast<double>(vol.times.size()) * rounds;
  // With one step, a later round finds it in the cache: no least time to give.
  char least_text[32] = "n/a (one step)";
  if (vol.times.size() > 1) std::snprintf(least_text, sizeof least_text, "%.3f s", least);
  std::printf("bench_import_only: open %.2f s, %zu steps x %d rounds loaded and converted in %.2f s (%.2f s per step, least %s)\n",
              open_s, vol.times.size(), rounds, steps_s, steps_s / n, least_text);
  return 0;
}
