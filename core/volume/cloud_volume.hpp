// A cloud volume on a spherical-Earth shell: a regular longitude/latitude/altitude grid, SI fields
// per valid time (loaded lazily, evicted), 2-D maps derived from them, and the import report.
// Plain data: nothing here knows NetCDF, GL or VTK.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <list>
#include <map>
#include <memory>
#include <new>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "volume/import_report.hpp"

namespace cv::core {

// start + i * step for i in [0, count).
struct RegularAxis {
  double start = 0.0;
  double step = 1.0;
  int count = 0;
  double at(int i) const { return start + step * i; }
  double last() const { return at(count - 1); }
};

struct VolumeGrid {
  RegularAxis lon_deg;  // ascending; may run past 180 across the date line
  RegularAxis lat_deg;  // ascending, south to north
  RegularAxis alt_m;    // geometric altitude above the sphere, ascending
  double earth_radius_m = 6371000.0;

  std::size_t columns() const { return std::size_t(lon_deg.count) * std::size_t(lat_deg.count); }
  std::size_t points() const { return columns() * std::size_t(alt_m.count); }
  // Longitude varies fastest, then latitude, then altitude: a 3-D texture of (nlon, nlat, nalt).
  std::size_t index(int i_lon, int j_lat, int k_alt) const {
    return (std::size_t(k_alt) * std::size_t(lat_deg.count) + std::size_t(j_lat)) * std::size_t(lon_deg.count) +
           std::size_t(i_lon);
  }
  std::size_t column(int i_lon, int j_lat) const {
    return std::size_t(j_lat) * std::size_t(lon_deg.count) + std::size_t(i_lon);
  }
  // True when the longitudes cover the whole circle (the last column's neighbour is the first).
  bool wraps_lon() const;
};

// 3-D fields in SI units. A field a file does not provide is absent (an empty vector); a point
// with no data (outside the model domain, below the lowest level) is NaN, never an invented value.
enum class Field : int {
  ExtinctionLiquid = 0,  // 1/m, in-cloud
  ExtinctionIce,         // 1/m, in-cloud
  CloudFraction,         // 0..1
  WindU,                 // m/s, eastward
  WindV,                 // m/s, northward
  WindW,                 // m/s, upward
  Temperature,           // K
  Pressure,              // Pa; held only where the file gives it (pressure or hybrid levels, WRF's P + PB)
};
inline constexpr int kFieldCount = 8;
const char* field_name(Field f);
const char* field_units(Field f);

// Per-column maps derived from the 3-D fields (NaN where a column has no data or no cloud).
struct Maps2D {
  std::vector<float> cloud_cover;        // 0..1, maximum-random overlap
  std::vector<float> cloud_base_m;       // lowest cloudy altitude
  std::vector<float> cloud_top_m;        // highest cloudy altitude
  std::vector<float> optical_depth;      // column integral of cloud fraction x in-cloud extinction
  std::vector<float> low_cover;          // below 2 km above the ground (above sea level without terrain)
  std::vector<float> mid_cover;          // 2 to 6 km
  std::vector<float> high_cover;         // above 6 km
};

// Thresholds for the derived maps.
struct MapOptions {
  float min_cloud_fraction = 0.01f;       // a point counts as cloudy from here...
  float min_extinction_per_m = 1e-6f;     // ...when its extinction also reaches this
  double low_top_m = 2000.0;
  double mid_top_m = 6000.0;
};

// The factor a field's SI value is multiplied by before it is stored as a half float (the .cvvol's
// float16 encoding, docs/formats.md): extinction in 1/km (values down to 6.1e-8 /m stay normal),
// pressure in hPa (Pa would pass the largest half, 65504), the others in SI units.
inline float half_field_scale(Field f) {
  if (f == Field::Pressure) return 0.01f;
  return f == Field::ExtinctionLiquid || f == Field::ExtinctionIce ? 1000.0f : 1.0f;
}

// An allocator whose construction without a value leaves the value uninitialised, so a resize of a
// buffer its owner writes whole next writes no zeros first (a global step's half floats are 670 MB:
// zeroing them was one core's first touch of every fresh page, a second in this VM's imports).
template <typename T, typename A = std::allocator<T>>
struct DefaultInitAllocator : A {
  using A::A;
  DefaultInitAllocator() = default;
  template <typename U>
  struct rebind {
    using other = DefaultInitAllocator<U, typename std::allocator_traits<A>::template rebind_alloc<U>>;
  };
  template <typename U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible_v<U>) {
    ::new (static_cast<void*>(p)) U;
  }
  template <typename U, typename... Args>
  void construct(U* p, Args&&... args) {
    std::allocator_traits<A>::construct(static_cast<A&>(*this), p, std::forward<Args>(args)...);
  }
};

// A field's half floats (TimeStepData::halves); resize() leaves new values uninitialised.
using HalfBuffer = std::vector<std::uint16_t, DefaultInitAllocator<std::uint16_t>>;

