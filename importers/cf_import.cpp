// CF / ERA5 pressure-level files to a CloudVolume: horizontal mapping (wrap, date line, descending
// and uneven latitudes, subsetting), heights from geopotential, the physics of the conversion, and
// the consistency checks of the import report.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <memory>
#include <exception>
#include <numeric>
#include <optional>
#include <thread>

#include <sys/mman.h>
#include <unistd.h>

#include "checks.hpp"
#include "cf_layout.hpp"
#include "column.hpp"
#include "diagnosed_cloud.hpp"
#include "wrf_import.hpp"
#include "importer.hpp"
#include "io/input_file.hpp"
#include "io/parallel.hpp"
#include "physics/physics.hpp"

namespace cv::importers {
namespace {

constexpr double kRd = 287.05;        // dry-air gas constant, J/(kg K)
constexpr double kG0 = 9.80665;       // m/s2
const double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string fmt(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.6g", v);
  return b;
}

// Output longitude columns: source index for each, and the regular output axis.
struct LonMap {
  std::vector<int> src;
  core::RegularAxis axis;
};

LonMap map_longitudes(const std::vector<double>& raw, const std::optional<Region>& region, int stride,
                      const std::string& where, std::vector<std::string>& notes) {
  const int n = static_cast<int>(raw.size());
  if (n < 2) throw ImportError(where + ": " + std::to_string(n) + " longitude(s), expected at least 2");
  // Sort the longitudes on the circle, dropping a duplicated wrap column (x and x + 360).
  std::vector<std::pair<double, int>> s;
  for (int i = 0; i < n; ++i) s.push_back({std::fmod(std::fmod(raw[static_cast<std::size_t>(i)], 360.0) + 360.0, 360.0), i});
  std::sort(s.begin(), s.end());
  std::vector<std::pair<double, int>> u;
  for (const auto& p : s) {
    if (!u.empty() && std::abs(p.first - u.back().first) < 1e-6) {
      notes.push_back("longitude column " + std::to_string(p.second) + " repeats column " + std::to_string(u.back().second) +
                      " (wrap column): dropped");
      continue;
    }
    u.push_back(p);
  }
  if (u.size() > 1 && 360.0 - u.back().first + u.front().first < 1e-6) u.pop_back();
  const int m = static_cast<int>(u.size());
  // Where the circle is cut: the one gap that differs from the grid's step. On a regional grid that
  // is the gap from its east edge round to its west edge (larger than the step); on a global grid
  // whose columns do not divide 360 it is the wrap gap (smaller than the step). The step is the
  // median gap (the smaller of two for a two-column grid); an evenly spaced circle is cut at 0.
  std::vector<double> gaps(static_cast<std::size_t>(m));  // gaps[i]: from column i - 1 to column i
  for (int i = 0; i < m; ++i) {
    gaps[static_cast<std::size_t>(i)] = i == 0 ? 360.0 - u.back().first + u.front().first
                                               : u[static_cast<std::size_t>(i)].first - u[static_cast<std::size_t>(i - 1)].first;
  }
  std::vector<double> sorted_gaps = gaps;
  std::sort(sorted_gaps.begin(), sorted_gaps.end());
  const double typical = m == 2 ? sorted_gaps.front() : sorted_gaps[static_cast<std::size_t>(m / 2)];
  int start = 0, odd = 0;
  for (int i = 0; i < m; ++i) {
    if (std::abs(gaps[static_cast<std::size_t>(i)] - typical) > 1e-3 * typical) {
      if (odd++ == 0) start = i;
    }
  }
  if (odd == 1 && gaps[static_cast<std::size_t>(start)] < typical) {
    notes.push_back("longitudes every " + fmt(typical) + " degrees do not close the circle evenly (the gap from " +
                    fmt(u[static_cast<std::size_t>((start + m - 1) % m)].first) + " to " +
                    fmt(u[static_cast<std::size_t>(start)].first) + " is " + fmt(gaps[static_cast<std::size_t>(start)]) +
                    " degrees): read as a regional grid cut there");
  }
  std::vector<double> lon;
  std::vector<int> idx;
  for (int k = 0; k < m; ++k) {
    const auto& p = u[static_cast<std::size_t>((start + k) % m)];
    double x = p.first;
    if (!lon.empty()) {
      while (x < lon.back()) x += 360.0;
    }
    lon.push_back(x);
    idx.push_back(p.second);
  }
  const double step = (lon.back() - lon.front()) / (m - 1);
  for (int k = 1; k < m; ++k) {
    const double d = lon[static_cast<std::size_t>(k)] - lon[static_cast<std::size_t>(k - 1)];
    if (std::abs(d - step) > 1e-3 * step) {
      throw ImportError(where + ": longitudes are not evenly spaced (step " + fmt(d) + " after " + fmt(lon[static_cast<std::size_t>(k - 1)]) +
                        ", expected " + fmt(step) + ")");
    }
  }
  const bool global = std::abs(step * m - 360.0) < 1e-3 * step;
  // Express longitudes in -180..540 starting at the western edge (a box across 180 stays contiguous).
  double west = lon.front();
  if (west >= 180.0) west -= 360.0;
  for (auto& x : lon) x += west - lon.front();
  std::vector<int> keep;
  double first = 0.0;
  if (region) {
    const double w = std::fmod(std::fmod(region->lon_west_deg, 360.0) + 360.0, 360.0);
    double width = std::fmod(std::fmod(region->lon_east_deg - region->lon_west_deg, 360.0) + 360.0, 360.0);
    if (width == 0.0) width = 360.0;
    auto inside = [&](int k) {
      return std::fmod(std::fmod(lon[static_cast<std::size_t>(k)] - w, 360.0) + 360.0, 360.0) <= width + 1e-9;
    };
    // Start at the box's western edge: the first column inside whose western neighbour is outside
    // (on a global grid the neighbour of column 0 is the last column).
    int s0 = -1;
    for (int k = 0; k < m && s0 < 0; ++k) {
      const bool prev_in = k > 0 ? inside(k - 1) : (global && inside(m - 1));
      if (inside(k) && !prev_in) s0 = k;
    }
    if (s0 < 0 && inside(0)) s0 = 0;  // the box covers every column
    for (int k = s0; s0 >= 0 && k < s0 + m && (global || k < m) && inside(k % m); ++k) keep.push_back(k);
    if (!keep.empty()) {
      first = lon[static_cast<std::size_t>(s0)];
      if (first >= 180.0) first -= 360.0;  // the box's western edge, in -180..180
    }
    if (keep.empty()) throw ImportError(where + ": the region's longitudes hold no grid column of the file");
  } else {
    for (int k = 0; k < m; ++k) keep.push_back(k);
    first = lon.front();
  }
  LonMap out;
  for (std::size_t k = 0; k < keep.size(); k += static_cast<std::size_t>(stride)) {
    out.src.push_back(idx[static_cast<std::size_t>(keep[k] % m)]);
  }
  out.axis = {first, step * stride, static_cast<int>(out.src.size())};
  return out;
}

// Output latitude rows: a regular ascending axis; each row interpolates two source rows.
struct LatMap {
  std::vector<int> j0, j1;
  std::vector<double> w;  // weight of j1
  core::RegularAxis axis;
};

LatMap map_latitudes(const std::vector<double>& raw, const std::optional<Region>& region, int stride,
                     const std::string& where, std::vector<std::string>& notes) {
  const int n = static_cast<int>(raw.size());
  if (n < 2) throw ImportError(where + ": " + std::to_string(n) + " latitude(s), expected at least 2");
  std::vector<int> order(static_cast<std::size_t>(n));
  std::iota(order.begin(), order.end(), 0);
  const bool descending = raw.front() > raw.back();
  if (descending) std::reverse(order.begin(), order.end());
  std::vector<double> lat;
  for (int i : order) lat.push_back(raw[static_cast<std::size_t>(i)]);
  for (int k = 1; k < n; ++k) {
    if (!(lat[static_cast<std::size_t>(k)] > lat[static_cast<std::size_t>(k - 1)])) {
      throw ImportError(where + ": latitudes are not monotonic (at index " + std::to_string(k) + ")");
    }
  }
  if (lat.front() < -90.0 - 1e-9 || lat.back() > 90.0 + 1e-9) {
    throw ImportError(where + ": latitudes run from " + fmt(lat.front()) + " to " + fmt(lat.back()) + ", expected within -90..90");
  }
  if (descending) notes.push_back("latitudes run north to south in the file; flipped to ascending");
  const double step0 = (lat.back() - lat.front()) / (n - 1);
  bool even = true;
  for (int k = 1; k < n; ++k) {
    even &= std::abs(lat[static_cast<std::size_t>(k)] - lat[static_cast<std::size_t>(k - 1)] - step0) < 1e-3 * step0;
  }
  if (!even) notes.push_back("latitudes are unevenly spaced (Gaussian grid): resampled linearly onto an even grid");
  double lo = lat.front(), hi = lat.back();
  if (region) {
    lo = std::max(lo, region->lat_south_deg);
    hi = std::min(hi, region->lat_north_deg);
    if (lo > hi) throw ImportError(where + ": the region's latitudes hold no grid row of the file");
    // Snap to the file's rows so an even grid keeps exactly its own values.
    lo = lat.front() + std::ceil((lo - lat.front()) / step0 - 1e-9) * step0;
    hi = lat.front() + std::floor((hi - lat.front()) / step0 + 1e-9) * step0;
  }
  const int count = static_cast<int>(std::floor((hi - lo) / (step0 * stride) + 1e-9)) + 1;
  if (hi < lo || count < 1) {
    throw ImportError(where + ": the region's latitudes fall between two grid rows; expected at least one row");
  }
  LatMap out;
  out.axis = {lo, step0 * stride, count};
  for (int r = 0; r < count; ++r) {
    const double y = out.axis.at(r);
    const auto it = std::lower_bound(lat.begin(), lat.end(), y - 1e-9 * step0);
    int k = static_cast<int>(it - lat.begin());
    k = std::clamp(k, 1, n - 1);
    const double a = lat[static_cast<std::size_t>(k - 1)], b = lat[static_cast<std::size_t>(k)];
    double w = std::clamp((y - a) / (b - a), 0.0, 1.0);
    if (std::abs(w - 1.0) < 1e-9) w = 1.0;
    if (std::abs(w) < 1e-9) w = 0.0;
    out.j0.push_back(order[static_cast<std::size_t>(k - 1)]);
    out.j1.push_back(order[static_cast<std::size_t>(k)]);
    out.w.push_back(w);
  }
  return out;
}

// One variable's per-time-step slab and its strides in source index space. Slabs are float (half
// the memory) except the geopotential, kept in double so every step's level heights agree to the
// last digit with the probe that fixed the altitude grid.
struct Slab {
  std::vector<float> f;
  std::vector<double> d;
  std::size_t s_lon = 0, s_lat = 0, s_lev = 0;
  int i_off = 0, j_off = 0, k_off = 0;  // the read starts here in the file's index space
  double at(int i, int j, int k) const {
    const std::size_t n = static_cast<std::size_t>(i - i_off) * s_lon + static_cast<std::size_t>(j - j_off) * s_lat +
                          (s_lev ? static_cast<std::size_t>(k - k_off) * s_lev : 0);
    return d.empty() ? f[n] : d[n];
  }
};

// A run of output columns [x0, x1) whose file columns are consecutive from src (the longitude map
// of a global file is one or two such runs).
struct LonRun {
  std::size_t x0 = 0, x1 = 0;
  int src = 0;
};
std::vector<LonRun> lon_runs(const std::vector<int>& src) {
  std::vector<LonRun> runs;
  for (std::size_t x = 0; x < src.size();) {
    std::size_t e = x + 1;
    while (e < src.size() && src[e] == src[e - 1] + 1) ++e;
    runs.push_back({x, e, src[x]});
    x = e;
  }
  return runs;
}

// One role's values along a row of one level: the slab's one or two file rows (weights w and
// 1 - w between them, as the output row's latitude falls) and its stride along longitude, so a
// value is one index and no more (value() in load_era5_step's rows: the same arithmetic).
struct RoleRow {
  const float* f0 = nullptr;
  const float* f1 = nullptr;
  const double* d0 = nullptr;
  const double* d1 = nullptr;
  std::size_t s_lon = 0;
  int i_off = 0;
  double w = 0.0;
  // Only rows with weight are read: the slab may hold no more than those.
  RoleRow(const Slab& s, int j0, int j1, double w_, int k) : s_lon(s.s_lon), i_off(s.i_off), w(w_) {
    const std::size_t lev = s.s_lev ? static_cast<std::size_t>(k - s.k_off) * s.s_lev : 0;
    const int ja = w == 1.0 ? j1 : j0, jb = w == 0.0 ? j0 : j1;
    const std::size_t a = static_cast<std::size_t>(ja - s.j_off) * s.s_lat + lev, b = static_cast<std::size_t>(jb - s.j_off) * s.s_lat + lev;
    if (s.d.empty()) f0 = s.f.data() + a, f1 = s.f.data() + b;
    else d0 = s.d.data() + a, d1 = s.d.data() + b;
  }
  RoleRow() = default;
  // The values of the file columns that `runs` map the output columns to, into out: at() of each,
  // with the row's weight and type tested once for the row, not once per value, and each run of
  // consecutive file columns read as one stretch (a gather through the column map, value by value,
  // waited on memory: a third of the conversion's row work).
  void fill(const std::vector<LonRun>& runs, double* out) const {
    const bool one = w == 0.0 || w == 1.0;
    auto run = [&](const auto* p0, const auto* p1) {
      for (const LonRun& r : runs) {
        const std::size_t first = static_cast<std::size_t>(r.src - i_off) * s_lon, n = r.x1 - r.x0;
        double* o = out + r.x0;
        const auto* a = p0 + first;
        const auto* b = p1 + first;
        if (one && s_lon == 1) {
          for (std::size_t x = 0; x < n; ++x) o[x] = a[x];
        } else if (one) {
          for (std::size_t x = 0; x < n; ++x) o[x] = a[x * s_lon];
        } else if (s_lon == 1) {
          for (std::size_t x = 0; x < n; ++x) o[x] = (1.0 - w) * a[x] + w * b[x];
        } else {
          for (std::size_t x = 0; x < n; ++x) o[x] = (1.0 - w) * a[x * s_lon] + w * b[x * s_lon];
        }
      }
    };
    if (d0) run(d0, d1);
    else run(f0, f1);
  }
  double at(int i) const {
    const std::size_t n = static_cast<std::size_t>(i - i_off) * s_lon;
    if (d0) {
      if (w == 0.0 || w == 1.0) return d0[n];
      return (1.0 - w) * d0[n] + w * d1[n];
    }
    if (w == 0.0 || w == 1.0) return f0[n];
    return (1.0 - w) * f0[n] + w * f1[n];
  }
};

}  // namespace

double isa_altitude_m(double p_pa) {
  constexpr double p0 = 101325.0, t0 = 288.15, lapse = 0.0065, p11 = 22632.06, t11 = 216.65;
  if (p_pa >= p11) return t0 / lapse * (1.0 - std::pow(p_pa / p0, kRd * lapse / kG0));
  return 11000.0 + kRd * t11 / kG0 * std::log(p11 / p_pa);
}

double isa_pressure_pa(double z) {
  if (z <= 11000.0) return 101325.0 * std::pow(1.0 - 0.0065 * z / 288.15, kG0 / (kRd * 0.0065));
  return 22632.06 * std::exp(-(z - 11000.0) * kG0 / (kRd * 216.65));
}

double isa_temperature_k(double altitude_m) { return altitude_m < 11000.0 ? 288.15 - 0.0065 * altitude_m : 216.65; }

struct Era5Source {
  std::unique_ptr<NcFile> file;
  CfLayout layout;
  LonMap lon;
  LatMap lat;
  std::vector<int> levels;            // source level indices kept, bottom (highest pressure) first
  std::vector<double> level_pa;       // pressure levels; the reference pressure of other kinds
  std::vector<double> level_z;        // height levels, metres
  std::vector<double> hyb_a, hyb_b;   // hybrid levels: p = a + b ps
  std::vector<int> steps;             // source time indices, in output order
  ImportOptions options;
  bool diagnose = false;  // a cloud diagnosed from relative humidity (the file has none)
  DiagnosedCloudScheme scheme;
  std::string scheme_text;
  // The index ranges of the file that the region, stride and levels need (inclusive): reads cover
  // only these.
  int lon_lo = 0, lon_hi = 0, lat_lo = 0, lat_hi = 0, lev_lo = 0, lev_hi = 0;
  // Per-step input slabs, kept between steps so their memory is reused (loads are sequential).
  mutable std::vector<Slab> scratch = std::vector<Slab>(kRoleCount);
  // The next band's slabs, read while the workers convert the band in `scratch`.
  mutable std::vector<Slab> scratch_next = std::vector<Slab>(kRoleCount);
  // The first step's half-float arrays with part of their pages already touched (FirstStepPages),
  // taken by the first load; empty after it, or when there are none.
  mutable std::array<core::HalfBuffer, core::kFieldCount> first_halves;
};

namespace {

// The first step's half-float arrays, their pages first touched on a core that is otherwise idle
// while the file is opened (the level scan and the altitude probe read the file from one thread).
//
// Why: on the team's VM (one that hands freed memory back to its host) the first write to each
// fresh page is slow, 1.5 ms per MB or more whether or not the kernel populated it first, so a
// global step's 670 MB of half floats cost its first load about a second more than the later
// loads, which reuse them (docs/BENCHMARKS.md). Touching them here takes part of that off the
// import's path, on the core the open leaves free; on other machines the same holds for the
// ordinary page faults, a few tenths of a second for a global step.
//
// The grid's level count is known only at the end of the open, so the arrays are reserved for
// more levels than the step is expected to have (virtual memory only) and their planes (one level
// of one field) touched bottom up, to the expected count at most, until finish() says how many
// there are; pages touched beyond them are given back, and planes not reached are faulted in then.
class FirstStepPages {
 public:
  // `fields`: the fields the step will hold as half floats; `plane`: values per level; room for
  // `reserve_planes` levels, of which at most `touch_planes` are touched. Nothing happens (the
  // step makes its own arrays) where the room cannot be had or the thread cannot start.
  FirstStepPages(const std::vector<int>& fields, std::size_t plane, std::size_t reserve_planes, std::size_t touch_planes)
      : fields_(fields), plane_(plane), reserve_planes_(reserve_planes), touch_planes_(std::min(touch_planes, reserve_planes)) {
    if (fields_.empty() || plane_ == 0 || touch_planes_ == 0) return;
    try {
      for (int f : fields_) buffers_[static_cast<std::size_t>(f)].resize(plane_ * reserve_planes_);  // reserved, not written
      thread_ = std::thread([this] { touch(); });
    } catch (const std::exception&) {  // no memory or no thread: only the head start is lost
      for (auto& b : buffers_) core::HalfBuffer().swap(b);
    }
  }
  ~FirstStepPages() { stop(); }
  FirstStepPages(const FirstStepPages&) = delete;
  FirstStepPages& operator=(const FirstStepPages&) = delete;

