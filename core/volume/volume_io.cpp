// .cvvol and .vti writers.
#include "volume/volume_io.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <cstring>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <unistd.h>

#include "io/background_writer.hpp"
#include "io/cpu.hpp"
#include "io/parallel.hpp"

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#endif

namespace cv::core {
namespace {

void put(std::FILE* f, const void* p, std::size_t n) {
  if (n && std::fwrite(p, 1, n, f) != n) throw WriteError(std::string("write failed (") + std::strerror(errno) + ")");
}
void put(std::FILE* f, const std::string& s) { put(f, s.data(), s.size()); }

std::string axis_json(const RegularAxis& a) {
  char buf[128];
  std::snprintf(buf, sizeof buf, "{\"start\": %.17g, \"step\": %.17g, \"count\": %d}", a.start, a.step, a.count);
  return buf;
}

using MapArrays = std::array<std::pair<const char*, const std::vector<float>*>, 7>;
MapArrays map_arrays(const Maps2D& m) {
  return {{{"cloud_cover", &m.cloud_cover}, {"cloud_base_m", &m.cloud_base_m}, {"cloud_top_m", &m.cloud_top_m},
           {"optical_depth", &m.optical_depth}, {"low_cover", &m.low_cover}, {"mid_cover", &m.mid_cover},
           {"high_cover", &m.high_cover}}};
}
// Outputs of at least this many field bytes are written with direct I/O (below it, the page cache's
// copy is cheap and keeps the file cached for the render that usually follows).
constexpr double kDirectWriteBytes = 64.0 * (1 << 20);
// Stored value = SI value x this, for the float16 encoding (cloud_volume.hpp).
float half_scale(int field) { return half_field_scale(static_cast<Field>(field)); }
}  // namespace

std::uint16_t float_to_half(float f) {
  std::uint32_t x;
  std::memcpy(&x, &f, sizeof x);
  const std::uint32_t sign = (x >> 16) & 0x8000u;
  const std::uint32_t abs = x & 0x7fffffffu;
  if (abs > 0x7f800000u) return static_cast<std::uint16_t>(sign | 0x7e00u);  // NaN
  if (abs >= 0x477ff000u) return static_cast<std::uint16_t>(sign | 0x7c00u);  // rounds past 65504: infinity
  if (abs < 0x38800000u) {
    // Below the smallest normal half (2^-14): a subnormal, in units of 2^-24, rounded to even.
    if (abs < 0x33000000u) return static_cast<std::uint16_t>(sign);  // under half of 2^-24
    const std::uint32_t mant = (abs & 0x7fffffu) | 0x800000u;
    const int shift = 126 - static_cast<int>(abs >> 23);  // value / 2^-24 = mant / 2^shift, shift 14..24
    const std::uint32_t q = mant >> shift, rem = mant & ((1u << shift) - 1u), half = 1u << (shift - 1);
    return static_cast<std::uint16_t>(sign | (q + (rem > half || (rem == half && (q & 1u)) ? 1u : 0u)));
  }
  // Normal: rebias the exponent (127 -> 15) and round the 23-bit mantissa to 10 bits, to even.
  const std::uint32_t rebased = abs - 0x38000000u;
  const std::uint32_t q = rebased >> 13, rem = rebased & 0x1fffu;
  return static_cast<std::uint16_t>(sign | (q + (rem > 0x1000u || (rem == 0x1000u && (q & 1u)) ? 1u : 0u)));
}

namespace {
#if defined(__x86_64__) && defined(__GNUC__)
// vcvtps2ph rounds to nearest even as float_to_half does, with the same overflow and subnormals;
// only a NaN's payload differs, so NaN lanes are set to float_to_half's quiet NaN (their sign and
// 0x7e00) in the same pass.
__attribute__((target("avx,f16c"))) void halves_f16c(const float* in, float scale, std::uint16_t* out, std::size_t n) {
  const __m256 k = _mm256_set1_ps(scale);
  const __m128i sign = _mm_set1_epi16(static_cast<short>(0x8000)), quiet = _mm_set1_epi16(0x7e00);
  std::size_t i = 0;
  for (; i + 8 <= n; i += 8) {
    const __m256 x = _mm256_mul_ps(_mm256_loadu_ps(in + i), k);
    const __m128i h = _mm256_cvtps_ph(x, _MM_FROUND_TO_NEAREST_INT);
    // The NaN lanes as 16-bit masks: the 32-bit compare's all-ones and zeros pack to the same.
    const __m256i m32 = _mm256_castps_si256(_mm256_cmp_ps(x, x, _CMP_UNORD_Q));
    const __m128i m16 = _mm_packs_epi32(_mm256_castsi256_si128(m32), _mm256_extractf128_si256(m32, 1));
    const __m128i nan = _mm_or_si128(_mm_and_si128(h, sign), quiet);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out + i), _mm_blendv_epi8(h, nan, m16));
  }
  for (; i < n; ++i) out[i] = float_to_half(in[i] * scale);
}

#endif
}  // namespace

void floats_to_halves(const float* in, float scale, std::uint16_t* out, std::size_t n) {
#if defined(__x86_64__) && defined(__GNUC__)
  if (cpu_has_avx_f16c()) {
    halves_f16c(in, scale, out, n);
    return;
  }
#endif
  for (std::size_t i = 0; i < n; ++i) out[i] = float_to_half(in[i] * scale);
}

