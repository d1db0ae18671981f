// CloudVolume: grid helpers, derived maps, and the lazy time-step cache.
#include "volume/cloud_volume.hpp"
#include "volume/volume_io.hpp"

#include "io/parallel.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

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
  struct ColumnState {
    MaxRandomOverlap all, low, mid, high;
    double tau = 0.0, base = std::numeric_limits<double>::quiet_NaN(), top = std::numeric_limits<double>::quiet_NaN();
    double ground = 0.0;
    bool any_data = false;
  };
  // Rows are independent: split over the cores.
  parallel_ranges(static_cast<std::size_t>(grid.lat_deg.count), 16, [&](std::size_t j_begin, std::size_t j_end, unsigned) {
    std::vector<ColumnState> row(static_cast<std::size_t>(nx));
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
        ColumnState& st = row[static_cast<std::size_t>(i)];
        st = ColumnState{};
        // Layers by height above the ground where the terrain is known, above sea level otherwise.
        const std::size_t col = grid.column(i, j);
        st.ground = col < data.ground_m.size() && std::isfinite(data.ground_m[col]) ? data.ground_m[col] : 0.0;
      }
      for (int k = grid.alt_m.count - 1; k >= 0; --k) {
        const double alt = grid.alt_m.at(k);
        const std::size_t p0 = grid.index(0, j, k);
        const float* cf = layer_row(src_cf, p0, widened[0]);
        const float* el = layer_row(src_el, p0, widened[1]);
        const float* ei = layer_row(src_ei, p0, widened[2]);
        for (int i = 0; i < nx; ++i) {
          ColumnState& st = row[static_cast<std::size_t>(i)];
          const std::size_t p = static_cast<std::size_t>(i);
          const double ext = (!el || std::isnan(el[p]) ? 0.0 : el[p]) + (!ei || std::isnan(ei[p]) ? 0.0 : ei[p]);
          const bool have = (cf && !std::isnan(cf[p])) || (el && !std::isnan(el[p])) || (ei && !std::isnan(ei[p]));
          if (!have) continue;
          st.any_data = true;
          // Without a cloud-fraction field, a point with water counts as fully cloudy.
          const double frac = !cf || std::isnan(cf[p]) ? (ext > 0.0 ? 1.0 : 0.0) : cf[p];
          const bool cloudy = map_cloudy(frac, ext, options);
          const double c = cloudy ? frac : 0.0;
          const double above = alt - st.ground;
          MaxRandomOverlap& layer = above < options.low_top_m ? st.low : above < options.mid_top_m ? st.mid : st.high;
          if (cloudy) {
            st.all.add(c);
            layer.add(c);
            st.tau += c * ext * dz;
            st.top = std::isnan(st.top) ? alt : st.top;
            st.base = alt;
          } else {
            st.all.gap();
            layer.gap();
          }
        }
      }
      for (int i = 0; i < nx; ++i) {
        const ColumnState& st = row[static_cast<std::size_t>(i)];
        if (!st.any_data) continue;
        const std::size_t col = grid.column(i, j);
        m.cloud_cover[col] = static_cast<float>(st.all.cover());
        m.low_cover[col] = static_cast<float>(st.low.cover());
        m.mid_cover[col] = static_cast<float>(st.mid.cover());
        m.high_cover[col] = static_cast<float>(st.high.cover());
        m.optical_depth[col] = static_cast<float>(st.tau);
        m.cloud_base_m[col] = static_cast<float>(st.base);
        m.cloud_top_m[col] = static_cast<float>(st.top);
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