  // Stops the touching and, when the step's `planes` levels fit, moves the arrays into `into`
  // (sized for them); otherwise they are dropped and the step makes its own.
  void finish(std::size_t planes, std::array<core::HalfBuffer, core::kFieldCount>& into) {
    stop();
    if (planes > reserve_planes_) return;
    const long page_size = ::sysconf(_SC_PAGESIZE);
    for (int f : fields_) {
      core::HalfBuffer& b = buffers_[static_cast<std::size_t>(f)];
      if (b.empty()) continue;
      // The whole pages past the step's values that were touched: handed back to the system.
      const std::uintptr_t used = reinterpret_cast<std::uintptr_t>(b.data() + plane_ * planes);
      // (The plane being touched when the thread stopped counts: some fields' were.)
      const std::size_t reached_planes = std::min(std::max(planes, touched_ + 1), reserve_planes_);
      const std::uintptr_t reached = reinterpret_cast<std::uintptr_t>(b.data() + plane_ * reached_planes);
      if (page_size > 0) {
        const std::uintptr_t page = static_cast<std::uintptr_t>(page_size);
        const std::uintptr_t lo = (used + page - 1) / page * page, hi = reached / page * page;
        if (hi > lo) (void)::madvise(reinterpret_cast<void*>(lo), hi - lo, MADV_DONTNEED);
      }
      // The planes not reached are faulted in as a fresh step's are (the first write then costs what
      // it would have).
      if (planes > touched_) core::populate_pages(b.data() + plane_ * touched_, plane_ * (planes - touched_) * sizeof(std::uint16_t));
      b.resize(plane_ * planes);  // smaller: the capacity (and the touched pages) stay
      into[static_cast<std::size_t>(f)] = std::move(b);
    }
  }