namespace {
#if defined(__x86_64__) && defined(__GNUC__)
// vcvtph2ps is exact (every half is a float), as half_to_float is; the product is the same float
// multiplication either way.
__attribute__((target("avx,f16c"))) void floats_f16c(const std::uint16_t* in, float scale, float* out, std::size_t n) {
  const __m256 k = _mm256_set1_ps(scale);
  std::size_t i = 0;
  for (; i + 8 <= n; i += 8) {
    const __m256 x = _mm256_cvtph_ps(_mm_loadu_si128(reinterpret_cast<const __m128i*>(in + i)));
    _mm256_storeu_ps(out + i, _mm256_mul_ps(x, k));
  }
  for (; i < n; ++i) out[i] = half_to_float(in[i]) * scale;
}
#endif
}  // namespace

void halves_to_floats(const std::uint16_t* in, float scale, float* out, std::size_t n) {
#if defined(__x86_64__) && defined(__GNUC__)
  if (cpu_has_avx_f16c()) {
    floats_f16c(in, scale, out, n);
    return;
  }
#endif
  for (std::size_t i = 0; i < n; ++i) out[i] = half_to_float(in[i]) * scale;
}

float half_to_float(std::uint16_t h) {
  const std::uint32_t sign = static_cast<std::uint32_t>(h & 0x8000u) << 16;
  const std::uint32_t exp = (h >> 10) & 0x1fu, mant = h & 0x3ffu;
  std::uint32_t x;
  if (exp == 0x1fu) {
    x = sign | 0x7f800000u | (mant << 13);  // infinity or NaN
  } else if (exp == 0) {
    const float v = std::ldexp(static_cast<float>(mant), -24);  // subnormal (or zero)
    return sign ? -v : v;
  } else {
    x = sign | ((exp + 112u) << 23) | (mant << 13);
  }
  float f;
  std::memcpy(&f, &x, sizeof f);
  return f;
}

