// Times the importer alone (open, then load and convert every time step) without writing output,
// to separate conversion cost from the cost of writing the volume.
#include <chrono>
#include <cstdio>

#include "importer.hpp"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: bench_import_only FILE.nc\n");
    return 2;
  }
  using clock = std::chrono::steady_clock;
  const auto t0 = clock::now();
  cv::importers::ImportOptions o;
  o.cache_steps = 1;
  auto vol = cv::importers::import_file(argv[1], o);
  const double open_s = std::chrono::duration<double>(clock::now() - t0).count();
  double steps_s = 0;
  for (std::size_t t = 0; t < vol.times.size(); ++t) {
    const auto a = clock::now();
    vol.step(t);
    steps_s += std::chrono::duration<double>(clock::now() - a).count();
  }
  std::printf("bench_import_only: open %.2f s, %zu steps loaded and converted in %.2f s (%.2f s per step)\n", open_s,
              vol.times.size(), steps_s, steps_s / static_cast<double>(vol.times.size()));
  return 0;
}
