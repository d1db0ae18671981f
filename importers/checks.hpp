// Checks every importer makes on what it derived from a file before it allocates or returns it:
// counts computed in double and refused before an int conversion could overflow, volumes of at
// least two points per axis, and the finished grid as a .cvvol reader checks it. Private to the
// importers target.
#pragma once

#include <cmath>
#include <cstdio>
#include <string>

#include "import_error.hpp"
#include "volume/cloud_volume.hpp"
#include "volume/volume_io.hpp"

namespace cv::importers {

// The number of levels from zmin to zmax at spacing dz (at least 2, at most 1e6), or ImportError
// naming `dz_from` (where the spacing came from) and the range.
inline int checked_level_count(const std::string& path, double zmin, double zmax, double dz, const std::string& dz_from) {
  char buf[320];
  if (!(zmax > zmin)) {
    std::snprintf(buf, sizeof buf, ": the levels' heights span no altitude range (all at %.6g m), expected levels at different heights", zmin);
    throw ImportError(path + buf);
  }
  const double n = std::floor((zmax - zmin) / dz) + 1.0;
  if (!(n >= 2.0 && n <= 1.0e6)) {
    std::snprintf(buf, sizeof buf, ": %s: found a spacing of %.6g m over the altitude range %.6g..%.6g m (%.6g levels), expected 2 to 1000000 levels",
                  dz_from.c_str(), dz, zmin, zmax, n);
    throw ImportError(path + buf);
  }
  return static_cast<int>(n);
}

// The finished volume's grid, checked as read_cvvol checks a header, so no importer hands on a
// grid a volume file could not hold: at least 2 points along each axis.
inline void check_imported_grid(const std::string& path, const core::VolumeGrid& g) {
  if (const std::string problem = core::grid_problem(g); !problem.empty()) {
    throw ImportError(path + ": the imported grid's " + problem);
  }
  if (g.lon_deg.count < 2 || g.lat_deg.count < 2 || g.alt_m.count < 2) {
    throw ImportError(path + ": the imported grid is " + std::to_string(g.lon_deg.count) + " x " + std::to_string(g.lat_deg.count) +
                      " x " + std::to_string(g.alt_m.count) + " points, expected at least 2 along each axis");
  }
}

}  // namespace cv::importers