 private:
  void stop() {
    stop_.store(true);
    if (thread_.joinable()) thread_.join();
  }
  void touch() {
    const std::size_t page = 4096;  // at most the page size: every page is written at least once
    for (std::size_t z = 0; z < touch_planes_; ++z) {
      for (int f : fields_) {
        if (stop_.load(std::memory_order_relaxed)) return;
        std::uint16_t* p = buffers_[static_cast<std::size_t>(f)].data() + plane_ * z;
        volatile unsigned char* c = reinterpret_cast<unsigned char*>(p);
        const std::size_t bytes = plane_ * sizeof(std::uint16_t);
        // Faulted in as one range first (one fault per page costs far more on this VM), then written.
        const std::uintptr_t lo = (reinterpret_cast<std::uintptr_t>(p) + page - 1) / page * page;
        const std::uintptr_t hi = (reinterpret_cast<std::uintptr_t>(p) + bytes) / page * page;
#ifdef MADV_POPULATE_WRITE
        if (hi > lo) (void)::madvise(reinterpret_cast<void*>(lo), hi - lo, MADV_POPULATE_WRITE);
#endif
        for (std::size_t at = 0; at < bytes; at += page) c[at] = 0;
        c[bytes - 1] = 0;
      }
      touched_ = z + 1;  // read after the join
    }
  }

