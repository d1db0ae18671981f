// Where the ground is water: the GSHHS shorelines (Wessel & Smith 1996; the shapefiles of Debian's
// python-cartopy-data) rasterised with shapelib into a water fraction per texel of an
// equirectangular grid, supersampled so coastal texels get fractions.
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace cv::render {

// Where python-cartopy-data installs GSHHS: DIR/<resolution>/GSHHS_<resolution>_L<level>.shp.
constexpr const char* kGshhsDir = "/usr/share/cartopy/data/shapefiles/gshhs";

// A closed polygon of GSHHS level `level` (1 land, 2 lake, 3 island in a lake, 4 pond on such an
// island), longitude and latitude in degrees, as the shapefile holds it (no wrap across 180: GSHHS
// splits polygons there). Rings of one polygon (parts) combine even-odd.
struct ShorePolygon {
  int level = 1;
  std::vector<std::vector<double>> rings;  // each ring: lon0, lat0, lon1, lat1, ...
};

// A water fraction per texel, rows from latitude 90 down, columns from longitude -180 (as
// core::AlbedoMap).
struct WaterFraction {
  int width = 0, height = 0;
  std::vector<float> water;
  std::string source;  // what it was made from, e.g. "GSHHS c L1, l L2 (4 x 4 samples per texel)"
};

// Appends the polygons of one GSHHS shapefile (its path without .shp), all of `level`, to `out`
// (the overlays' coastlines read them too); throws std::runtime_error naming a file it cannot read.
void read_shore_polygons(const std::string& base, int level, std::vector<ShorePolygon>& out);

// Rasterises polygons onto a w x h grid, ss x ss samples per texel at their centres: a sample is
// land when the highest level among the polygons containing it is odd (in land, not in a lake or
// in an island in one), water otherwise (none, or a lake); a texel's water fraction is its share
// of water samples.
WaterFraction rasterise_water(const std::vector<ShorePolygon>& polygons, int w, int h, int ss);

// The GSHHS resolution ('c', 'l', 'i', 'h', 'f') whose detail fits texels of a w-pixel-wide map:
// the coarsest whose shorelines are resolved to half a texel (c: ~25 km, l: ~5 km, i: ~1 km, ...).
char gshhs_resolution_for(int w);

// The water fraction of a w x h map from the GSHHS files under dir: for each level the file of the
// resolution that fits (gshhs_resolution_for), else the nearest one installed (finer first).
// Nothing (nullopt) when dir holds no level-1 (land) file; a shapefile that cannot be read throws
// std::runtime_error naming it.
std::optional<WaterFraction> gshhs_water_fraction(int w, int h, const std::string& dir = kGshhsDir);

}  // namespace cv::render
