// Importers: NetCDF model output to a CloudVolume. netCDF stays inside this target; callers see
// only core types, ImportError, and these options.
#pragma once

#include <cstddef>
#include <optional>
#include <string>

#include "import_error.hpp"
#include "volume/cloud_volume.hpp"

namespace cv::importers {

// A longitude/latitude box. Longitudes run east from lon_west_deg to lon_east_deg, so a box across
// the date line is e.g. west 170, east -170 (or 190).
struct Region {
  double lon_west_deg = -180.0;
  double lon_east_deg = 180.0;
  double lat_south_deg = -90.0;
  double lat_north_deg = 90.0;
};

struct ImportOptions {
  std::optional<Region> region;
  // Time steps by index (inclusive; -1 = last) and stride.
  int time_first = 0;
  int time_last = -1;
  int time_stride = 1;
  // And/or by valid time, ISO 8601 UTC ("2024-01-15T03:00:00Z"), inclusive; empty = open.
  std::string time_from_iso, time_to_iso;
  // Pressure levels kept, hPa (inclusive).
  double level_min_hpa = 0.0;
  double level_max_hpa = 1e9;
  int horizontal_stride = 1;
  double dz_m = 0.0;               // altitude spacing of the volume; 0 = from the data's levels
  double r_eff_liquid_um = 10.0;   // droplet effective radius
  double r_eff_ice_um = 0.0;       // 0 = temperature-dependent (see docs/importers.md)
  std::size_t cache_steps = 2;     // time steps kept in memory
  double max_volume_bytes = 8e9;   // refuse volumes larger than this per time step
  // A file with temperature and humidity but no cloud field gets a cloud diagnosed from relative
  // humidity (docs/importers.md, "Diagnosed cloud"); only when asked.
  bool diagnose_cloud = false;
  // Keep the levels above the highest cloud of every step imported (CF files); by default they are
  // left out, with one cloud-free level kept above the cloud.
  bool keep_cloudless_levels = false;
  double rh_critical = 0.8;        // the scheme's threshold relative humidity, 0..1
  // Steps hold their fields as half floats (core::TimeStepData::halves) where the reader can make
  // them (CF files): for the import on its way to a float16 .cvvol, which needs nothing else of a
  // step. Half the memory, and the half floats made row by row as the conversion stores them.
  bool half_fields = false;
};

// What the importer understands of a file (grid, axes, variables it will use, times), as text,
// ending with whether `import_file(path, options)` succeeds and, when not, its message.
std::string describe_file(const std::string& path, const ImportOptions& options = {});

// Opens the file, checks it, fixes the grid, and returns a volume whose time steps load lazily.
core::CloudVolume import_file(const std::string& path, const ImportOptions& options = {});

// How many CF imports in this process read the levels' heights a second time for the exact median
// level thickness (only where the median's 1 cm bin leaves the automatic altitude axis undecided):
// for tests and benchmarks.
std::size_t exact_median_passes();

// Effective radius of ice crystals (um) used when none is set: grows from 20 um at -60 C to 50 um
// at 0 C, clamped to 20..50 um outside. Inline, so the conversion's loops over a row vectorize.
inline double ice_effective_radius_um(double temperature_k) {
  const double r = 50.0 + 0.5 * (temperature_k - 273.15);
  const double above = r < 20.0 ? 20.0 : r;  // std::clamp's result, NaN included, as two selects
  return 50.0 < above ? 50.0 : above;
}

// International Standard Atmosphere altitude (m) of a pressure (Pa), troposphere and lower stratosphere.
double isa_altitude_m(double pressure_pa);
double isa_temperature_k(double altitude_m);

}  // namespace cv::importers