namespace {
// Version 2's plane table: one byte per (field, level) plane of a step, padded with zeros to a
// multiple of 8 bytes so the fields after it stay aligned:
//   0  every value is zero (of either sign): left out, read back as +0;
//   1  the plane is stored;
//   2  every value is zero or NaN (no data), with at least one NaN: stored as a mask of the NaNs,
//      bit i % 8 of byte i / 8 for the plane's value i, padded with zeros to 8 bytes (a WRF domain
//      resampled to latitude and longitude has no data outside it, on every level).
enum PlaneCode : std::uint8_t { kPlaneZero = 0, kPlaneStored = 1, kPlaneNanMask = 2 };
std::size_t cvvol_plane_table_bytes(std::size_t fields, std::size_t levels) { return (fields * levels + 7) / 8 * 8; }
std::size_t cvvol_mask_bytes(std::size_t cols) { return (cols + 63) / 64 * 8; }
// Blocks of 4096 values, each scanned without a branch (vectorised), so a plane with data stops
// early. Per value: `zero`, `nan`, or neither (the plane is stored).
constexpr std::size_t kZeroScanBlock = 4096;
template <class T, class Classify>
PlaneCode plane_code(const T* p, std::size_t n, Classify classify) {
  bool any_nan = false;
  for (std::size_t at = 0; at < n; at += kZeroScanBlock) {
    const std::size_t e = std::min(n, at + kZeroScanBlock);
    unsigned other = 0, nan = 0;
    for (std::size_t i = at; i < e; ++i) {
      const auto [is_zero, is_nan] = classify(p[i]);
      other |= static_cast<unsigned>(!is_zero & !is_nan);
      nan |= static_cast<unsigned>(is_nan);
    }
    if (other) return kPlaneStored;
    any_nan = any_nan || nan;
  }
  return any_nan ? kPlaneNanMask : kPlaneZero;
}
struct ZeroNan {
  bool zero, nan;
};
// Held half floats: zero is +-0, NaN is an exponent of all ones with a mantissa.
ZeroNan half_zero_nan(std::uint16_t h) {
  const unsigned m = h & 0x7fffu;
  return {m == 0, m > 0x7c00u};
}
// float32 as stored.
ZeroNan float_zero_nan(float x) {
  std::uint32_t b;
  std::memcpy(&b, &x, sizeof b);
  b &= 0x7fffffffu;
  return {b == 0, b > 0x7f800000u};
}
// float32 to be stored as float_to_half(x * k): zero where the product's magnitude is at most 2^-25
// (0x33000000), which rounds to zero, to even at the tie.
struct FloatHalfZeroNan {
  float k;
  ZeroNan operator()(float x) const {
    const float y = x * k;
    std::uint32_t b;
    std::memcpy(&b, &y, sizeof b);
    b &= 0x7fffffffu;
    return {b <= 0x33000000u, b > 0x7f800000u};
  }
};
// The mask of a kPlaneNanMask plane, into `mask` (cvvol_mask_bytes(n) bytes).
template <class IsNan>
void nan_mask(std::size_t n, IsNan is_nan, std::vector<std::uint8_t>& mask) {
  mask.assign(cvvol_mask_bytes(n), 0);
  for (std::size_t i = 0; i < n; ++i) mask[i / 8] |= static_cast<std::uint8_t>(is_nan(i) << (i % 8));
}

void write_cvvol_to(const std::function<void(const std::string&, const std::function<void(std::FILE*)>&)>& writer,
                    const std::string& path, CloudVolume& v, const std::function<void(std::size_t, std::size_t)>& progress,
                    CvvolEncoding encoding) {
  const bool half = encoding == CvvolEncoding::Float16;
  std::string fields = "[", maps = "[", times = "[";
  for (int i = 0; i < kFieldCount; ++i) {
    if (v.has_field[static_cast<std::size_t>(i)]) {
      fields += std::string(fields.size() > 1 ? ", " : "") + json_quote(field_name(static_cast<Field>(i)));
    }
  }
  const Maps2D none;
  for (const auto& [name, arr] : map_arrays(none)) maps += std::string(maps.size() > 1 ? ", " : "") + json_quote(name);
  // The ground's altitude, when the file gave terrain: read back, since the cover maps are derived
  // again from it.
  if (v.has_ground) maps += ", \"ground_m\"";
  for (std::size_t t = 0; t < v.times.size(); ++t) {
    times += std::string(t ? ", " : "") + "{\"iso_utc\": " + json_quote(v.times[t].iso_utc) +
             ", \"unix_s\": " + std::to_string(v.times[t].unix_s) + "}";
  }
  std::string header = "{\"format\": \"cvvol\", \"version\": 2, \"zero_planes\": \"left out\",\n \"grid\": {\"lon_deg\": " + axis_json(v.grid.lon_deg) +
                             ", \"lat_deg\": " + axis_json(v.grid.lat_deg) + ", \"alt_m\": " + axis_json(v.grid.alt_m) +
                             ", \"earth_radius_m\": " + std::to_string(v.grid.earth_radius_m) + "},\n \"liquid_r_eff_um\": " +
                             std::to_string(v.liquid_r_eff_um) + ",\n" +
                             (half ? " \"encoding\": \"float16\", \"field_scale\": \"extinction x 1000 (1/km); pressure x 0.01 (hPa); others x 1\",\n"
                                   : "") +
                             " \"times\": " + times +
                             "],\n \"fields\": " + fields + "],\n \"maps\": " + maps +
                             "],\n \"layout\": \"" + (half ? "fields float16, maps float32" : "float32") +
                             " little-endian; per time step, a plane table (a byte per field and level, 1 = "
                             "stored, 0 = all zero and left out, 2 = zeros and NaNs only, stored as a bit mask of the "
                             "NaNs, bit i % 8 of byte i / 8, padded to 8 bytes; the table padded to 8 bytes), each "
                             "field's stored levels (lon fastest, then lat), then each map (lon fastest, then lat); "
                             "NaN = no data\"}\n";
  // Padded so the data starts 8-byte aligned (magic 8 + length 8 + header): the half floats are
  // then converted in place in the write queue.
  header.pop_back();  // the closing newline, put back after the spaces
  header.append((8 - (16 + header.size() + 1) % 8) % 8, ' ');
  header.push_back('\n');
  writer(path, [&](std::FILE* f) {
    // Through a writer thread: the disk writes a step while the next one is loaded, with direct
    // I/O for outputs large enough that the page cache's copy costs more than it saves.
    std::size_t fields_per_step = 0;
    for (int i = 0; i < kFieldCount; ++i) fields_per_step += v.has_field[static_cast<std::size_t>(i)] ? 1 : 0;
    const double bytes = static_cast<double>(v.grid.points()) * static_cast<double>(fields_per_step) *
                         static_cast<double>(v.times.size()) * (half ? 2.0 : 4.0);
    BackgroundWriter::Options wo;
    wo.direct = bytes >= kDirectWriteBytes;
    if (!wo.direct) wo.chunk_bytes = std::size_t(1) << 20;  // a small file: a small queue (4 MB)
    BackgroundWriter out(f, wo);
    // Version 2's own magic: a reader of version 1 (which ignores the header's version) refuses
    // the file instead of misreading it.
    out.write("CVVOL02\n", 8);
    const std::uint64_t len = header.size();
    out.write(&len, sizeof len);
    out.write(header.data(), header.size());
    const std::size_t cols = v.grid.columns(), levels = static_cast<std::size_t>(v.grid.alt_m.count);
    std::vector<int> order;
    for (int i = 0; i < kFieldCount; ++i) {
      if (v.has_field[static_cast<std::size_t>(i)]) order.push_back(i);
    }
    const std::size_t table_bytes = cvvol_plane_table_bytes(order.size(), levels);
    std::vector<std::uint8_t> table(table_bytes), mask;
    for (std::size_t t = 0; t < v.times.size(); ++t) {
      if (progress) progress(t, v.times.size());
      const TimeStepData& d = v.step(t);
      // The step's plane table: which (field, level) planes hold a value other than zero or NaN.
      std::fill(table.begin(), table.end(), std::uint8_t{0});
      for (std::size_t fi = 0; fi < order.size(); ++fi) {
        const int i = order[fi];
        const auto& a = d.fields[static_cast<std::size_t>(i)];
        const auto& h = d.halves[static_cast<std::size_t>(i)];
        if (a.size() != v.grid.points() && h.size() != v.grid.points()) {
          throw std::runtime_error(std::string("field ") + field_name(static_cast<Field>(i)) + " has the wrong size");
        }
        const float k = half_scale(i);
        for (std::size_t z = 0; z < levels; ++z) {
          PlaneCode code;
          if (a.size() != v.grid.points()) code = plane_code(h.data() + z * cols, cols, half_zero_nan);
          else if (half) code = plane_code(a.data() + z * cols, cols, FloatHalfZeroNan{k});
          else code = plane_code(a.data() + z * cols, cols, float_zero_nan);
          table[fi * levels + z] = code;
        }
      }
      out.write(table.data(), table.size());
      for (std::size_t fi = 0; fi < order.size(); ++fi) {
        const int i = order[fi];
        const auto& a_all = d.fields[static_cast<std::size_t>(i)];
        const auto& h_all = d.halves[static_cast<std::size_t>(i)];
        // Each run of consecutive stored planes, as one span of the field; a NaN mask in its place.
        for (std::size_t z0 = 0; z0 < levels;) {
          if (table[fi * levels + z0] == kPlaneZero) {
            ++z0;
            continue;
          }
          if (table[fi * levels + z0] == kPlaneNanMask) {
            if (a_all.size() != v.grid.points()) {
              const std::uint16_t* p = h_all.data() + z0 * cols;
              nan_mask(cols, [p](std::size_t j) { return half_zero_nan(p[j]).nan; }, mask);
            } else {
              const float* p = a_all.data() + z0 * cols;
              nan_mask(cols, [p](std::size_t j) { return std::isnan(p[j]); }, mask);
            }
            out.write(mask.data(), mask.size());
            ++z0;
            continue;
          }
          std::size_t z1 = z0 + 1;
          while (z1 < levels && table[fi * levels + z1] == kPlaneStored) ++z1;
          const std::size_t first = z0 * cols, count = (z1 - z0) * cols;
          z0 = z1;
          if (a_all.size() != v.grid.points()) {
            // Held as half floats already (TimeStepData::halves): written as they are, or widened.
            const std::uint16_t* h = h_all.data() + first;
            if (half) {
              out.write(h, count * sizeof(std::uint16_t));
            } else {
              const float k = 1.0f / half_scale(i);
              std::vector<float> buf(std::min<std::size_t>(count, std::size_t(1) << 18));
              for (std::size_t at = 0; at < count; at += buf.size()) {
                const std::size_t n = std::min(buf.size(), count - at);
                halves_to_floats(h + at, k, buf.data(), n);
                out.write(buf.data(), n * sizeof(float));
              }
            }
          } else if (half) {
            // Converted straight into the write queue's chunks, so no second copy of the volume exists.
            const float k = half_scale(i);
            const float* a = a_all.data() + first;
            for (std::size_t at = 0; at < count;) {
              const std::span<std::byte> r = out.room();
              const std::size_t n = std::min(count - at, r.size() / sizeof(std::uint16_t));
              if (n == 0 || reinterpret_cast<std::uintptr_t>(r.data()) % alignof(std::uint16_t)) {
                // Not at a half's alignment (cannot happen with the padded header and table; kept
                // for safety): through a small buffer instead.
                std::uint16_t hb[256];
                const std::size_t m = std::min<std::size_t>(count - at, 256);
                floats_to_halves(a + at, k, hb, m);
                out.write(hb, m * sizeof(std::uint16_t));
                at += m;
                continue;
              }
              std::uint16_t* dst = reinterpret_cast<std::uint16_t*>(r.data());
              const float* src = a + at;
              parallel_ranges(n, std::size_t(1) << 20, [&](std::size_t b, std::size_t e, unsigned) {
                floats_to_halves(src + b, k, dst + b, e - b);
              });
              out.commit(n * sizeof(std::uint16_t));
              at += n;
            }
          } else {
            out.write(a_all.data() + first, count * sizeof(float));
          }
        }
      }
      for (const auto& [name, arr] : map_arrays(d.maps)) out.write(arr->data(), arr->size() * sizeof(float));
      if (v.has_ground) {
        if (d.ground_m.size() == v.grid.columns()) {
          out.write(d.ground_m.data(), d.ground_m.size() * sizeof(float));
        } else {
          const std::vector<float> unknown(v.grid.columns(), std::numeric_limits<float>::quiet_NaN());
          out.write(unknown.data(), unknown.size() * sizeof(float));
        }
      }
    }
    out.finish();
  });
}
}  // namespace

