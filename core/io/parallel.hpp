// Splitting a loop over [0, n) into contiguous ranges run on the machine's cores.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdlib>
#include <exception>
#include <thread>
#include <vector>

namespace cv::core {

// The threads to use: one per hardware core, or CLOUDVIEWER_THREADS when set to a positive number
// (`cloudviewer` refuses any other value before it starts).
inline unsigned worker_count() {
  unsigned hw = std::max(1u, std::thread::hardware_concurrency());
  if (const char* env = std::getenv("CLOUDVIEWER_THREADS"); env && std::atoi(env) > 0) hw = static_cast<unsigned>(std::atoi(env));
  return hw;
}

// Calls fn(begin, end, part) for `parts` contiguous ranges covering [0, n), one per thread (the
// caller's thread runs the first), with at most worker_count() parts and none shorter than
// `grain` (so small loops stay on one thread). The first exception thrown is rethrown after all
// parts end. Returns the number of parts.
template <typename F>
unsigned parallel_ranges(std::size_t n, std::size_t grain, F&& fn) {
  const std::size_t most = grain ? std::max<std::size_t>(1, n / grain) : n;
  const unsigned parts = static_cast<unsigned>(std::max<std::size_t>(1, std::min<std::size_t>(worker_count(), most)));
  if (parts == 1) {
    fn(std::size_t(0), n, 0u);
    return 1;
  }
  std::vector<std::exception_ptr> errors(parts);
  auto run = [&](unsigned p) {
    try {
      fn(n * p / parts, n * (p + 1) / parts, p);
    } catch (...) {
      errors[p] = std::current_exception();
    }
  };
  std::vector<std::thread> threads;
  threads.reserve(parts - 1);
  for (unsigned p = 1; p < parts; ++p) threads.emplace_back(run, p);
  run(0);
  for (auto& t : threads) t.join();
  for (auto& e : errors) {
    if (e) std::rethrow_exception(e);
  }
  return parts;
}

}  // namespace cv::core
