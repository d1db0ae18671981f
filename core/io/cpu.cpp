// CPUID and XCR0, read once.
#include "io/cpu.hpp"

#include <atomic>
#include <cstdlib>
#include <cstring>

#if defined(__x86_64__) && defined(__GNUC__)
#include <cpuid.h>
#endif

namespace cv::core {
namespace {
// CPUID leaf 1's ECX bits (27 OSXSAVE, 28 AVX, 29 F16C) all set in `want`, and the SSE and YMM
// state enabled in XCR0. Read here rather than with __builtin_cpu_supports, whose "f16c" clang 14
// (the fuzz build) does not know.
bool cpu_has(unsigned want) {
#if defined(__x86_64__) && defined(__GNUC__)
  unsigned a = 0, b = 0, c = 0, d = 0;
  if (!__get_cpuid(1, &a, &b, &c, &d)) return false;
  if ((c & want) != want) return false;
  unsigned lo = 0, hi = 0;
  __asm__ volatile("xgetbv" : "=a"(lo), "=d"(hi) : "c"(0u));
  return (lo & 0x6u) == 0x6u;
#else
  (void)want;
  return false;
#endif
}
constexpr unsigned kOsxsave = 1u << 27, kAvx = 1u << 28, kF16c = 1u << 29;

std::atomic<bool> forced_baseline{false};

bool environment_asks_baseline() {
  static const bool asked = [] {
    const char* v = std::getenv("CLOUDVIEWER_CPU");
    return v && std::strcmp(v, "baseline") == 0;
  }();
  return asked;
}
}  // namespace

void set_baseline_cpu(bool on) { forced_baseline.store(on, std::memory_order_relaxed); }

bool baseline_cpu() { return environment_asks_baseline() || forced_baseline.load(std::memory_order_relaxed); }

bool cpu_has_avx() {
  static const bool has = cpu_has(kOsxsave | kAvx);
  return has && !baseline_cpu();
}

bool cpu_has_avx_f16c() {
  static const bool has = cpu_has(kOsxsave | kAvx | kF16c);
  return has && !baseline_cpu();
}

}  // namespace cv::core
