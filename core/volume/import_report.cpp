// The import report: collection, text and JSON.
#include "volume/import_report.hpp"

#include "io/parallel.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <type_traits>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>

#include "io/cpu.hpp"
#endif

namespace cv::core {

void ValueStats::add(double v) {
  if (!std::isfinite(v)) {
    ++missing;
    return;
  }
  min = std::min(min, v);
  max = std::max(max, v);
  ++count;
}

namespace {
// Adds a range's finite values (a value that is not finite, |x| <= max being false for NaN and
// infinity, is counted as missing). A global step holds 10^8 values per field, and the compiler
// does not vectorise a floating-point min/max reduction without fast-math (which would let it drop
// the finiteness test), so the x86-64 loops are written with SSE2, four floats or two doubles at a
// time; other processors take the scalar loop.
template <typename T>
void add_scalar(const T* v, std::size_t n, T& lo, T& hi, std::size_t& finite) {
  const T inf = std::numeric_limits<T>::infinity(), big = std::numeric_limits<T>::max();
  for (std::size_t i = 0; i < n; ++i) {
    const T x = v[i];
    const bool ok = std::abs(x) <= big;
    lo = std::min(lo, ok ? x : inf);
    hi = std::max(hi, ok ? x : -inf);
    finite += ok ? 1 : 0;
  }
}

#if defined(__SSE2__)
void add_simd(const float* v, std::size_t n, float& lo, float& hi, std::size_t& finite) {
  const __m128 inf = _mm_set1_ps(std::numeric_limits<float>::infinity()), ninf = _mm_set1_ps(-std::numeric_limits<float>::infinity());
  const __m128 big = _mm_set1_ps(std::numeric_limits<float>::max());
  const __m128 abs_mask = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
  __m128 vlo = inf, vhi = ninf;
  std::size_t i = 0;
  // The count in 32-bit lanes, flushed to the total every 2^24 values (well before a lane overflows).
  while (n - i >= 4) {
    __m128i count = _mm_setzero_si128();
    const std::size_t end = i + std::min<std::size_t>((n - i) / 4 * 4, std::size_t(1) << 24);
    for (; i < end; i += 4) {
      const __m128 x = _mm_loadu_ps(v + i);
      const __m128 ok = _mm_cmple_ps(_mm_and_ps(x, abs_mask), big);  // false for NaN and infinity
      vlo = _mm_min_ps(vlo, _mm_or_ps(_mm_and_ps(ok, x), _mm_andnot_ps(ok, inf)));
      vhi = _mm_max_ps(vhi, _mm_or_ps(_mm_and_ps(ok, x), _mm_andnot_ps(ok, ninf)));
      count = _mm_sub_epi32(count, _mm_castps_si128(ok));  // ok lanes are -1
    }
    alignas(16) std::uint32_t c[4];
    _mm_store_si128(reinterpret_cast<__m128i*>(c), count);
    finite += std::size_t(c[0]) + c[1] + c[2] + c[3];
  }
  alignas(16) float l[4], h[4];
  _mm_store_ps(l, vlo);
  _mm_store_ps(h, vhi);
  for (int k = 0; k < 4; ++k) lo = std::min(lo, l[k]), hi = std::max(hi, h[k]);
  add_scalar(v + i, n - i, lo, hi, finite);
}

#if defined(__x86_64__) && defined(__GNUC__)
// The float loop with AVX where the processor has it: sixteen values a step in two independent
// accumulators (the SSE2 loop waits on one minimum and one maximum chain, and the import adds every
// stored row of a global step, a few per cent of its time). The same minimum, maximum and count.
__attribute__((target("avx"))) void add_avx(const float* v, std::size_t n, float& lo, float& hi, std::size_t& finite) {
  const __m256 inf = _mm256_set1_ps(std::numeric_limits<float>::infinity());
  const __m256 ninf = _mm256_set1_ps(-std::numeric_limits<float>::infinity());
  const __m256 big = _mm256_set1_ps(std::numeric_limits<float>::max());
  const __m256 abs_mask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
  __m256 lo0 = inf, lo1 = inf, hi0 = ninf, hi1 = ninf;
  std::size_t i = 0, count = 0;
  for (; n - i >= 16; i += 16) {
    const __m256 x0 = _mm256_loadu_ps(v + i), x1 = _mm256_loadu_ps(v + i + 8);
    const __m256 ok0 = _mm256_cmp_ps(_mm256_and_ps(x0, abs_mask), big, _CMP_LE_OQ);  // false for NaN and infinity
    const __m256 ok1 = _mm256_cmp_ps(_mm256_and_ps(x1, abs_mask), big, _CMP_LE_OQ);
    // Masks rather than blends (GCC 12 takes the blend's mask apart lane by lane here).
    const __m256 in0 = _mm256_and_ps(ok0, x0), in1 = _mm256_and_ps(ok1, x1);
    lo0 = _mm256_min_ps(lo0, _mm256_or_ps(in0, _mm256_andnot_ps(ok0, inf)));
    hi0 = _mm256_max_ps(hi0, _mm256_or_ps(in0, _mm256_andnot_ps(ok0, ninf)));
    lo1 = _mm256_min_ps(lo1, _mm256_or_ps(in1, _mm256_andnot_ps(ok1, inf)));
    hi1 = _mm256_max_ps(hi1, _mm256_or_ps(in1, _mm256_andnot_ps(ok1, ninf)));
    count += mask_lanes(static_cast<unsigned>(_mm256_movemask_ps(ok0))) + mask_lanes(static_cast<unsigned>(_mm256_movemask_ps(ok1)));
  }
  alignas(32) float l[8], h[8];
  _mm256_store_ps(l, _mm256_min_ps(lo0, lo1));
  _mm256_store_ps(h, _mm256_max_ps(hi0, hi1));
  for (int k = 0; k < 8; ++k) lo = std::min(lo, l[k]), hi = std::max(hi, h[k]);
  finite += count;
  add_scalar(v + i, n - i, lo, hi, finite);
}
#endif

void add_simd(const double* v, std::size_t n, double& lo, double& hi, std::size_t& finite) {
  const __m128d inf = _mm_set1_pd(std::numeric_limits<double>::infinity()), ninf = _mm_set1_pd(-std::numeric_limits<double>::infinity());
  const __m128d big = _mm_set1_pd(std::numeric_limits<double>::max());
  const __m128d abs_mask = _mm_castsi128_pd(_mm_set1_epi64x(0x7fffffffffffffffLL));
  __m128d vlo = inf, vhi = ninf;
  __m128i count = _mm_setzero_si128();
  std::size_t i = 0;
  for (; n - i >= 2; i += 2) {
    const __m128d x = _mm_loadu_pd(v + i);
    const __m128d ok = _mm_cmple_pd(_mm_and_pd(x, abs_mask), big);
    vlo = _mm_min_pd(vlo, _mm_or_pd(_mm_and_pd(ok, x), _mm_andnot_pd(ok, inf)));
    vhi = _mm_max_pd(vhi, _mm_or_pd(_mm_and_pd(ok, x), _mm_andnot_pd(ok, ninf)));
    count = _mm_sub_epi64(count, _mm_castpd_si128(ok));
  }
  alignas(16) std::uint64_t c[2];
  _mm_store_si128(reinterpret_cast<__m128i*>(c), count);
  finite += c[0] + c[1];
  alignas(16) double l[2], h[2];
  _mm_store_pd(l, vlo);
  _mm_store_pd(h, vhi);
  for (int k = 0; k < 2; ++k) lo = std::min(lo, l[k]), hi = std::max(hi, h[k]);
  add_scalar(v + i, n - i, lo, hi, finite);
}
#endif

template <typename T>
void add_range(ValueStats& s, const T* v, std::size_t n) {
  T lo = std::numeric_limits<T>::infinity(), hi = -std::numeric_limits<T>::infinity();
  std::size_t finite = 0;
#if defined(__x86_64__) && defined(__GNUC__)
  if constexpr (std::is_same_v<T, float>) {
    if (cpu_has_avx()) add_avx(v, n, lo, hi, finite);
    else add_simd(v, n, lo, hi, finite);
  } else {
    add_simd(v, n, lo, hi, finite);
  }
#elif defined(__SSE2__)
  add_simd(v, n, lo, hi, finite);
#else
  add_scalar(v, n, lo, hi, finite);
#endif
  if (finite) {
    s.min = std::min(s.min, static_cast<double>(lo));
    s.max = std::max(s.max, static_cast<double>(hi));
  }
  s.count += finite;
  s.missing += n - finite;
}

// Large arrays (a global step's field is 48 million values) are split over the cores: the pass is
// memory-bound and each core brings its own bandwidth.
template <typename T>
void add_parallel(ValueStats& s, const T* v, std::size_t n) {
  constexpr std::size_t kGrain = std::size_t(1) << 22;
  if (n < 2 * kGrain) {
    add_range(s, v, n);
    return;
  }
  std::vector<ValueStats> part(worker_count());
  const unsigned parts = parallel_ranges(n, kGrain, [&](std::size_t b, std::size_t e, unsigned p) { add_range(part[p], v + b, e - b); });
  for (unsigned p = 0; p < parts; ++p) s.merge(part[p]);
}
}  // namespace

void ValueStats::add_all(const float* v, std::size_t n) { add_parallel(*this, v, n); }
void ValueStats::add_all(const double* v, std::size_t n) { add_parallel(*this, v, n); }

void ValueStats::merge(const ValueStats& o) {
  min = std::min(min, o.min);
  max = std::max(max, o.max);
  count += o.count;
  missing += o.missing;
}

VariableUse& ImportReport::use(const std::string& role) {
  for (auto& v : variables) {
    if (v.role == role) return v;
  }
  variables.push_back({});
  variables.back().role = role;
  return variables.back();
}

void ImportReport::warn(const std::string& message) {
  if (std::find(warnings.begin(), warnings.end(), message) == warnings.end()) warnings.push_back(message);
}

std::string json_quote(const std::string& s) {
  std::string out = "\"";
  for (unsigned char c : s) {
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\t': out += "\\t"; break;
      default:
        if (c < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04x", c);
          out += buf;
        } else {
          out += static_cast<char>(c);
        }
    }
  }
  return out + "\"";
}