void write_cvvol(const std::string& path, CloudVolume& v, const std::function<void(std::size_t, std::size_t)>& progress,
                 CvvolEncoding encoding) {
  write_cvvol_to(write_file_atomically, path, v, progress, encoding);
}

void write_cvvol(OutputGroup& group, const std::string& path, CloudVolume& v,
                 const std::function<void(std::size_t, std::size_t)>& progress, CvvolEncoding encoding) {
  write_cvvol_to([&](const std::string& p, const std::function<void(std::FILE*)>& w) { group.write(p, w); }, path, v, progress,
                 encoding);
}

namespace {
// Minimal readers for the header this file writes (not a general JSON parser); every value is
// checked to be there, to be a number, and finite.
double json_number(const std::string& j, const std::string& key, std::size_t from, const std::string& path) {
  const std::size_t k = j.find("\"" + key + "\":", from);
  if (k == std::string::npos) throw VolumeFileError(path + ": header has no '" + key + "'");
  const char* text = j.c_str() + k + key.size() + 3;
  char* end = nullptr;
  const double v = std::strtod(text, &end);
  if (end == text || !std::isfinite(v)) {
    std::string found = j.substr(k + key.size() + 3, 24);
    found.erase(0, found.find_first_not_of(' '));
    found = found.substr(0, found.find_first_of(",}]"));
    throw VolumeFileError(path + ": header key '" + key + "': found '" + found + "', expected a finite number");
  }
  return v;
}
RegularAxis json_axis(const std::string& j, const std::string& key, const std::string& path) {
  const std::size_t k = j.find("\"" + key + "\":");
  if (k == std::string::npos) throw VolumeFileError(path + ": header has no axis '" + key + "'");
  RegularAxis a;
  a.start = json_number(j, "start", k, path);
  a.step = json_number(j, "step", k, path);
  const double count = json_number(j, "count", k, path);
  if (!(count >= 1 && count <= 1000000) || count != std::floor(count)) {
    char found[32];
    std::snprintf(found, sizeof found, "%.17g", count);
    throw VolumeFileError(path + ": axis '" + key + "' count: found " + found + ", expected an integer 1..1000000");
  }
  a.count = static_cast<int>(count);
  return a;
}
// The quoted string that starts at j[q] (a '"'), or a VolumeFileError for one left open.
std::string json_quoted(const std::string& j, std::size_t q, const std::string& key, const std::string& path,
                        std::size_t before = std::string::npos) {
  const std::size_t e = q == std::string::npos ? q : j.find('"', q + 1);
  if (q == std::string::npos || e == std::string::npos || e > before) {
    throw VolumeFileError(path + ": header key '" + key + "': found a string without its closing quote, expected \"...\"");
  }
  return j.substr(q + 1, e - q - 1);
}
// The names in the header's list `key`, at most max_names of them.
std::vector<std::string> json_strings(const std::string& j, const std::string& key, const std::string& path,
                                      std::size_t max_names) {
  const std::size_t k = j.find("\"" + key + "\":");
  if (k == std::string::npos) throw VolumeFileError(path + ": header has no '" + key + "'");
  const std::size_t open = j.find('[', k), close = open == std::string::npos ? open : j.find(']', open);
  if (close == std::string::npos) throw VolumeFileError(path + ": header key '" + key + "': found no [ ... ] list, expected one");
  std::vector<std::string> out;
  for (std::size_t q = j.find('"', open); q < close; q = j.find('"', q + 1)) {
    out.push_back(json_quoted(j, q, key, path, close));
    q += out.back().size() + 1;
    if (out.size() > max_names) {
      throw VolumeFileError(path + ": header key '" + key + "': found more than " + std::to_string(max_names) +
                            " names, expected each at most once");
    }
  }
  return out;
}
}  // namespace

