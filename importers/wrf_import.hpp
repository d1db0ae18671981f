// The WRF reader (private to the importers target).
#pragma once

#include <memory>
#include <string>
#include <utility>

#include "importer.hpp"
#include "nc_file.hpp"

namespace cv::importers {

bool is_wrf_file(const NcFile& f);
// A WRF GEOGRID static file (geo_em.d0N.nc: XLAT_M, XLONG_M, HGT_M): terrain, no cloud.
bool is_wrf_geogrid_file(const NcFile& f);
// The one line that says what such a file is and why it is not imported.
std::string wrf_geogrid_message(const NcFile& f);
core::CloudVolume import_wrf(std::unique_ptr<NcFile> file, const ImportOptions& options);
std::string describe_wrf(const NcFile& f);
// (cos, sin) of the grid-to-earth wind rotation at a point, from the projection alone (used when
// the file has no COSALPHA/SINALPHA).
std::pair<double, double> wrf_rotation_from_projection(const NcFile& f, double lat, double lon);

}  // namespace cv::importers