struct TimeStepData {
  std::array<std::vector<float>, kFieldCount> fields;
  // A field held as half floats of its value x half_field_scale instead of `fields` (whose vector
  // is then empty): only the import on its way to a float16 .cvvol asks a reader for these
  // (importers' ImportOptions::half_fields), which halves the step's memory and leaves write_cvvol
  // no conversion. derive_maps and write_cvvol read either; nothing else is given such a step.
  std::array<HalfBuffer, kFieldCount> halves;
  // Per column, the ground's altitude (m) where the file gives terrain; empty (or NaN in a column)
  // where it does not. Low/mid/high cover is measured from here.
  std::vector<float> ground_m;
  Maps2D maps;
  std::vector<float>& operator[](Field f) { return fields[static_cast<std::size_t>(f)]; }
  const std::vector<float>& operator[](Field f) const { return fields[static_cast<std::size_t>(f)]; }
  std::size_t bytes() const;
};

// Maximum-random overlap (Geleyn & Hollingsworth 1979): adjacent cloudy layers overlap maximally,
// layers separated by clear air randomly. Fed a column's layers from the top with their fractions
// (derive_maps, and the probes of core/analysis on a sampled column).
struct MaxRandomOverlap {
  double clear = 1.0;  // probability of a clear line of sight so far
  double prev = 0.0;   // fraction of the layer above
  void add(double c) {
    c = c < 0.0 ? 0.0 : c > 1.0 ? 1.0 : c;
    if (prev < 1.0) clear *= (1.0 - (c > prev ? c : prev)) / (1.0 - prev);
    else clear = c >= 1.0 ? 0.0 : clear;  // an overcast layer above already hides everything
    prev = c;
  }
  void gap() { prev = 0.0; }
  double cover() const { return clear > 1.0 ? 0.0 : clear < 0.0 ? 1.0 : 1.0 - clear; }
};

// The layer masks' named bands (render.march.layer_bottom_m/top_m, `--layer`): heights above the
// ground of the derived maps' low, mid and high cover (MapOptions' 2 km and 6 km), and "all".
// False for any other name.
struct LayerBand {
  double bottom_m = -100000.0, top_m = 1e7;  // the settings' "no end" values
};
bool named_layer_band(const std::string& name, LayerBand& out, const MapOptions& o = {});

// Whether a level counts as cloudy in the derived maps (and the probes): its fraction and its
// in-cloud extinction both reach the thresholds.
inline bool map_cloudy(double fraction, double extinction_per_m, const MapOptions& o) {
  return fraction >= o.min_cloud_fraction && extinction_per_m >= o.min_extinction_per_m;
}

// Fills data.maps from data's fields.
void derive_maps(const VolumeGrid& grid, TimeStepData& data, const MapOptions& options = {});

struct ValidTime {
  std::int64_t unix_s = 0;      // seconds since 1970-01-01 UTC (for non-standard calendars, the
                                // nearest real date; the report says so)
  std::string iso_utc;          // e.g. "2024-01-15T03:00:00Z", in the file's own calendar
};

// The volume: grid, times, which fields exist, report; time steps come from a loader on demand and
// at most `cache_steps` stay in memory.
class CloudVolume {
 public:
  // Fills `out` with a step's fields. `out` may arrive holding an evicted step's arrays, so their
  // memory is reused (a global step is gigabytes: fresh pages cost more than the conversion); the
  // loader must assign every field it provides and clear() the others.
  using Loader = std::function<void(std::size_t step, ImportReport& report, TimeStepData& out)>;

  VolumeGrid grid;
  std::vector<ValidTime> times;
  // The cloud droplets' effective radius the liquid extinction was computed with (micrometres):
  // the renderer's approximate Mie phase takes its droplet diameter, 2 r_eff, from here.
  double liquid_r_eff_um = 10.0;
  std::array<bool, kFieldCount> has_field{};
  // Whether the steps carry the ground's altitude (TimeStepData::ground_m).
  bool has_ground = false;
  ImportReport report;

  void set_loader(Loader loader, std::size_t cache_steps = 2);
  // Stores a step directly (eager importers, tests); it is never evicted.
  void put(std::size_t step, TimeStepData data);
  // The step's data, loading it if needed and evicting the least recently used beyond the cache.
  const TimeStepData& step(std::size_t index);
  bool is_loaded(std::size_t index) const { return pinned_.count(index) || cache_.count(index); }
  std::size_t loaded_steps() const { return pinned_.size() + cache_.size(); }
  // The memory of the steps held: loaded, and the last evicted one's arrays kept for reuse.
  std::size_t resident_bytes() const;

 private:
  Loader loader_;
  std::size_t cache_steps_ = 2;
  std::map<std::size_t, TimeStepData> pinned_;
  std::map<std::size_t, TimeStepData> cache_;
  std::list<std::size_t> lru_;  // most recent first
  TimeStepData spare_;           // the last evicted step's arrays, for reuse
};

}  // namespace cv::core