std::string grid_problem(const VolumeGrid& g) {
  const std::pair<const char*, const RegularAxis*> axes[] = {{"lon_deg", &g.lon_deg}, {"lat_deg", &g.lat_deg}, {"alt_m", &g.alt_m}};
  for (const auto& [name, a] : axes) {
    char buf[256];
    if (!std::isfinite(a->start) || !std::isfinite(a->step) || !(a->step > 0.0) || a->count < 1 || a->count > 1000000) {
      std::snprintf(buf, sizeof buf, "axis %s: found start %g, step %g, count %d; expected a finite start, a step > 0 and 1..1000000 points",
                    name, a->start, a->step, a->count);
      return buf;
    }
  }
  char buf[256];
  if (g.lon_deg.step * (g.lon_deg.count - 1) > 360.0 + 1e-6 || std::abs(g.lon_deg.start) > 720.0) {
    std::snprintf(buf, sizeof buf, "axis lon_deg: found %g..%g, expected at most one turn (360 degrees) within -720..720",
                  g.lon_deg.start, g.lon_deg.last());
    return buf;
  }
  if (g.lat_deg.start < -90.0 - 1e-6 || g.lat_deg.last() > 90.0 + 1e-6) {
    std::snprintf(buf, sizeof buf, "axis lat_deg: found %g..%g, expected latitudes within -90..90", g.lat_deg.start, g.lat_deg.last());
    return buf;
  }
  if (g.alt_m.start < -1000.0 - 1e-6 || g.alt_m.last() > 1.0e5 + 1e-6) {
    std::snprintf(buf, sizeof buf, "axis alt_m: found %g..%g m, expected altitudes within -1000..100000 m", g.alt_m.start, g.alt_m.last());
    return buf;
  }
  if (!(g.earth_radius_m >= 1e6 && g.earth_radius_m <= 1e8)) {
    std::snprintf(buf, sizeof buf, "earth_radius_m: found %g, expected 1e6..1e8 m", g.earth_radius_m);
    return buf;
  }
  return "";
}

