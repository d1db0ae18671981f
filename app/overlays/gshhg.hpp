// Borders, rivers and shorelines of GSHHG (the Global Self-consistent, Hierarchical,
// High-resolution Geography database) through the GMT library's `coast` module, from the binned
// netCDF files of Debian's gmt-gshhg-low (resolutions c, l, i), gmt-gshhg-high (h) and
// gmt-gshhg-full (f). GMT is PRIVATE to cv_overlays: nothing above sees it.
#pragma once

#include <string>
#include <vector>

#include <glm/vec2.hpp>

namespace cv::overlays {

inline constexpr const char* kGshhgDir = "/usr/share/gmt-gshhg";

enum class GshhgFeature { Shore, Border, River };

// A lon/lat box (degrees); `global` true takes the whole Earth.
struct GeoBox {
  bool global = true;
  double lon_min = -180.0, lon_max = 180.0, lat_min = -90.0, lat_max = 90.0;
};

// The polylines (lon, lat in degrees) of a feature at resolution `res` (c, l, i, h, f; the nearest
// installed when that one is not, finer first), inside `box`. `select` is the feature's class in
// GMT's letters: for borders 1 (national), 2 (states of the Americas), 3 (marine) or a (all); for
// rivers 1 (permanent major), r (all permanent), a (all, with canals); ignored for shores.
// `chosen` (when given) receives the resolution read. Throws OverlayError naming the package that
// provides the files when none is installed under `dir`, and GMT's own message when it fails.
std::vector<std::vector<glm::dvec2>> read_gshhg_lines(GshhgFeature feature, char res, const std::string& select, const GeoBox& box,
                                                      const std::string& dir = kGshhgDir, char* chosen = nullptr);

}  // namespace cv::overlays