namespace {
std::string num(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

std::string stats_json(const ValueStats& s) {
  return "{\"min\": " + num(s.empty() ? NAN : s.min) + ", \"max\": " + num(s.empty() ? NAN : s.max) +
         ", \"count\": " + std::to_string(s.count) + ", \"missing\": " + std::to_string(s.missing) + "}";
}

std::string range_text(const ValueStats& s) {
  if (s.empty()) return "no values";
  char buf[96];
  std::snprintf(buf, sizeof buf, "%.4g .. %.4g", s.min, s.max);
  return buf;
}
}  // namespace

std::string ImportReport::to_json() const {
  std::string j = "{\n  \"file\": " + json_quote(file) + ",\n  \"format\": " + json_quote(format) + ",\n";
  j += "  \"variables\": [\n";
  for (size_t i = 0; i < variables.size(); ++i) {
    const auto& v = variables[i];
    j += "    {\"role\": " + json_quote(v.role) + ", \"variable\": " + json_quote(v.variable) +
         ", \"units\": " + json_quote(v.units) + ", \"conversion\": " + json_quote(v.conversion) +
         ", \"before\": " + stats_json(v.before) + ", \"after\": " + stats_json(v.after) + ", \"after_units\": " + json_quote(v.after_units) +
         ", \"clamped\": " + std::to_string(v.clamped) + "}" + (i + 1 < variables.size() ? ",\n" : "\n");
  }
  j += "  ],\n  \"warnings\": [";
  for (size_t i = 0; i < warnings.size(); ++i) j += (i ? ", " : "") + json_quote(warnings[i]);
  j += "],\n  \"notes\": [";
  for (size_t i = 0; i < notes.size(); ++i) j += (i ? ", " : "") + json_quote(notes[i]);
  j += "]\n}\n";
  return j;
}

std::string ImportReport::to_text() const {
  std::string t = "import report for " + file + " (" + format + ")\n";
  for (const auto& v : variables) {
    t += "  " + v.role + " <- " + v.variable + " [" + (v.units.empty() ? "no units" : v.units) + "]: " +
         v.conversion + "\n      read " + range_text(v.before) + (v.units.empty() || v.before.empty() ? std::string() : " " + v.units) + " (" +
         std::to_string(v.before.missing) + " missing)" + (v.after.empty() && v.after.missing == 0 ? std::string() : ", stored " + range_text(v.after) + (v.after_units.empty() ? std::string() : " " + v.after_units)) + (v.clamped ? ", " + std::to_string(v.clamped) + " clamped" : "") +
         "\n";
  }
  for (const auto& n : notes) t += "  note: " + n + "\n";
  for (const auto& w : warnings) t += "  WARNING: " + w + "\n";
  return t;
}

}  // namespace cv::core