CloudVolume read_cvvol(const std::string& path, std::size_t cache_steps) {
  std::FILE* f = nullptr;
  try {
    f = open_regular_file(path, "the cloud volume");
  } catch (const InputError& e) {
    throw VolumeFileError(e.what());
  }
  std::shared_ptr<std::FILE> file(f, [](std::FILE* p) { std::fclose(p); });
  char magic[8];
  std::uint64_t len = 0;
  if (std::fread(magic, 1, 8, f) != 8 || (std::memcmp(magic, "CVVOL01\n", 8) != 0 && std::memcmp(magic, "CVVOL02\n", 8) != 0)) {
    throw VolumeFileError(path + ": not a cloud volume (expected the CVVOL01 or CVVOL02 header of a .cvvol file)");
  }
  const int magic_version = magic[6] - '0';
  if (std::fread(&len, sizeof len, 1, f) != 1 || len > (1u << 26)) throw VolumeFileError(path + ": truncated or corrupt header");
  std::string header(len, '\0');
  if (std::fread(header.data(), 1, len, f) != len) throw VolumeFileError(path + ": truncated header");
  CloudVolume v;
  v.grid.lon_deg = json_axis(header, "lon_deg", path);
  v.grid.lat_deg = json_axis(header, "lat_deg", path);
  v.grid.alt_m = json_axis(header, "alt_m", path);
  v.grid.earth_radius_m = json_number(header, "earth_radius_m", 0, path);
  if (const std::string problem = grid_problem(v.grid); !problem.empty()) throw VolumeFileError(path + ": header " + problem);
  // Volumes written before the effective radius was recorded were all made with 10 um.
  if (header.find("\"liquid_r_eff_um\":") != std::string::npos) v.liquid_r_eff_um = json_number(header, "liquid_r_eff_um", 0, path);
  if (!(v.liquid_r_eff_um > 0.0 && v.liquid_r_eff_um < 1000.0)) {
    throw VolumeFileError(path + ": liquid_r_eff_um is " + std::to_string(v.liquid_r_eff_um) + ", expected 0..1000 um");
  }
  const std::vector<std::string> fields = json_strings(header, "fields", path, static_cast<std::size_t>(kFieldCount));
  std::vector<int> order;
  for (const auto& name : fields) {
    int found = -1;
    for (int i = 0; i < kFieldCount; ++i) {
      if (name == field_name(static_cast<Field>(i))) found = i;
    }
    if (found < 0) throw VolumeFileError(path + ": unknown field '" + name + "' in the header");
    v.has_field[static_cast<std::size_t>(found)] = true;
    order.push_back(found);
  }
  // Times: pairs of iso_utc and unix_s, in order.
  for (std::size_t k = header.find("\"iso_utc\":"); k != std::string::npos; k = header.find("\"iso_utc\":", k + 1)) {
    ValidTime t;
    t.iso_utc = json_quoted(header, header.find('"', k + 10), "iso_utc", path);
    // Converted to an integer only once known to be one within range: a double beyond int64's
    // range converted is undefined behaviour (the fuzzer found 'unix_s': 1e300).
    const double unix_s = json_number(header, "unix_s", k, path);
    if (!(std::fabs(unix_s) <= 1e12) || unix_s != std::floor(unix_s)) {
      char found[32];
      std::snprintf(found, sizeof found, "%.17g", unix_s);
      throw VolumeFileError(path + ": header key 'unix_s': found " + found + ", expected whole seconds within +-1e12 of 1970");
    }
    t.unix_s = static_cast<std::int64_t>(unix_s);
    v.times.push_back(t);
  }
  const bool half = header.find("\"encoding\": \"float16\"") != std::string::npos;
  const std::uint64_t value_bytes = half ? sizeof(std::uint16_t) : sizeof(float);
  // Sizes from the header, multiplied with overflow checks: one time step (held in memory as
  // float32, with at least the seven maps every volume has) must fit the memory limit before
  // anything else is read, and the file must hold exactly the steps the header declares.
  const std::size_t points = v.grid.points(), cols = v.grid.columns();
  const auto field_values = checked_product({order.size(), points});
  const auto least_maps = checked_product({7, cols});
  const auto step_values = field_values && least_maps ? checked_product({1, *field_values + *least_maps}) : std::nullopt;
  const auto memory_bytes = step_values ? checked_product({*step_values, sizeof(float)}) : std::nullopt;
  char grid_text[96];
  std::snprintf(grid_text, sizeof grid_text, "one time step of %d x %d x %d points", v.grid.lon_deg.count, v.grid.lat_deg.count,
                v.grid.alt_m.count);
  try {
    require_within_memory_limit(path, grid_text, memory_bytes);
  } catch (const InputError& e) {
    throw VolumeFileError(e.what());
  }
  // The maps: the seven derived ones and, where the file gave terrain, the ground's altitude.
  const std::vector<std::string> maps = json_strings(header, "maps", path, 16);
  v.has_ground = std::find(maps.begin(), maps.end(), "ground_m") != maps.end();
  const std::uint64_t map_count = v.has_ground ? 8 : 7;
  const auto map_values = checked_product({map_count, cols});
  const auto field_bytes = field_values ? checked_product({*field_values, value_bytes}) : std::nullopt;
  const auto map_bytes = map_values ? checked_product({*map_values, sizeof(float)}) : std::nullopt;
  if (!field_bytes || !map_bytes) throw VolumeFileError(path + ": one time step's size overflows 64 bits");
  // Version 1 stores every plane; version 2 starts each step with a plane table, leaves out the
  // planes whose values are all zero and stores planes of zeros and NaN as masks, so its steps'
  // sizes differ: each step's table is read here to find where the step starts, and the sizes
  // must add up to the file's.
  double version = 1;
  if (header.find("\"version\":") != std::string::npos) version = json_number(header, "version", 0, path);
  if (version != 1 && version != 2) {
    char found[32];
    std::snprintf(found, sizeof found, "%.17g", version);
    throw VolumeFileError(path + ": header key 'version': found " + found + ", expected 1 or 2 (written by a newer cloudviewer?)");
  }
  if (version != magic_version) {
    throw VolumeFileError(path + ": header key 'version': found " + std::to_string(static_cast<int>(version)) + ", expected " +
                          std::to_string(magic_version) + " in a file that starts CVVOL0" + std::to_string(magic_version));
  }
  const bool sparse = version == 2;
  const std::size_t levels = static_cast<std::size_t>(v.grid.alt_m.count);
  const std::size_t table_bytes = sparse ? cvvol_plane_table_bytes(order.size(), levels) : 0;
  const std::uint64_t plane_bytes = static_cast<std::uint64_t>(cols) * value_bytes;
  const std::uint64_t data0 = 16 + len;
  std::fseek(f, 0, SEEK_END);
  const long long size_signed = std::ftell(f);
  const std::uint64_t size = size_signed < 0 ? 0 : static_cast<std::uint64_t>(size_signed);
  const auto refuse_size = [&](const std::string& expected) {
    throw VolumeFileError(path + ": holds " + std::to_string(size) + " bytes, expected " + expected + " for its header's " +
                          std::to_string(v.times.size()) + " time step(s) (truncated?)");
  };
  // The table at `at`, checked: every byte 0, 1 or 2, the padding 0. Counts the planes stored and
  // the NaN masks.
  struct TableCount {
    std::uint64_t planes = 0, masks = 0;
  };
  const auto read_table = [path, table_bytes, n = order.size() * levels](std::FILE* file, std::uint64_t at, std::size_t t,
                                                                       std::vector<std::uint8_t>& table) {
    table.resize(table_bytes);
    if (std::fseek(file, static_cast<long>(at), SEEK_SET) != 0 || std::fread(table.data(), 1, table_bytes, file) != table_bytes) {
      throw VolumeFileError(path + ": truncated in the plane table of time step " + std::to_string(t));
    }
    TableCount c;
    for (std::size_t k = 0; k < table_bytes; ++k) {
      if (table[k] > (k < n ? kPlaneNanMask : 0)) {
        throw VolumeFileError(path + ": plane table of time step " + std::to_string(t) + ", byte " + std::to_string(k) +
                              ": found " + std::to_string(table[k]) + ", expected " + (k < n ? "0, 1 or 2" : "0 (padding)"));
      }
      c.planes += table[k] == kPlaneStored;
      c.masks += table[k] == kPlaneNanMask;
    }
    return c;
  };
  std::vector<std::uint64_t> starts;
  const std::uint64_t all_planes = static_cast<std::uint64_t>(order.size()) * levels * v.times.size();
  std::uint64_t stored_planes = sparse ? 0 : all_planes, mask_planes = 0;
  const std::uint64_t mask_bytes = cvvol_mask_bytes(cols);
  if (!sparse) {
    const std::uint64_t step_bytes = *field_bytes + *map_bytes;
    const auto payload = checked_product({step_bytes, v.times.size()});
    if (!payload || *payload > std::numeric_limits<std::uint64_t>::max() - data0 || size != data0 + *payload) {
      refuse_size(payload ? std::to_string(data0 + *payload) : std::string("more than 2^64"));
    }
    for (std::size_t t = 0; t < v.times.size(); ++t) starts.push_back(data0 + step_bytes * t);
  } else {
    std::vector<std::uint8_t> table;
    std::uint64_t at = data0;
    for (std::size_t t = 0; t < v.times.size(); ++t) {
      if (at > size || size - at < table_bytes) refuse_size("more");
      starts.push_back(at);
      const TableCount c = read_table(f, at, t, table);
      stored_planes += c.planes;
      mask_planes += c.masks;
      // planes + masks <= fields x levels, and a mask's bytes <= 8 + a float16 plane's: bounded by
      // the step's memory checked above, so the sum stays far below 2^64.
      const std::uint64_t step = table_bytes + c.planes * plane_bytes + c.masks * mask_bytes + *map_bytes;
      if (size - at < step) refuse_size("more");
      at += step;
    }
    if (at != size) refuse_size(std::to_string(at));
  }
  v.report.file = path;
  v.report.format = "cloud volume (.cvvol)";
  // What `cloudviewer info` says of the storage.
  v.report.notes.push_back(std::string("storage: ") + (half ? "float16" : "float32") + " fields, " +
                           std::to_string(stored_planes) + " of " + std::to_string(all_planes) + " field planes stored" +
                           (sparse ? " (" + std::to_string(mask_planes) + " of zeros and no data as masks, " +
                                         std::to_string(all_planes - stored_planes - mask_planes) + " holding only zeros left out)"
                                   : " (version 1: every plane stored)"));
  v.set_loader(
      [file, order, starts, read_table, levels, points, cols, half, sparse, ground = v.has_ground, path](
          std::size_t t, ImportReport&, TimeStepData& out) {
        std::vector<std::uint8_t> table, mask(sparse ? cvvol_mask_bytes(cols) : 0);
        if (sparse) {
          read_table(file.get(), starts[t], t, table);  // and leaves the file after it
        } else if (std::fseek(file.get(), static_cast<long>(starts[t]), SEEK_SET) != 0) {
          throw VolumeFileError(path + ": cannot seek to time step " + std::to_string(t));
        }
        for (auto& fld : out.fields) fld.clear();
        const auto truncated = [&] { return VolumeFileError(path + ": truncated at time step " + std::to_string(t)); };
        std::vector<std::uint16_t> buf(half ? std::min<std::size_t>(cols, std::size_t(1) << 20) : 0);
        for (std::size_t fi = 0; fi < order.size(); ++fi) {
          const int i = order[fi];
          auto& a = out.fields[static_cast<std::size_t>(i)];
          a.resize(points);
          for (std::size_t z = 0; z < levels; ++z) {
            float* plane = a.data() + z * cols;
            if (sparse && table[fi * levels + z] == kPlaneZero) {
              std::fill(plane, plane + cols, 0.0f);
            } else if (sparse && table[fi * levels + z] == kPlaneNanMask) {
              if (std::fread(mask.data(), 1, mask.size(), file.get()) != mask.size()) throw truncated();
              // At least one NaN (a plane of zeros is left out), and its bits past the plane's
              // values zero, as written.
              if (std::all_of(mask.begin(), mask.end(), [](std::uint8_t b) { return b == 0; })) {
                throw VolumeFileError(path + ": NaN mask of time step " + std::to_string(t) + ", field " +
                                      field_name(static_cast<Field>(i)) + ", level " + std::to_string(z) +
                                      ": no bit set, expected at least one (a plane of zeros is left out)");
              }
              for (std::size_t j = cols; j < mask.size() * 8; ++j) {
                if ((mask[j / 8] >> (j % 8)) & 1u) {
                  throw VolumeFileError(path + ": NaN mask of time step " + std::to_string(t) + ", field " +
                                        field_name(static_cast<Field>(i)) + ", level " + std::to_string(z) + ": bit " +
                                        std::to_string(j) + " past its " + std::to_string(cols) + " values is set, expected 0");
                }
              }
              for (std::size_t j = 0; j < cols; ++j) {
                plane[j] = (mask[j / 8] >> (j % 8)) & 1u ? std::numeric_limits<float>::quiet_NaN() : 0.0f;
              }
            } else if (half) {
              const float k = 1.0f / half_scale(i);
              for (std::size_t at = 0; at < cols; at += buf.size()) {
                const std::size_t n = std::min(buf.size(), cols - at);
                if (std::fread(buf.data(), sizeof(std::uint16_t), n, file.get()) != n) throw truncated();
                halves_to_floats(buf.data(), k, plane + at, n);
              }
            } else if (std::fread(plane, sizeof(float), cols, file.get()) != cols) {
              throw truncated();
            }
          }
        }
        // The maps that follow are derived again from the fields (and the ground) by CloudVolume::step.
        out.ground_m.clear();
        if (ground) {
          if (std::fseek(file.get(), static_cast<long>(7 * cols * sizeof(float)), SEEK_CUR) != 0) {
            throw VolumeFileError(path + ": cannot seek to the ground of time step " + std::to_string(t));
          }
          out.ground_m.resize(cols);
          if (std::fread(out.ground_m.data(), sizeof(float), cols, file.get()) != cols) throw truncated();
        }
      },
      cache_steps);
  return v;
}

