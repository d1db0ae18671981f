// CloudVolume: grid helpers, derived maps, and the lazy time-step cache.
#include "volume/cloud_volume.hpp"
#include "volume/volume_io.hpp"

#include "io/cpu.hpp"
#include "io/parallel.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#endif

namespace cv::core {

bool VolumeGrid::wraps_lon() const {
  return lon_deg.count > 1 && std::abs(lon_deg.step * lon_deg.count - 360.0) < 1e-6 * 360.0;
}

const char* field_name(Field f) {
  static const char* names[kFieldCount] = {"extinction_liquid", "extinction_ice", "cloud_fraction", "wind_u",
                                           "wind_v", "wind_w", "temperature", "pressure"};
  return names[static_cast<int>(f)];
}

const char* field_units(Field f) {
  static const char* units[kFieldCount] = {"1/m", "1/m", "1", "m/s", "m/s", "m/s", "K", "Pa"};
  return units[static_cast<int>(f)];
}

std::size_t TimeStepData::bytes() const {
  std::size_t b = 0;
  for (const auto& f : fields) b += f.size() * sizeof(float);
  for (const auto& h : halves) b += h.size() * sizeof(std::uint16_t);
  b += ground_m.size() * sizeof(float);
  for (const auto* m : {&maps.cloud_cover, &maps.cloud_base_m, &maps.cloud_top_m, &maps.optical_depth,
                        &maps.low_cover, &maps.mid_cover, &maps.high_cover}) {
    b += m->size() * sizeof(float);
  }
  return b;
}


bool named_layer_band(const std::string& name, LayerBand& out, const MapOptions& o) {
  const LayerBand none;
  if (name == "all") out = none;
  else if (name == "low") out = {none.bottom_m, o.low_top_m};
  else if (name == "mid") out = {o.low_top_m, o.mid_top_m};
  else if (name == "high") out = {o.mid_top_m, none.top_m};
  else return false;
  return true;
}

namespace {
// A row of columns walked from the top, one array per quantity (so that four columns fit one AVX
// register): the maximum-random overlap of all layers (band 0) and of the low, mid and high bands,
// the optical depth, the cloud's base and top, the ground, and whether the column holds any data.
struct MapRow {
  enum Band { kAll = 0, kLow = 1, kMid = 2, kHigh = 3 };
  explicit MapRow(std::size_t n) : tau(n), base(n), top(n), ground(n), any_data(n) {
    for (auto& c : clear) c.resize(n);
    for (auto& q : prev) q.resize(n);
  }
  void start(std::size_t i, double ground_m) {
    for (int b = 0; b < 4; ++b) set(b, i, MaxRandomOverlap{});
    tau[i] = 0.0;
    base[i] = top[i] = std::numeric_limits<double>::quiet_NaN();
    ground[i] = ground_m;
    any_data[i] = 0;
  }
  MaxRandomOverlap band(int b, std::size_t i) const { return {clear[b][i], prev[b][i]}; }
  void set(int b, std::size_t i, const MaxRandomOverlap& o) { clear[b][i] = o.clear, prev[b][i] = o.prev; }
  std::vector<double> clear[4], prev[4];
  std::vector<double> tau, base, top, ground;
  std::vector<unsigned char> any_data;
};

// One level's row of the three fields the maps read (nullptr where a field is absent), with the
// level's altitude and the grid's spacing.
struct MapLayer {
  const float *cf, *el, *ei;
  double alt, dz;
};

// Column i takes the level: the maps' definition, value by value.
void add_layer_at(MapRow& r, const MapLayer& l, const MapOptions& options, std::size_t i) {
  const double ext = (!l.el || std::isnan(l.el[i]) ? 0.0 : l.el[i]) + (!l.ei || std::isnan(l.ei[i]) ? 0.0 : l.ei[i]);
  const bool have = (l.cf && !std::isnan(l.cf[i])) || (l.el && !std::isnan(l.el[i])) || (l.ei && !std::isnan(l.ei[i]));
  if (!have) return;
  r.any_data[i] = 1;
  // Without a cloud-fraction field, a point with water counts as fully cloudy.
  const double frac = !l.cf || std::isnan(l.cf[i]) ? (ext > 0.0 ? 1.0 : 0.0) : l.cf[i];
  const bool cloudy = map_cloudy(frac, ext, options);
  const double c = cloudy ? frac : 0.0;
  const double above = l.alt - r.ground[i];
  const int band = above < options.low_top_m ? MapRow::kLow : above < options.mid_top_m ? MapRow::kMid : MapRow::kHigh;
  MaxRandomOverlap all = r.band(MapRow::kAll, i), layer = r.band(band, i);
  if (cloudy) {
    all.add(c);
    layer.add(c);
    r.tau[i] += c * ext * l.dz;
    r.top[i] = std::isnan(r.top[i]) ? l.alt : r.top[i];
    r.base[i] = l.alt;
  } else {
    all.gap();
    layer.gap();
  }
  r.set(MapRow::kAll, i, all);
  r.set(band, i, layer);
}

#if defined(__x86_64__) && defined(__GNUC__)
// mask ? a : b, lane by lane (masks rather than blends: GCC 12 has taken a blend's mask apart lane
// by lane, core/volume/import_report.cpp).
__attribute__((target("avx"))) inline __m256d select_pd(__m256d mask, __m256d a, __m256d b) {
  return _mm256_or_pd(_mm256_and_pd(mask, a), _mm256_andnot_pd(mask, b));
}

// Four values of a field as doubles, and where they are numbers (nowhere for an absent field).
__attribute__((target("avx"))) inline void load_four(const float* f, std::size_t i, __m256d& v, __m256d& ok) {
  if (!f) {
    v = ok = _mm256_setzero_pd();
    return;
  }
  v = _mm256_cvtps_pd(_mm_loadu_ps(f + i));
  ok = _mm256_cmp_pd(v, v, _CMP_ORD_Q);
}

// MaxRandomOverlap::add(c) where `add` is set and gap() where `gap` is set, on band b of columns
// i..i+3: add's branches as masks.
__attribute__((target("avx"))) inline void overlap_four(MapRow& r, int b, std::size_t i, __m256d c, __m256d add, __m256d gap) {
  const __m256d zero = _mm256_setzero_pd(), one = _mm256_set1_pd(1.0);
  const __m256d prev = _mm256_loadu_pd(r.prev[b].data() + i);
  if (_mm256_movemask_pd(add) == 0) {  // no cloud: at most gaps (most groups, and the bands the level is not in)
    if (_mm256_movemask_pd(gap) != 0) _mm256_storeu_pd(r.prev[b].data() + i, select_pd(gap, zero, prev));
    return;
  }
  const __m256d clear = _mm256_loadu_pd(r.clear[b].data() + i);
  const __m256d cc = select_pd(_mm256_cmp_pd(c, zero, _CMP_LT_OQ), zero, select_pd(_mm256_cmp_pd(c, one, _CMP_GT_OQ), one, c));
  const __m256d m = select_pd(_mm256_cmp_pd(cc, prev, _CMP_GT_OQ), cc, prev);
  const __m256d partial = _mm256_mul_pd(clear, _mm256_div_pd(_mm256_sub_pd(one, m), _mm256_sub_pd(one, prev)));
  const __m256d overcast = select_pd(_mm256_cmp_pd(cc, one, _CMP_GE_OQ), zero, clear);
  const __m256d added = select_pd(_mm256_cmp_pd(prev, one, _CMP_LT_OQ), partial, overcast);
  _mm256_storeu_pd(r.clear[b].data() + i, select_pd(add, added, clear));
  _mm256_storeu_pd(r.prev[b].data() + i, select_pd(add, cc, select_pd(gap, zero, prev)));
}

// add_layer_at for four columns at a time while four remain, with AVX: the same operations on each
// column's doubles in the same order, so the maps are the same to the bit. Returns the first
// column left to add_layer_at.
__attribute__((target("avx"))) std::size_t add_layer_avx(MapRow& r, const MapLayer& l, const MapOptions& options, std::size_t n) {
  const __m256d zero = _mm256_setzero_pd(), one = _mm256_set1_pd(1.0);
  const __m256d min_frac = _mm256_set1_pd(static_cast<double>(options.min_cloud_fraction));
  const __m256d min_ext = _mm256_set1_pd(static_cast<double>(options.min_extinction_per_m));
  const __m256d alt = _mm256_set1_pd(l.alt), dz = _mm256_set1_pd(l.dz);
  const __m256d low_top = _mm256_set1_pd(options.low_top_m), mid_top = _mm256_set1_pd(options.mid_top_m);
  std::size_t i = 0;
  for (; i + 4 <= n; i += 4) {
    __m256d cf, cf_ok, el, el_ok, ei, ei_ok;
    load_four(l.cf, i, cf, cf_ok);
    load_four(l.el, i, el, el_ok);
    load_four(l.ei, i, ei, ei_ok);
    const __m256d have = _mm256_or_pd(cf_ok, _mm256_or_pd(el_ok, ei_ok));
    const int have_bits = _mm256_movemask_pd(have);
    if (have_bits == 0) continue;
    for (int k = 0; k < 4; ++k) r.any_data[i + static_cast<std::size_t>(k)] |= static_cast<unsigned char>((have_bits >> k) & 1);
    const __m256d ext = _mm256_add_pd(select_pd(el_ok, el, zero), select_pd(ei_ok, ei, zero));
    const __m256d frac = select_pd(cf_ok, cf, select_pd(_mm256_cmp_pd(ext, zero, _CMP_GT_OQ), one, zero));
    const __m256d cloudy = _mm256_and_pd(_mm256_cmp_pd(frac, min_frac, _CMP_GE_OQ), _mm256_cmp_pd(ext, min_ext, _CMP_GE_OQ));
    const __m256d c = select_pd(cloudy, frac, zero);
    const __m256d add = _mm256_and_pd(have, cloudy), gap = _mm256_andnot_pd(cloudy, have);
    const __m256d above = _mm256_sub_pd(alt, _mm256_loadu_pd(r.ground.data() + i));
    const __m256d low = _mm256_cmp_pd(above, low_top, _CMP_LT_OQ);
    const __m256d mid = _mm256_andnot_pd(low, _mm256_cmp_pd(above, mid_top, _CMP_LT_OQ));
    const __m256d high = _mm256_andnot_pd(_mm256_or_pd(low, mid), have);
    overlap_four(r, MapRow::kAll, i, c, add, gap);
    overlap_four(r, MapRow::kLow, i, c, _mm256_and_pd(add, low), _mm256_and_pd(gap, low));
    overlap_four(r, MapRow::kMid, i, c, _mm256_and_pd(add, mid), _mm256_and_pd(gap, mid));
    overlap_four(r, MapRow::kHigh, i, c, _mm256_and_pd(add, high), _mm256_and_pd(gap, high));
    const __m256d tau = _mm256_loadu_pd(r.tau.data() + i), top = _mm256_loadu_pd(r.top.data() + i);
    _mm256_storeu_pd(r.tau.data() + i, select_pd(add, _mm256_add_pd(tau, _mm256_mul_pd(_mm256_mul_pd(c, ext), dz)), tau));
    _mm256_storeu_pd(r.top.data() + i, select_pd(_mm256_and_pd(add, _mm256_cmp_pd(top, top, _CMP_UNORD_Q)), alt, top));
    _mm256_storeu_pd(r.base.data() + i, select_pd(add, alt, _mm256_loadu_pd(r.base.data() + i)));
  }
  return i;
}
#endif
}  // namespace

void derive_maps(const VolumeGrid& grid, TimeStepData& data, const MapOptions& options) {
  const std::size_t ncol = grid.columns();
  // The three fields the maps read, as floats or as half floats (a step on its way to a float16
  // .cvvol): a layer's row of halves is widened into a buffer first, as read_cvvol widens them.
  struct Source {
    const float* f = nullptr;
    const std::uint16_t* h = nullptr;
    float k = 1.0f;  // 1 / half_field_scale
  };
  auto source = [&](Field which) {
    Source s;
    const auto& fv = data[which];
    const auto& hv = data.halves[static_cast<std::size_t>(which)];
    if (fv.size() == grid.points()) s.f = fv.data();
    else if (hv.size() == grid.points()) s.h = hv.data(), s.k = 1.0f / half_field_scale(which);
    return s;
  };
  const Source src_cf = source(Field::CloudFraction), src_el = source(Field::ExtinctionLiquid),
               src_ei = source(Field::ExtinctionIce);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  Maps2D& m = data.maps;
  for (auto* v : {&m.cloud_cover, &m.cloud_base_m, &m.cloud_top_m, &m.optical_depth, &m.low_cover, &m.mid_cover,
                  &m.high_cover}) {
    v->assign(ncol, nan);
  }
  const double dz = grid.alt_m.step;
  // A row of columns at a time, levels outer and longitudes inner: the fields are read along their
  // contiguous axis (a column's levels lie a whole layer apart). Each column's arithmetic is the
  // same as walking it alone from the top.
  const int nx = grid.lon_deg.count;
  const bool avx = cpu_has_avx();
  // Rows are independent: split over the cores.
  parallel_ranges(static_cast<std::size_t>(grid.lat_deg.count), 16, [&](std::size_t j_begin, std::size_t j_end, unsigned) {
    MapRow row(static_cast<std::size_t>(nx));
    std::vector<float> widened[3];
    // The layer row at p0 of a field: nullptr where the field is absent.
    auto layer_row = [&](const Source& s, std::size_t p0, std::vector<float>& buf) -> const float* {
      if (s.f) return s.f + p0;
      if (!s.h) return nullptr;
      buf.resize(static_cast<std::size_t>(nx));
      halves_to_floats(s.h + p0, s.k, buf.data(), buf.size());
      return buf.data();
    };
    for (int j = static_cast<int>(j_begin); j < static_cast<int>(j_end); ++j) {
      for (int i = 0; i < nx; ++i) {
        // Layers by height above the ground where the terrain is known, above sea level otherwise.
        const std::size_t col = grid.column(i, j);
        row.start(static_cast<std::size_t>(i), col < data.ground_m.size() && std::isfinite(data.ground_m[col]) ? data.ground_m[col] : 0.0);
      }
      for (int k = grid.alt_m.count - 1; k >= 0; --k) {
        const MapLayer layer{layer_row(src_cf, grid.index(0, j, k), widened[0]), layer_row(src_el, grid.index(0, j, k), widened[1]),
                             layer_row(src_ei, grid.index(0, j, k), widened[2]), grid.alt_m.at(k), dz};
        std::size_t i = 0;
#if defined(__x86_64__) && defined(__GNUC__)
        if (avx) i = add_layer_avx(row, layer, options, static_cast<std::size_t>(nx));
#else
        (void)avx;
#endif
        for (; i < static_cast<std::size_t>(nx); ++i) add_layer_at(row, layer, options, i);
      }
      for (int i = 0; i < nx; ++i) {
        const std::size_t p = static_cast<std::size_t>(i);
        if (!row.any_data[p]) continue;
        const std::size_t col = grid.column(i, j);
        m.cloud_cover[col] = static_cast<float>(row.band(MapRow::kAll, p).cover());
        m.low_cover[col] = static_cast<float>(row.band(MapRow::kLow, p).cover());
        m.mid_cover[col] = static_cast<float>(row.band(MapRow::kMid, p).cover());
        m.high_cover[col] = static_cast<float>(row.band(MapRow::kHigh, p).cover());
        m.optical_depth[col] = static_cast<float>(row.tau[p]);
        m.cloud_base_m[col] = static_cast<float>(row.base[p]);
        m.cloud_top_m[col] = static_cast<float>(row.top[p]);
      }
    }
  });
}

void CloudVolume::set_loader(Loader loader, std::size_t cache_steps) {
  loader_ = std::move(loader);
  cache_steps_ = std::max<std::size_t>(1, cache_steps);
}

void CloudVolume::put(std::size_t index, TimeStepData data) { pinned_[index] = std::move(data); }

std::size_t CloudVolume::resident_bytes() const {
  std::size_t b = spare_.bytes();
  for (const auto* held : {&pinned_, &cache_})
    for (const auto& [index, data] : *held) b += data.bytes();
  return b;
}

const TimeStepData& CloudVolume::step(std::size_t index) {
  if (index >= times.size()) {
    throw std::out_of_range("time step " + std::to_string(index) + " of " + std::to_string(times.size()));
  }
  if (auto it = pinned_.find(index); it != pinned_.end()) return it->second;
  if (auto it = cache_.find(index); it != cache_.end()) {
    lru_.remove(index);
    lru_.push_front(index);
    return it->second;
  }
  if (!loader_) throw std::logic_error("time step " + std::to_string(index) + " is not loaded and no loader is set");
  // Evict before loading so peak memory holds at most cache_steps steps; keep the evicted arrays.
  while (cache_.size() >= cache_steps_) {
    auto it = cache_.find(lru_.back());
    spare_ = std::move(it->second);
    cache_.erase(it);
    lru_.pop_back();
  }
  TimeStepData data = std::move(spare_);
  spare_ = TimeStepData{};
  loader_(index, report, data);
  derive_maps(grid, data);
  lru_.push_front(index);
  return cache_.emplace(index, std::move(data)).first->second;
}

}  // namespace cv::core