  std::vector<int> fields_;
  std::size_t plane_, reserve_planes_, touch_planes_;
  std::array<core::HalfBuffer, core::kFieldCount> buffers_;
  std::size_t touched_ = 0;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// Reads into `s`, reusing its memory: the region's rows, or rows j_lo .. j_hi of the file when
// given (j_lo >= 0).
void read_slab_into(Slab& s, const Era5Source& S, const NcVar& v, int time_index, UnpackInfo* info, bool as_double,
                    int j_lo = -1, int j_hi = -1) {
  const NcFile& f = *S.file;
  const CfLayout& L = S.layout;
  if (j_lo < 0) j_lo = S.lat_lo, j_hi = S.lat_hi;
  s.s_lon = s.s_lat = s.s_lev = 0;
  s.i_off = s.j_off = s.k_off = 0;
  std::vector<std::size_t> start(v.dims.size(), 0), count(v.dims.size(), 0);
  std::size_t stride = 1;
  for (int a = static_cast<int>(v.dims.size()) - 1; a >= 0; --a) {
    const int d = v.dims[static_cast<std::size_t>(a)];
    const std::size_t len = f.dims()[static_cast<std::size_t>(d)].length;
    std::size_t c = len, first = 0;
    auto range = [&](int lo, int hi, int& off) {
      first = static_cast<std::size_t>(lo);
      c = static_cast<std::size_t>(hi - lo + 1);
      off = lo;
    };
    if (d == L.time.dim) first = static_cast<std::size_t>(time_index), c = 1;
    if (d == L.lon.dim) range(S.lon_lo, S.lon_hi, s.i_off), s.s_lon = stride;
    if (d == L.lat.dim) range(j_lo, j_hi, s.j_off), s.s_lat = stride;
    if (d == L.vertical.dim) range(S.lev_lo, S.lev_hi, s.k_off), s.s_lev = stride;
    start[static_cast<std::size_t>(a)] = first;
    count[static_cast<std::size_t>(a)] = c;
    stride *= c;
  }
  if (as_double) {
    s.f.clear();
    f.read_into(s.d, v, start, count, info);
  } else {
    s.d.clear();
    f.read_float_into(s.f, v, start, count, info);
  }
}

// Whether any cloud variable holds cloud on source level k at time index t, within the region:
// a fraction of at least kZeroCloudFraction or water above kZeroWater (int16 packing leaves noise
// below both where there is none).
bool level_has_cloud(const Era5Source& S, int k, int time_index) {
  const CfLayout& L = S.layout;
  for (Role r : {Role::CloudFraction, Role::Liquid, Role::Ice, Role::Snow}) {
    const NcVar* v = L.roles[static_cast<int>(r)];
    if (!v) continue;
    std::vector<std::size_t> start(v->dims.size(), 0), count(v->dims.size(), 1);
    for (std::size_t a = 0; a < v->dims.size(); ++a) {
      const int d = v->dims[a];
      if (d == L.time.dim) start[a] = static_cast<std::size_t>(time_index);
      if (d == L.vertical.dim) start[a] = static_cast<std::size_t>(k);
      if (d == L.lon.dim) start[a] = static_cast<std::size_t>(S.lon_lo), count[a] = static_cast<std::size_t>(S.lon_hi - S.lon_lo + 1);
      if (d == L.lat.dim) start[a] = static_cast<std::size_t>(S.lat_lo), count[a] = static_cast<std::size_t>(S.lat_hi - S.lat_lo + 1);
    }
    const double threshold = (r == Role::CloudFraction ? kZeroCloudFraction : kZeroWater) / L.role_scale[static_cast<int>(r)];
    if (S.file->any_at_least(*v, start, count, threshold)) return true;
  }
  return false;
}

Slab read_slab(const Era5Source& S, const NcVar& v, int time_index, UnpackInfo* info, bool as_double) {
  Slab s;
  read_slab_into(s, S, v, time_index, info, as_double);
  return s;
}

}  // namespace

// What one conversion worker owns: a row of level samples, the running state of the hypsometric
// integration up each column, its consistency counts, and the error that stopped it, if any.
struct RowWork {
  RowLevels levels;  // the row's level samples, level-major
  PlaceRowScratch place;  // place_row's working arrays: the workers' threads are new for every band
  StoredStats stored;  // ranges of the values the row's conversion stored
  std::vector<double> z_prev, p_prev, tv_prev;
  // Per column of the row: the surface geopotential height and geometric altitude, and the surface
  // pressure (hybrid levels), found once per row instead of once per level.
  std::vector<double> zsurf, zsurf_geometric, p_surface;
  // One level's values of each role read, per column of the row (RoleRow::fill).
  std::array<std::vector<double>, kRoleCount> role_values;
  std::vector<double> snow;  // a level's snow, checked before it joins the ice
  std::size_t negative_water = 0, clamped_cf = 0;
  double worst_negative = 0.0;
  ColumnCounts counts;
  std::exception_ptr error;
};

void load_era5_step(const Era5Source& S, const core::VolumeGrid& grid, std::size_t step, core::ImportReport& report,
                    core::TimeStepData& out) {
  const CfLayout& L = S.layout;
  const std::string& path = S.file->path();
  const int t = S.steps[step];
  // The band the workers convert, and the one the reading thread fills meanwhile.
  std::vector<Slab>* slab_now = &S.scratch;
  std::vector<Slab>* slab_next = &S.scratch_next;
  bool have[kRoleCount] = {};
  const bool diagnose = S.diagnose;
  // The variables read: every role present, relative humidity only for a diagnosed cloud (humidity
  // of the file's own cloud is not needed).
  std::vector<int> roles_read;
  for (int r = 0; r < kRoleCount; ++r) {
    if (!L.roles[r]) continue;
    if (static_cast<Role>(r) == Role::RelativeHumidity && !diagnose) continue;
    have[r] = true;
    roles_read.push_back(r);
    auto& use = report.use(role_name(static_cast<Role>(r)));
    use.variable = L.roles[r]->name;
    use.units = L.roles[r]->text("units");
  }
  // Reads a band of the file's rows for every role: rows j_lo .. j_hi, of which rows j_lo .. j_own
  // are counted in the report's "before" ranges (each row is counted by one band only). The
  // slabs hold a band, not the step: a global step's slabs were 900 MB of fresh memory.
  bool first_band = true;
  auto read_band = [&](std::vector<Slab>& slab, int j_lo, int j_hi, int j_own) {
    for (int r : roles_read) {
      UnpackInfo info;
      const bool heights = static_cast<Role>(r) == Role::Geopotential || static_cast<Role>(r) == Role::GeopotentialHeight;
      Slab& sl = slab[static_cast<std::size_t>(r)];
      read_slab_into(sl, S, *L.roles[r], t, &info, heights, j_lo, j_hi);
      auto& use = report.use(role_name(static_cast<Role>(r)));
      // The owned rows, level by level (a row's longitudes are contiguous in the usual layout).
      // On the reading thread alone: the cores are converting the band before this one.
      const std::size_t nlon = static_cast<std::size_t>(S.lon_hi - S.lon_lo + 1), nk = sl.s_lev ? static_cast<std::size_t>(S.lev_hi - S.lev_lo + 1) : 1;
      core::ValueStats st;
      for (std::size_t k = 0; k < nk; ++k) {
        for (int j = j_lo; j <= j_own; ++j) {
          const std::size_t base = static_cast<std::size_t>(j - sl.j_off) * sl.s_lat + k * sl.s_lev;
          if (sl.s_lon == 1) {
            if (!sl.f.empty()) st.add_all(sl.f.data() + base, nlon);
            if (!sl.d.empty()) st.add_all(sl.d.data() + base, nlon);
          } else {
            for (std::size_t i = 0; i < nlon; ++i) {
              const std::size_t at = base + i * sl.s_lon;
              st.add(sl.f.empty() ? sl.d[at] : static_cast<double>(sl.f[at]));
            }
          }
        }
      }
      use.before.merge(st);
      if (first_band && info.packed && use.conversion.empty()) {
        use.conversion = "unpacked x * " + fmt(info.scale) + " + " + fmt(info.offset) + "; ";
      }
      // Units to the conversion's: % to 0..1, g/kg to kg/kg.
      if (const double k = L.role_scale[r]; k != 1.0) {
        for (float& x : sl.f) x = static_cast<float>(x * k);
        for (double& x : sl.d) x *= k;
        const std::string what = "x " + fmt(k) + " (units '" + use.units + "'); ";
        if (use.conversion.find(what) == std::string::npos) use.conversion += what;
      }
    }
    first_band = false;
  };
  const int nlev = static_cast<int>(S.levels.size());
  Slab ps, zs;
  if (L.vertical_kind == Vertical::Hybrid) ps = read_slab(S, *L.surface_pressure, t, nullptr, true);
  if (L.surface_geopotential) zs = read_slab(S, *L.surface_geopotential, t, nullptr, true);
  auto surf = [&](const Slab& sl, int i, int j0, int j1, double w) {
    if (w == 0.0) return sl.at(i, j0, 0);
    if (w == 1.0) return sl.at(i, j1, 0);
    return (1.0 - w) * sl.at(i, j0, 0) + w * sl.at(i, j1, 0);
  };
  auto surface_pressure = [&](int i, int j0, int j1, double w) {
    const double v = surf(ps, i, j0, j1, w);
    return L.surface_pressure_is_log ? std::exp(v) : v;
  };
  const std::size_t row_len = static_cast<std::size_t>(grid.lon_deg.count);
  const int nx = grid.lon_deg.count, ny = grid.lat_deg.count;
  const bool has_cf = have[static_cast<int>(Role::CloudFraction)];
  auto alloc = [&](core::Field f, bool on) {
    auto& halves = out.halves[static_cast<std::size_t>(f)];
    if (on && S.options.half_fields) {
      out[f].clear();
      out[f].shrink_to_fit();
      // The first step takes the arrays whose pages were touched while the file was opened.
      auto& first = S.first_halves[static_cast<std::size_t>(f)];
      if (halves.capacity() < grid.points() && first.capacity() >= grid.points()) halves.swap(first);
      core::HalfBuffer().swap(first);
      const bool fresh = halves.capacity() < grid.points();
      core::reserve_exact(halves, grid.points());
      if (fresh) core::populate_pages(halves.data(), grid.points() * sizeof(std::uint16_t));
      // Not zeroed first (HalfBuffer): every node is written by its row's place_row, on every core.
      halves.resize(grid.points());
    } else if (on) {
      halves.clear();
      halves.shrink_to_fit();
      // Faulted in on every core: a fresh global field is 190 MB of pages to touch.
      const bool fresh = out[f].capacity() < grid.points();
      core::reserve_exact(out[f], grid.points());
      if (fresh) core::populate_pages(out[f].data(), grid.points() * sizeof(float));
      out[f].resize(grid.points());  // every node is written by its row's place_row, NaN where it has no data
    } else {
      out[f].clear();
      halves.clear();
    }
  };
  alloc(core::Field::ExtinctionLiquid, have[static_cast<int>(Role::Liquid)] || diagnose);
  alloc(core::Field::ExtinctionIce, have[static_cast<int>(Role::Ice)] || have[static_cast<int>(Role::Snow)] || diagnose);
  alloc(core::Field::CloudFraction, has_cf || diagnose);
  // The ground's altitude per column, where the file gives terrain.
  if (L.surface_geopotential) out.ground_m.assign(grid.columns(), std::numeric_limits<float>::quiet_NaN());
  else out.ground_m.clear();
  alloc(core::Field::WindU, have[static_cast<int>(Role::U)]);
  alloc(core::Field::WindV, have[static_cast<int>(Role::V)]);
  alloc(core::Field::WindW, have[static_cast<int>(Role::Omega)] || have[static_cast<int>(Role::UpwardVelocity)]);
  alloc(core::Field::Temperature, true);
  // Pressure where the file gives it (its pressure levels, or hybrid levels with the surface
  // pressure); on height levels it would be the standard atmosphere's, so it is not stored.
  alloc(core::Field::Pressure, L.vertical_kind != Vertical::Height);

  ConversionOptions conv{S.options.r_eff_liquid_um, S.options.r_eff_ice_um};
  // A latitude row at a time, levels outer and longitudes inner: the slabs are read along their
  // contiguous axis (a column's levels lie megabytes apart in a global file).
  auto bad = [&](Role r, double v, const char* expected) {
    throw ImportError(path + ": variable '" + L.roles[static_cast<int>(r)]->name + "' has value " + fmt(v) +
                      " at time step " + std::to_string(t) + ", expected " + expected);
  };
  auto has = [&](Role r) { return have[static_cast<int>(r)]; };
  // Rows are independent: workers take every n-th row, each with its own buffers and counts; an
  // error in any row stops the step with that row's message.
  const std::vector<LonRun> runs = lon_runs(S.lon.src);
  auto do_row = [&](int y, RowWork& W) {
    const int j0 = S.lat.j0[static_cast<std::size_t>(y)], j1 = S.lat.j1[static_cast<std::size_t>(y)];
    const double w = S.lat.w[static_cast<std::size_t>(y)];
    // The surface where the file gives it, once per column: as a geopotential height (hypsometric
    // start) and as a geometric altitude (heights above ground); a surface_altitude variable is the
    // latter already. And the surface pressure of hybrid levels.
    const bool given_altitude = L.surface_geopotential_scale != 1.0;
    for (int x = 0; x < nx; ++x) {
      const int i = S.lon.src[static_cast<std::size_t>(x)];
      const std::size_t X_ = static_cast<std::size_t>(x);
      const double surf_raw = L.surface_geopotential ? surf(zs, i, j0, j1, w) : 0.0;
      W.zsurf[X_] = given_altitude ? surf_raw * grid.earth_radius_m / (grid.earth_radius_m + surf_raw) : surf_raw / kG0;
      W.zsurf_geometric[X_] = given_altitude ? surf_raw : physics::f64::geopotential_to_height_m(surf_raw, grid.earth_radius_m);
      W.p_surface[X_] = L.vertical_kind == Vertical::Hybrid ? surface_pressure(i, j0, j1, w) : 0.0;
    }
    for (int l = 0; l < nlev; ++l) {
      const int k = S.levels[static_cast<std::size_t>(l)];
      for (int r : roles_read) {
        RoleRow((*slab_now)[static_cast<std::size_t>(r)], j0, j1, w, k).fill(runs, W.role_values[static_cast<std::size_t>(r)].data());
      }
      const double* role_value[kRoleCount];
      for (int r = 0; r < kRoleCount; ++r) role_value[r] = W.role_values[static_cast<std::size_t>(r)].data();
      // The level's quantities a row at a time, each in its own loop (the checks apart), written
      // where place_row reads them: the level's row of each of W.levels' arrays.
      RowLevels& R = W.levels;
      const std::size_t L_ = static_cast<std::size_t>(l), base = R.at(l, 0), n = row_len;
      double *const zr = R.z_m.data() + base, *const pr = R.p_pa.data() + base, *const tr = R.t_k.data() + base;
      double *const qvr = R.qv.data() + base, *const cfr = R.cf.data() + base, *const qlr = R.q_liquid.data() + base;
      double *const qir = R.q_ice.data() + base, *const ur = R.u.data() + base, *const vr = R.v.data() + base;
      double *const wr = R.w.data() + base;
      auto row_of = [&](Role r) { return role_value[static_cast<int>(r)]; };
      auto copy_or_nan = [&](Role r, double* dst) {
        if (has(r)) std::copy(row_of(r), row_of(r) + n, dst);
        else std::fill(dst, dst + n, kNaN);
      };
      switch (L.vertical_kind) {
        case Vertical::Pressure: std::fill(pr, pr + n, S.level_pa[L_]); break;
        case Vertical::Hybrid:
          for (std::size_t x = 0; x < n; ++x) pr[x] = S.hyb_a[L_] + S.hyb_b[L_] * W.p_surface[x];
          break;
        case Vertical::Height:
          for (std::size_t x = 0; x < n; ++x) pr[x] = isa_pressure_pa(S.level_z[L_] + (L.height_above_ground ? W.zsurf_geometric[x] : 0.0));
          break;
      }
      // Humidity, 0 where absent; the temperature as read (NaN where the file has none, filled below).
      if (has(Role::Humidity)) {
        const double* q = row_of(Role::Humidity);
        for (std::size_t x = 0; x < n; ++x) qvr[x] = std::isnan(q[x]) ? 0.0 : q[x];
      } else {
        std::fill(qvr, qvr + n, 0.0);
      }
      copy_or_nan(Role::Temperature, tr);
      // Height: geopotential -> geometric height on the sphere; else from the coordinate itself.
      if (has(Role::Geopotential)) {
        const double* g = row_of(Role::Geopotential);
        for (std::size_t x = 0; x < n; ++x) zr[x] = physics::f64::geopotential_to_height_m(g[x], grid.earth_radius_m);
      } else if (has(Role::GeopotentialHeight)) {
        const double* g = row_of(Role::GeopotentialHeight);
        for (std::size_t x = 0; x < n; ++x) zr[x] = physics::f64::geopotential_to_height_m(kG0 * g[x], grid.earth_radius_m);
      } else if (L.vertical_kind == Vertical::Height) {
        for (std::size_t x = 0; x < n; ++x) zr[x] = S.level_z[L_] + (L.height_above_ground ? W.zsurf_geometric[x] : 0.0);
      } else if (L.vertical_kind == Vertical::Hybrid) {
        // Hypsometric equation from the surface: dZ = R_d T_v / g0 d(ln p), in geopotential metres.
        for (std::size_t x = 0; x < n; ++x) {
          const double tv = tr[x] * (1.0 + 0.608 * qvr[x]);
          const double zgp = l == 0 ? W.zsurf[x] + kRd * tv / kG0 * std::log(W.p_surface[x] / pr[x])
                                    : W.z_prev[x] + kRd * 0.5 * (tv + W.tv_prev[x]) / kG0 * std::log(W.p_prev[x] / pr[x]);
          W.z_prev[x] = zgp, W.p_prev[x] = pr[x], W.tv_prev[x] = tv;
          zr[x] = physics::f64::geopotential_to_height_m(kG0 * zgp, grid.earth_radius_m);
        }
      } else {
        for (std::size_t x = 0; x < n; ++x) zr[x] = isa_altitude_m(pr[x]);
      }
      for (std::size_t x = 0; x < n; ++x) {
        if (!std::isnan(zr[x]) && (zr[x] < -1000.0 || zr[x] > 1.0e5)) {
          bad(has(Role::Geopotential) ? Role::Geopotential : Role::GeopotentialHeight, zr[x], "a height between -1 km and 100 km");
        }
      }
      if (!has(Role::Temperature)) {
        for (std::size_t x = 0; x < n; ++x) tr[x] = isa_temperature_k(zr[x]);
      }
      for (std::size_t x = 0; x < n; ++x) {
        if (!std::isnan(tr[x]) && (tr[x] < 100.0 || tr[x] > 400.0)) bad(Role::Temperature, tr[x], "a temperature between 100 and 400 K");
      }
      // Cloud fraction: tiny excursions from unpacking are clamped and counted; absurd values stop.
      copy_or_nan(Role::CloudFraction, cfr);
      if (has(Role::CloudFraction)) {
        for (std::size_t x = 0; x < n; ++x) {
          const double cf = cfr[x];
          if (std::isnan(cf) || (cf >= 0.0 && cf <= 1.0)) continue;
          if (cf < -0.01 || cf > 1.01) bad(Role::CloudFraction, cf, "a fraction between 0 and 1");
          ++W.clamped_cf;
          cfr[x] = std::clamp(cf, 0.0, 1.0);
        }
      }
      // Water: small negatives from unpacking are set to 0 and counted; absurd values stop.
      auto water_row = [&](Role r, double* dst) {
        for (std::size_t x = 0; x < n; ++x) {
          const double qw = dst[x];
          if (std::isnan(qw) || (qw >= 0.0 && qw <= 0.05)) continue;
          if (qw < -1e-5 || qw > 0.05) bad(r, qw, "a mixing ratio between 0 and 0.05 kg/kg");
          ++W.negative_water;
          W.worst_negative = std::min(W.worst_negative, qw);
          dst[x] = 0.0;
        }
      };
      copy_or_nan(Role::Liquid, qlr);
      if (has(Role::Liquid)) water_row(Role::Liquid, qlr);
      copy_or_nan(Role::Ice, qir);
      if (has(Role::Ice)) water_row(Role::Ice, qir);
      if (has(Role::Snow)) {
        // Snow adds to the ice (missing ice counts as none where there is snow).
        double* const qs = W.snow.data();
        std::copy(row_of(Role::Snow), row_of(Role::Snow) + n, qs);
        water_row(Role::Snow, qs);
        for (std::size_t x = 0; x < n; ++x) {
          if (!std::isnan(qs[x])) qir[x] = (std::isnan(qir[x]) ? 0.0 : qir[x]) + qs[x];
        }
      }
      if (diagnose) {
        for (std::size_t x = 0; x < n; ++x) {
          // Relative humidity from the file, or from specific humidity and q_sat(p, T).
          double rh = NAN;
          if (has(Role::RelativeHumidity)) rh = row_of(Role::RelativeHumidity)[x];
          else if (has(Role::Humidity)) rh = qvr[x] / saturation_specific_humidity(pr[x], tr[x]);
          if (std::isnan(rh) || std::isnan(tr[x])) continue;
          if (rh < -0.01 || rh > 2.0) bad(has(Role::RelativeHumidity) ? Role::RelativeHumidity : Role::Humidity, rh,
                                          "a relative humidity between 0 and 200 %");
          const DiagnosedBox box = diagnose_box(rh, pr[x], tr[x], S.scheme);
          cfr[x] = box.cloud_fraction;
          qlr[x] = box.q_liquid;
          qir[x] = box.q_ice;
        }
      }
      copy_or_nan(Role::U, ur);
      copy_or_nan(Role::V, vr);
      copy_or_nan(Role::UpwardVelocity, wr);
      // Omega (Pa/s) to w (m/s) by hydrostatics: w = -omega / (rho g).
      if (has(Role::Omega)) {
        const double* om = row_of(Role::Omega);
        for (std::size_t x = 0; x < n; ++x) {
          const double rho = pr[x] / (kRd * tr[x] * (1.0 + 0.608 * qvr[x]));
          wr[x] = -om[x] / (rho * kG0);
        }
      }
    }
    if (L.surface_geopotential) {
      for (int x = 0; x < nx; ++x) {
        const double raw = surf(zs, S.lon.src[static_cast<std::size_t>(x)], j0, j1, w);
        const double zg = L.surface_geopotential_scale != 1.0 ? raw : physics::f64::geopotential_to_height_m(raw, grid.earth_radius_m);
        out.ground_m[grid.column(x, y)] = static_cast<float>(zg);
      }
    }
    place_row(W.levels, grid, 0, y, conv, out, W.counts, &W.stored, W.place);
    };
  const unsigned hw = core::worker_count();  // the machine's cores, or CLOUDVIEWER_THREADS
  const int workers = static_cast<int>(std::min<unsigned>(std::min(hw, 8u), static_cast<unsigned>(std::max(1, ny / 4))));
  std::vector<RowWork> work(static_cast<std::size_t>(workers));
  for (auto& W : work) {
    W.levels.resize(nx, nlev);
    W.z_prev.resize(row_len), W.p_prev.resize(row_len), W.tv_prev.resize(row_len);
    W.zsurf.resize(row_len), W.zsurf_geometric.resize(row_len), W.p_surface.resize(row_len);
    for (int r : roles_read) W.role_values[static_cast<std::size_t>(r)].resize(row_len);
    W.snow.resize(row_len);
  }
  // Bands of kBandRows file rows: each output row goes with the band holding the lowest file row
  // it reads, and a band's read reaches as far as its rows need.
  constexpr int kBandRows = 32;
  const int bands = (S.lat_hi - S.lat_lo) / kBandRows + 1;
  std::vector<std::vector<int>> band_rows(static_cast<std::size_t>(bands));
  std::vector<int> band_hi(static_cast<std::size_t>(bands));
  for (int b = 0; b < bands; ++b) band_hi[static_cast<std::size_t>(b)] = std::min(S.lat_hi, S.lat_lo + (b + 1) * kBandRows - 1);
  for (int y = 0; y < ny; ++y) {
    const std::size_t yy = static_cast<std::size_t>(y);
    const int j0 = S.lat.j0[yy], j1 = S.lat.j1[yy];
    const double w = S.lat.w[yy];
    // The rows value() reads: j0 unless the weight is all j1's, j1 unless it is all j0's.
    const int lo = w == 1.0 ? j1 : w == 0.0 ? j0 : std::min(j0, j1), hi = w == 1.0 ? j1 : w == 0.0 ? j0 : std::max(j0, j1);
    const std::size_t b = static_cast<std::size_t>((lo - S.lat_lo) / kBandRows);
    band_rows[b].push_back(y);
    band_hi[b] = std::max(band_hi[b], hi);
  }
  for (int b = 0; b < bands; ++b) {
    const std::size_t bb = static_cast<std::size_t>(b);
    const int j_lo = S.lat_lo + b * kBandRows, j_own = std::min(S.lat_hi, j_lo + kBandRows - 1);
    // The next band is read on its own thread while the workers convert this one (netCDF is
    // called from that thread alone): the reads no longer leave a core idle.
    if (b == 0) read_band(*slab_now, j_lo, band_hi[bb], j_own);
    std::thread reader;
    std::exception_ptr read_error;
    struct JoinAtExit {  // so that an error below never leaves the reading thread running
      std::thread& t;
      ~JoinAtExit() {
        if (t.joinable()) t.join();
      }
    } join_reader{reader};
    if (b + 1 < bands) {
      const int n_lo = S.lat_lo + (b + 1) * kBandRows, n_own = std::min(S.lat_hi, n_lo + kBandRows - 1), n_hi = band_hi[bb + 1];
      reader = std::thread([&, n_lo, n_own, n_hi] {
        try {
          read_band(*slab_next, n_lo, n_hi, n_own);
        } catch (...) {
          read_error = std::current_exception();
        }
      });
    }
    const std::vector<int>& rows = band_rows[bb];
    auto run = [&](int wid) {
      RowWork& W = work[static_cast<std::size_t>(wid)];
      try {
        for (std::size_t n = static_cast<std::size_t>(wid); n < rows.size(); n += static_cast<std::size_t>(workers)) {
          do_row(rows[n], W);
        }
      } catch (...) {
        W.error = std::current_exception();
      }
    };
    std::vector<std::thread> threads;
    struct JoinAllAtExit {  // a thread that cannot be started must not leave the others running
      std::vector<std::thread>& ts;
      ~JoinAllAtExit() {
        for (auto& th : ts) {
          if (th.joinable()) th.join();
        }
      }
    } join_workers{threads};
    for (int wid = 1; wid < workers && static_cast<std::size_t>(wid) < rows.size(); ++wid) threads.emplace_back(run, wid);
    run(0);
    for (auto& th : threads) th.join();
    if (reader.joinable()) reader.join();
    for (auto& W : work) {
      if (W.error) std::rethrow_exception(W.error);
    }
    if (read_error) std::rethrow_exception(read_error);
    std::swap(slab_now, slab_next);
  }
  std::size_t negative_water = 0, clamped_cf = 0;
  double worst_negative = 0.0;
  ColumnCounts counts;
  StoredStats stored;
  for (auto& W : work) {
    if (W.error) std::rethrow_exception(W.error);
    negative_water += W.negative_water;
    clamped_cf += W.clamped_cf;
    worst_negative = std::min(worst_negative, W.worst_negative);
    counts.merge(W.counts);
    for (std::size_t f = 0; f < stored.size(); ++f) stored[f].merge(W.stored[f]);
  }
  // Every point the conversion did not store (no level pair around it) holds NaN: missing.
  for (auto& st : stored) st.missing = grid.points() - st.count;
  // Report: SI ranges, conversions, consistency.
  const double r_l = S.options.r_eff_liquid_um;
  auto after = [&](Role r, core::Field f, const std::string& conv) {
    if (!have[static_cast<int>(r)]) return;
    auto& use = report.use(role_name(r));
    if (use.conversion.find(conv) == std::string::npos) use.conversion += conv;
    use.after.merge(stored[static_cast<std::size_t>(f)]);
    use.after_units = core::field_units(f);
  };
  after(Role::Liquid, core::Field::ExtinctionLiquid,
        "LWC = rho q, rho = p / (287.05 T (1 + 0.608 q_v)); sigma = 3 LWC / (2 rho_w r_eff), r_eff " +
            fmt(r_l) + " um (grid-box mean, interpolated in altitude with the fraction) -> in-cloud liquid extinction = mean / fraction, 1/m");
  after(Role::Ice, core::Field::ExtinctionIce,
        std::string("IWC = rho q; sigma = 3 IWC / (2 917 kg/m3 r_eff), r_eff ") +
            (S.options.r_eff_ice_um > 0 ? fmt(S.options.r_eff_ice_um) + " um" : "50 + 0.5 T[C] um in 20..50") +
            " (grid-box mean, interpolated with the fraction) -> in-cloud ice extinction = mean / fraction, 1/m");
  after(Role::CloudFraction, core::Field::CloudFraction, "clamped to 0..1");
  if (diagnose) {
    auto& use = report.use("diagnosed cloud (not in the file)");
    use.variable = has(Role::RelativeHumidity) ? L.roles[static_cast<int>(Role::RelativeHumidity)]->name
                                                : L.roles[static_cast<int>(Role::Humidity)]->name;
    use.units = L.roles[static_cast<int>(has(Role::RelativeHumidity) ? Role::RelativeHumidity : Role::Humidity)]->text("units");
    use.conversion = S.scheme_text;
    use.after.merge(stored[static_cast<std::size_t>(core::Field::CloudFraction)]);
    use.after_units = "cloud fraction";
  }
  after(Role::U, core::Field::WindU, "interpolated in altitude");
  after(Role::V, core::Field::WindV, "interpolated in altitude");
  after(Role::Omega, core::Field::WindW, "w = -omega / (rho g0)");
  after(Role::UpwardVelocity, core::Field::WindW, "interpolated in altitude");
  after(Role::Temperature, core::Field::Temperature, "interpolated in altitude");
  auto used_for = [&](Role r, const std::string& what) {
    if (!have[static_cast<int>(r)]) return;
    auto& use = report.use(role_name(r));
    if (use.conversion.find(what) == std::string::npos) use.conversion += what;
  };
  used_for(Role::Geopotential, "level heights z = Phi R / (g0 R - Phi) (not stored)");
  used_for(Role::GeopotentialHeight, "level heights from Phi = g0 gh, z = Phi R / (g0 R - Phi) (not stored)");
  used_for(Role::Humidity, "virtual temperature for air density (not stored)");
  if (have[static_cast<int>(Role::CloudFraction)]) report.use(role_name(Role::CloudFraction)).clamped += clamped_cf;
  if (negative_water) {
    report.warn(std::to_string(negative_water) + " negative mixing ratios (down to " + fmt(worst_negative) +
                " kg/kg) set to 0 at time step " + std::to_string(t));
  }
  if (diagnose) {
    // The consistency of a file's own cloud fields; a diagnosed cloud is consistent by construction.
    counts.water_without_cf = counts.water_without_cf_significant = counts.cf_without_water = 0;
  }
  report_counts(counts, t, report);
}

namespace {
std::atomic<std::size_t> exact_median_count{0};
}  // namespace

std::size_t exact_median_passes() { return exact_median_count.load(std::memory_order_relaxed); }

core::CloudVolume import_file(const std::string& path, const ImportOptions& options) {
  auto S = std::make_shared<Era5Source>();
  S->file = std::make_unique<NcFile>(path);
  S->options = options;
  const NcFile& f = *S->file;
  if (is_wrf_file(f)) return import_wrf(std::move(S->file), options);
  if (is_wrf_geogrid_file(f)) throw ImportError(wrf_geogrid_message(f));
  S->layout = detect_cf_layout(f);
  CfLayout& L = S->layout;
  core::CloudVolume vol;
  vol.liquid_r_eff_um = options.r_eff_liquid_um;
  vol.report.file = path;
  vol.report.format = "CF pressure levels";
  for (const auto& n : L.notes) vol.report.notes.push_back(n);
  vol.report.notes.push_back("longitude '" + L.lon.var->name + "' recognised " + L.lon.how);
  vol.report.notes.push_back("latitude '" + L.lat.var->name + "' recognised " + L.lat.how);
  if (!has_cloud(L)) {
    const bool t = L.roles[static_cast<int>(Role::Temperature)], rh = L.roles[static_cast<int>(Role::RelativeHumidity)],
               q = L.roles[static_cast<int>(Role::Humidity)];
    std::string what = path + ": no cloud variable; expected at least one of cloud fraction (cc, fraction_of_cloud_cover, "
                       "GRIB 0-6-1/22/32), liquid (clwc, cloud_mixing_ratio, GRIB 0-1-22/83), ice (ciwc, "
                       "ice_water_mixing_ratio, GRIB 0-1-23/84) or snow";
    if (!options.diagnose_cloud) {
      if (t && (rh || q)) what += "; the file has temperature and humidity: --diagnose-cloud diagnoses a cloud from them";
      else if (t || rh || q) {
        what += std::string("; nor can one be diagnosed (--diagnose-cloud needs temperature and relative or specific humidity, "
                            "and the file has ") + (t ? "no humidity" : "no temperature") + ")";
      }
      if (!L.precipitation.empty()) what += " (precipitation alone, '" + L.precipitation.front() + "', is not cloud)";
      throw ImportError(what);
    }
    if (!t || !(rh || q)) {
      throw ImportError(path + ": --diagnose-cloud needs temperature and relative (or specific) humidity on the levels; "
                        "the file has " + (t ? "temperature" : "no temperature") + " and " +
                        (rh || q ? "humidity" : "no humidity"));
    }
    S->diagnose = true;
    S->scheme.rh_critical = options.rh_critical;
    const NcVar* hum = rh ? L.roles[static_cast<int>(Role::RelativeHumidity)] : L.roles[static_cast<int>(Role::Humidity)];
    S->scheme_text = "cloud fraction from Sundqvist et al. (1989), 1 - sqrt((1 - RH) / (1 - RH_c)), RH_c " + fmt(options.rh_critical) +
                     ", RH from '" + hum->name + "'" + (rh ? "" : " / q_sat") + "; in-cloud condensate " +
                     fmt(S->scheme.condensate_of_saturation) + " q_sat(p, T from '" +
                     L.roles[static_cast<int>(Role::Temperature)]->name +
                     "'), liquid share ((T - 250.16) / 23)^2 between -23 and 0 C";
    vol.report.warn("DIAGNOSED CLOUD: the file has no cloud field; the cloud shown is diagnosed from humidity (" +
                    S->scheme_text + "). See docs/importers.md, 'Diagnosed cloud'");
  }
  for (const auto& p : L.precipitation) {
    vol.report.notes.push_back("'" + p + "' (precipitation) is not part of the cloud volume");
  }
  if (L.roles[static_cast<int>(Role::Snow)]) {
    vol.report.notes.push_back("snow '" + L.roles[static_cast<int>(Role::Snow)]->name + "' is added to the cloud ice");
  }
  // Horizontal grid.
  S->lon = map_longitudes(L.lon.values, options.region, std::max(1, options.horizontal_stride),
                          path + ": coordinate '" + L.lon.var->name + "'", vol.report.notes);
  S->lat = map_latitudes(L.lat.values, options.region, std::max(1, options.horizontal_stride),
                         path + ": coordinate '" + L.lat.var->name + "'", vol.report.notes);
  vol.grid.lon_deg = S->lon.axis;
  vol.grid.lat_deg = S->lat.axis;
  // Levels: kept by (reference) pressure range, ordered bottom to top. Height levels get the
  // standard atmosphere's pressure as their reference; hybrid levels a + b 1013.25 hPa.
  struct Lev {
    double ref_pa;
    int k;
    double z;
  };
  std::vector<Lev> lev;
  for (std::size_t k = 0; k < L.vertical.values.size(); ++k) {
    const double value = L.vertical.values[k];
    double pa = 0.0, z = NAN;
    if (L.vertical_kind == Vertical::Pressure) {
      pa = value * L.pressure_scale_to_pa;
    } else if (L.vertical_kind == Vertical::Hybrid) {
      pa = L.hybrid_a_pa[k] + L.hybrid_b[k] * 101325.0;
    } else {
      z = value * L.height_scale_to_m;
      if (!(z > -1000.0 && z < 1.0e5)) {
        throw ImportError(path + ": level " + fmt(value) + " " + L.vertical.var->text("units") + " is not a height between -1 and 100 km");
      }
      pa = isa_pressure_pa(z);
    }
    if (!(pa > 0.0) || pa > 1.2e5) {
      throw ImportError(path + ": level " + fmt(value) + " of '" + L.vertical.var->name +
                        "' is not a pressure between 0 and 1200 hPa");
    }
    if (pa >= options.level_min_hpa * 100.0 && pa <= options.level_max_hpa * 100.0) lev.push_back({pa, static_cast<int>(k), z});
  }
  if (lev.size() < 2) throw ImportError(path + ": fewer than 2 levels in the requested range");
  const bool top_first = lev.front().ref_pa < lev.back().ref_pa;
  std::sort(lev.begin(), lev.end(), [](const Lev& a, const Lev& b) { return a.ref_pa > b.ref_pa; });
  if (top_first) vol.report.notes.push_back("levels are stored top first; ordered bottom to top");
  for (const Lev& l : lev) {
    S->level_pa.push_back(l.ref_pa);
    S->levels.push_back(l.k);
    S->level_z.push_back(l.z);
    if (L.vertical_kind == Vertical::Hybrid) {
      S->hyb_a.push_back(L.hybrid_a_pa[static_cast<std::size_t>(l.k)]);
      S->hyb_b.push_back(L.hybrid_b[static_cast<std::size_t>(l.k)]);
    }
  }
  const bool has_geo = L.roles[static_cast<int>(Role::Geopotential)] || L.roles[static_cast<int>(Role::GeopotentialHeight)];
  if (L.vertical_kind == Vertical::Hybrid) {
    vol.report.format = "CF hybrid sigma-pressure levels";
    if (!L.vertical.var->text("formula_terms").empty()) {
      vol.report.notes.push_back("pressure p = a + b ps from formula_terms '" + L.vertical.var->text("formula_terms") + "'");
    }
    if (!has_geo && !L.roles[static_cast<int>(Role::Temperature)]) {
      throw ImportError(path + ": hybrid levels without geopotential need temperature to find their heights; neither is in the file");
    }
    if (!has_geo) vol.report.notes.push_back("level heights from the hypsometric equation, integrated up from the surface");
    if (!has_geo && !L.surface_geopotential) vol.report.warn("no surface geopotential: the surface is taken at sea level");
  } else if (L.vertical_kind == Vertical::Height) {
    vol.report.format = "CF height levels";
    vol.report.warn("height levels: air pressure (for air density) comes from the standard atmosphere");
    if (L.height_above_ground && !L.surface_geopotential && !has_geo) {
      vol.report.warn("heights are above the ground but the file has no surface altitude: taken as above sea level");
    }
  }
  // What the reads must cover: the bounding ranges of the columns, rows and levels kept.
  S->lon_lo = *std::min_element(S->lon.src.begin(), S->lon.src.end());
  S->lon_hi = *std::max_element(S->lon.src.begin(), S->lon.src.end());
  S->lat_lo = std::numeric_limits<int>::max();
  S->lat_hi = std::numeric_limits<int>::min();
  for (std::size_t r = 0; r < S->lat.w.size(); ++r) {  // rows that carry weight
    for (const auto& [j, used] : {std::pair{S->lat.j0[r], S->lat.w[r] < 1.0}, std::pair{S->lat.j1[r], S->lat.w[r] > 0.0}}) {
      if (used) S->lat_lo = std::min(S->lat_lo, j), S->lat_hi = std::max(S->lat_hi, j);
    }
  }
  S->lev_lo = *std::min_element(S->levels.begin(), S->levels.end());
  S->lev_hi = *std::max_element(S->levels.begin(), S->levels.end());
  // Time steps.
  const int nt = static_cast<int>(L.times.size());
  const int last = options.time_last < 0 ? nt - 1 : std::min(options.time_last, nt - 1);
  for (int t = std::max(0, options.time_first); t <= last; t += std::max(1, options.time_stride)) {
    if (in_time_range(L.times[static_cast<std::size_t>(t)], options)) S->steps.push_back(t);
  }
  if (S->steps.empty()) {
    throw ImportError(path + ": no time step in the requested range; the file has " + std::to_string(nt) +
                      (nt ? ", from " + L.times.front().iso_utc + " to " + L.times.back().iso_utc : std::string()));
  }
  for (int t : S->steps) vol.times.push_back(L.times[static_cast<std::size_t>(t)]);
  // The fields a step holds (load_era5_step's allocations follow the same roles).
  vol.has_field[static_cast<int>(core::Field::ExtinctionLiquid)] = L.roles[static_cast<int>(Role::Liquid)] != nullptr || S->diagnose;
  vol.has_field[static_cast<int>(core::Field::ExtinctionIce)] =
      L.roles[static_cast<int>(Role::Ice)] != nullptr || L.roles[static_cast<int>(Role::Snow)] != nullptr || S->diagnose;
  vol.has_field[static_cast<int>(core::Field::CloudFraction)] = L.roles[static_cast<int>(Role::CloudFraction)] != nullptr || S->diagnose;
  vol.has_field[static_cast<int>(core::Field::WindU)] = L.roles[static_cast<int>(Role::U)] != nullptr;
  vol.has_field[static_cast<int>(core::Field::WindV)] = L.roles[static_cast<int>(Role::V)] != nullptr;
  vol.has_field[static_cast<int>(core::Field::WindW)] =
      L.roles[static_cast<int>(Role::Omega)] != nullptr || L.roles[static_cast<int>(Role::UpwardVelocity)] != nullptr;
  vol.has_field[static_cast<int>(core::Field::Temperature)] = true;
  vol.has_field[static_cast<int>(core::Field::Pressure)] = L.vertical_kind != Vertical::Height;
  // The first step's half floats get their pages touched on the second core while the rest of the
  // open reads the file on this one: up to two grid levels per source level (the automatic spacing
  // is half the median level thickness), with room for four times that (never more than a volume
  // the import accepts). Not with a spacing asked for (--dz), whose level count nothing here can
  // foresee.
  std::optional<FirstStepPages> first_pages;
  if (options.half_fields && options.dz_m <= 0.0 && core::worker_count() >= 2) {
    std::vector<int> fields;
    for (int i = 0; i < core::kFieldCount; ++i) {
      if (vol.has_field[static_cast<std::size_t>(i)]) fields.push_back(i);
    }
    const std::size_t plane = vol.grid.columns();
    const double accepted = std::floor(options.max_volume_bytes / (static_cast<double>(plane) * core::kFieldCount * sizeof(float)));
    const double expected = 2.0 * static_cast<double>(S->levels.size()) + 2.0;
    if (accepted >= 1.0) {  // false for NaN too
      const double room = std::min(accepted, 4.0 * expected + 16.0);
      first_pages.emplace(fields, plane, static_cast<std::size_t>(room), static_cast<std::size_t>(std::min(room, expected)));
    }
  }
  if (L.times_uneven) vol.report.warn("time steps are unevenly spaced");
  if (!has_geo && L.vertical_kind == Vertical::Pressure) {
    vol.report.warn("no geopotential: level heights come from the standard atmosphere (errors of a few hundred metres)");
  }
  if (!L.roles[static_cast<int>(Role::Temperature)]) vol.report.warn("no temperature: the standard atmosphere's is used");
  // Levels above the highest one holding cloud at any step imported are empty bricks: they are
  // left out (with one cloud-free level kept above the cloud, so it fades to zero), unless asked
  // to keep them. Found by reading the cloud variables a level at a time from the top down.
  if (!options.keep_cloudless_levels && !S->diagnose && S->levels.size() > 2) {
    int top = -1;  // index into S->levels of the highest level with cloud
    for (int l = static_cast<int>(S->levels.size()) - 1; l >= 0 && top < 0; --l) {
      for (int t : S->steps) {
        if (level_has_cloud(*S, S->levels[static_cast<std::size_t>(l)], t)) {
          top = l;
          break;
        }
      }
    }
    const std::size_t keep = static_cast<std::size_t>(std::max(top + 2, 2));
    if (keep < S->levels.size()) {
      const std::size_t n = S->levels.size();
      vol.report.notes.push_back(std::to_string(n - keep) + " level(s) from " + fmt(S->level_pa[keep] / 100.0) +
                                 " hPa (reference pressure) up hold no cloud at any step imported: left out, with the "
                                 "cloud-free level at " + fmt(S->level_pa[keep - 1] / 100.0) +
                                 " hPa kept above the cloud (--all-levels keeps them)");
      S->levels.resize(keep), S->level_pa.resize(keep), S->level_z.resize(keep);
      if (!S->hyb_a.empty()) S->hyb_a.resize(keep), S->hyb_b.resize(keep);
      S->lev_lo = *std::min_element(S->levels.begin(), S->levels.end());
      S->lev_hi = *std::max_element(S->levels.begin(), S->levels.end());
    }
  }
  // Altitude grid from the first step's level heights (geometric, above the sphere).
  double zmin = 1e30, zmax = -1e30;
  {
    core::VolumeGrid probe = vol.grid;
    probe.alt_m = {0.0, 1.0, 0};  // heights only
    const NcVar* zv = L.roles[static_cast<int>(Role::Geopotential)];
    const NcVar* ghv = L.roles[static_cast<int>(Role::GeopotentialHeight)];
    std::vector<double> thick;
    std::optional<double> median_thickness;
    if (zv || ghv) {
      const NcVar& hv = zv ? *zv : *ghv;
      // The heights are read a band of file rows at a time into the slab the steps read them into
      // (the whole step's heights at once were 200 MB of fresh memory for a global file, most of
      // this probe's time), and each band's rows are split over the cores.
      Slab& s = S->scratch[static_cast<std::size_t>(zv ? Role::Geopotential : Role::GeopotentialHeight)];
      const int nx = probe.lon_deg.count, ny = probe.lat_deg.count;
      constexpr int kProbeBandRows = 32;
      const int nbands = (S->lat_hi - S->lat_lo) / kProbeBandRows + 1;
      // Each output row reads one file row: the output rows grouped by that row's band.
      std::vector<std::vector<int>> band_rows(static_cast<std::size_t>(nbands));
      auto file_row = [&](int y) {
        const std::size_t yy = static_cast<std::size_t>(y);
        return S->lat.w[yy] == 1.0 ? S->lat.j1[yy] : S->lat.j0[yy];
      };
      for (int y = 0; y < ny; ++y) band_rows[static_cast<std::size_t>((file_row(y) - S->lat_lo) / kProbeBandRows)].push_back(y);
      // What a part of each band's rows gathers, in a copy on its own thread's stack while it runs.
      struct ProbePart {
        double zmin = 1e30, zmax = -1e30;
        std::vector<std::uint64_t> bins;  // thicknesses counted in 1 m bins (64 bits: no count can wrap)
        std::vector<double> in_bin;       // the thicknesses in the median's bin (second pass)
        bool bad = false;                 // a height out of range: the first one met
        double bad_raw = 0.0, bad_z = 0.0;
      };
      std::vector<ProbePart> part(core::worker_count());
      // Each column's level heights, bottom up, to `visit(part, raw value, height, thickness below
      // or NaN)`; a part's calls come level by level over its rows, each column's in order up.
      auto heights = [&](auto&& visit) {
        std::vector<std::vector<double>> prevs(part.size());
        for (int b = 0; b < nbands; ++b) {
          const std::vector<int>& rows = band_rows[static_cast<std::size_t>(b)];
          if (rows.empty()) continue;
          const int j_lo = S->lat_lo + b * kProbeBandRows, j_hi = std::min(S->lat_hi, j_lo + kProbeBandRows - 1);
          read_slab_into(s, *S, hv, S->steps.front(), nullptr, true, j_lo, j_hi);
          core::parallel_ranges(rows.size(), 1, [&](std::size_t r0, std::size_t r1, unsigned p) {
            ProbePart local = std::move(part[p]);
            std::vector<double>& prev = prevs[p];  // each column's last height below
            prev.assign((r1 - r0) * static_cast<std::size_t>(nx), kNaN);
            for (std::size_t l = 0; l < S->levels.size(); ++l) {
              for (std::size_t r = r0; r < r1; ++r) {
                const int row = file_row(rows[r]);
                double* pv = prev.data() + (r - r0) * static_cast<std::size_t>(nx);
                for (int x = 0; x < nx; ++x) {
                  const double raw = s.at(S->lon.src[static_cast<std::size_t>(x)], row, S->levels[l]);
                  const double zz = physics::f64::geopotential_to_height_m(zv ? raw : kG0 * raw, vol.grid.earth_radius_m);
                  if (std::isnan(zz)) continue;
                  visit(local, raw, zz, !std::isnan(pv[x]) && zz > pv[x] ? zz - pv[x] : kNaN);
                  pv[x] = zz;
                }
              }
            }
            part[p] = std::move(local);
          });
        }
      };
      // The median thickness without storing 10^7 thicknesses: a first pass counts them in bins
      // (1 cm up to 5 km, 1 m beyond, to 200 km: the heights are checked to 100 km); the axis
      // depends on the median only through its number of intervals, so a second pass that keeps
      // only the median's bin, for the exact median (the element a full sort would put in the
      // middle), is made only when the bin's ends would give different axes.
      constexpr std::size_t kFineBins = 500000, kBins = kFineBins + 195000;
      auto bin_of = [](double t) {
        return t < 5000.0 ? std::min(kFineBins - 1, static_cast<std::size_t>(t * 100.0))
                          : std::min(kBins - 1, kFineBins + static_cast<std::size_t>(t - 5000.0));
      };
      auto bin_start = [](std::size_t i) { return i < kFineBins ? static_cast<double>(i) / 100.0 : 5000.0 + static_cast<double>(i - kFineBins); };
      for (ProbePart& q : part) q.bins.assign(kBins, 0);
      heights([&](ProbePart& q, double raw, double zz, double t) {
        if (!(zz >= -1000.0 && zz <= 1.0e5)) {
          if (!q.bad) q.bad = true, q.bad_raw = raw, q.bad_z = zz;
          return;
        }
        q.zmin = std::min(q.zmin, zz);
        q.zmax = std::max(q.zmax, zz);
        if (!std::isnan(t)) ++q.bins[bin_of(t)];
      });
      for (const ProbePart& q : part) {
        if (q.bad) {
          throw ImportError(path + ": variable '" + hv.name + "' has value " + fmt(q.bad_raw) + " (a height of " +
                            fmt(q.bad_z) + " m), expected a height between -1 km and 100 km");
        }
      }
      std::vector<std::size_t> bins(kBins, 0);
      std::size_t n_thick = 0;
      for (ProbePart& q : part) {
        zmin = std::min(zmin, q.zmin);
        zmax = std::max(zmax, q.zmax);
        for (std::size_t i = 0; i < kBins; ++i) bins[i] += q.bins[i], n_thick += q.bins[i];
        std::vector<std::uint64_t>().swap(q.bins);
      }
      if (n_thick) {
        const std::size_t mid = n_thick / 2;  // the index of the median in sorted order
        std::size_t below = 0, bin = 0;
        while (below + bins[bin] <= mid) below += bins[bin++];
        // The automatic axis a median gives (its node count), or -1 where the import refuses it
        // (that message names the spacing, so the exact median is found for it).
        auto axis_nodes = [&](double median) {
          const double d = std::clamp(median / 2.0, 50.0, 500.0), lo = std::max(zmin, -500.0);
          try {
            checked_level_count(path, lo, zmax, d, "the levels' spacing");
          } catch (const ImportError&) {
            return -1;
          }
          return altitude_axis(lo, zmax, d, true).count;
        };
        // The bin's ends widened by a micrometre, against rounding in the bin's index.
        const bool exact = options.dz_m <= 0.0 &&
                           (bin + 1 >= kBins || axis_nodes(bin_start(bin) - 1e-6) != axis_nodes(bin_start(bin + 1) + 1e-6));
        if (exact) {
          exact_median_count.fetch_add(1, std::memory_order_relaxed);
          heights([&](ProbePart& q, double, double, double t) {
            if (!std::isnan(t) && bin_of(t) == bin) q.in_bin.push_back(t);
          });
          std::vector<double> in_bin;
          in_bin.reserve(bins[bin]);
          for (const ProbePart& q : part) in_bin.insert(in_bin.end(), q.in_bin.begin(), q.in_bin.end());
          const auto at = in_bin.begin() + static_cast<std::ptrdiff_t>(mid - below);
          std::nth_element(in_bin.begin(), at, in_bin.end());
          median_thickness = *at;
        } else {
          median_thickness = 0.5 * (bin_start(bin) + bin_start(bin + 1));  // within the bin: the same axis
        }
      }
    } else {
      // Height levels are their own heights; pressure and hybrid levels take the standard
      // atmosphere's height of their (reference) pressure, with a margin for hybrid columns.
      double surface_min = 0.0, surface_max = 0.0;
      if (L.surface_geopotential && (L.vertical_kind == Vertical::Hybrid || L.height_above_ground)) {
        const Slab sg = read_slab(*S, *L.surface_geopotential, S->steps.front(), nullptr, true);
        surface_min = 1e30, surface_max = -1e30;
        for (double v : sg.d) {
          if (std::isnan(v)) continue;
          const double h = L.surface_geopotential_scale != 1.0 ? v : physics::f64::geopotential_to_height_m(v, vol.grid.earth_radius_m);
          surface_min = std::min(surface_min, h);
          surface_max = std::max(surface_max, h);
        }
      }
      for (std::size_t l = 0; l < S->levels.size(); ++l) {
        const double zz = L.vertical_kind == Vertical::Height ? S->level_z[l] : isa_altitude_m(S->level_pa[l]);
        const double prev = l == 0 ? zz : L.vertical_kind == Vertical::Height ? S->level_z[l - 1] : isa_altitude_m(S->level_pa[l - 1]);
        // Heights above ground sit on the surface; the other kinds' heights are already altitudes.
        const bool agl = L.vertical_kind == Vertical::Height && L.height_above_ground;
        zmin = std::min(zmin, zz + (agl ? surface_min : 0.0));
        zmax = std::max(zmax, zz + (agl ? surface_max : 0.0));
        if (l) thick.push_back(zz - prev);
      }
      if (L.vertical_kind == Vertical::Hybrid) {
        zmin = std::min(zmin, surface_min);
        zmax += 0.05 * (zmax - zmin);
        vol.report.notes.push_back("altitude range from the standard atmosphere of the hybrid levels, with a 5 % margin");
      }
    }
    if (!(zmax > zmin)) throw ImportError(path + ": the levels' heights span no altitude range");
    double dz = options.dz_m;
    if (dz <= 0.0) {
      // The median (the element a full sort would put in the middle), without sorting.
      if (!median_thickness && !thick.empty()) {
        std::nth_element(thick.begin(), thick.begin() + static_cast<std::ptrdiff_t>(thick.size() / 2), thick.end());
        median_thickness = thick[thick.size() / 2];
      }
      const double median = median_thickness.value_or(500.0);
      dz = std::clamp(median / 2.0, 50.0, 500.0);
    }
    zmin = std::max(zmin, -500.0);
    // Refused first where the span is nothing or the levels too many; then the axis reaches the
    // highest level (an automatic spacing is fitted to end on it).
    checked_level_count(path, zmin, zmax, dz, options.dz_m > 0.0 ? "--dz (dz_m)" : "the levels' spacing");
    vol.grid.alt_m = altitude_axis(zmin, zmax, dz, options.dz_m <= 0.0);
  }
  check_imported_grid(path, vol.grid);
  const double bytes = static_cast<double>(vol.grid.points()) * core::kFieldCount * sizeof(float);
  if (bytes > options.max_volume_bytes) {
    throw ImportError(path + ": the volume would take " + fmt(bytes / 1e9) + " GB per time step (limit " +
                      fmt(options.max_volume_bytes / 1e9) + " GB); subset the region, levels or stride, or raise --dz");
  }
  vol.has_ground = L.surface_geopotential != nullptr;
  vol.report.notes.push_back(vol.has_ground ? "low/mid/high cover by height above the ground ('" + L.surface_geopotential->name + "')"
                                            : "low/mid/high cover by height above sea level (the file gives no terrain)");
  if (!L.roles[static_cast<int>(Role::CloudFraction)] && !S->diagnose) {
    vol.report.notes.push_back("no cloud fraction: water is taken as covering whole grid boxes");
  }
  if (first_pages) first_pages->finish(static_cast<std::size_t>(vol.grid.alt_m.count), S->first_halves);
  const core::VolumeGrid grid = vol.grid;
  vol.set_loader([S, grid](std::size_t step, core::ImportReport& report, core::TimeStepData& out) {
    load_era5_step(*S, grid, step, report, out);
  }, options.cache_steps);
  return vol;
}

}  // namespace cv::importers