namespace {
void write_vti_to(const std::function<void(const std::string&, const std::function<void(std::FILE*)>&)>& writer,
                  const std::string& path, const VolumeGrid& g, const TimeStepData& d, const std::array<bool, kFieldCount>& has) {
  // Altitude in km so the box keeps a sensible aspect next to degrees in ParaView.
  char head[512];
  std::snprintf(head, sizeof head,
                "<?xml version=\"1.0\"?>\n<VTKFile type=\"ImageData\" version=\"1.0\" byte_order=\"LittleEndian\" "
                "header_type=\"UInt64\">\n<ImageData WholeExtent=\"0 %d 0 %d 0 %d\" Origin=\"%.10g %.10g %.10g\" "
                "Spacing=\"%.10g %.10g %.10g\">\n<Piece Extent=\"0 %d 0 %d 0 %d\">\n<PointData>\n",
                g.lon_deg.count - 1, g.lat_deg.count - 1, g.alt_m.count - 1, g.lon_deg.start, g.lat_deg.start,
                g.alt_m.start / 1000.0, g.lon_deg.step, g.lat_deg.step, g.alt_m.step / 1000.0, g.lon_deg.count - 1,
                g.lat_deg.count - 1, g.alt_m.count - 1);
  std::string xml = head;
  std::vector<const std::vector<float>*> arrays;
  std::uint64_t offset = 0;
  for (int i = 0; i < kFieldCount; ++i) {
    if (!has[static_cast<std::size_t>(i)]) continue;
    const auto& a = d.fields[static_cast<std::size_t>(i)];
    xml += std::string("<DataArray type=\"Float32\" Name=\"") + field_name(static_cast<Field>(i)) +
           "\" format=\"appended\" offset=\"" + std::to_string(offset) + "\"/>\n";
    arrays.push_back(&a);
    offset += sizeof(std::uint64_t) + a.size() * sizeof(float);
  }
  xml += "</PointData>\n</Piece>\n</ImageData>\n<AppendedData encoding=\"raw\">\n_";
  writer(path, [&](std::FILE* f) {
    put(f, xml);
    for (const auto* a : arrays) {
      const std::uint64_t n = a->size() * sizeof(float);
      put(f, &n, sizeof n);
      put(f, a->data(), n);
    }
    put(f, "\n</AppendedData>\n</VTKFile>\n");
  });
}

}  // namespace

void write_vti(const std::string& path, const VolumeGrid& g, const TimeStepData& d, const std::array<bool, kFieldCount>& has) {
  write_vti_to(write_file_atomically, path, g, d, has);
}

void write_vti(OutputGroup& group, const std::string& path, const VolumeGrid& g, const TimeStepData& d,
               const std::array<bool, kFieldCount>& has) {
  write_vti_to([&](const std::string& p, const std::function<void(std::FILE*)>& w) { group.write(p, w); }, path, g, d, has);
}

}  // namespace cv::core
