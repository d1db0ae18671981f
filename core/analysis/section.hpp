// Vertical sections for analysts: a field against distance along the great circle between two
// points and altitude, read through the march's sampler (volume/sampler.hpp), with the ground and
// where the cloud is (derive_maps' cloudy rule) per sample, so a plot can mark both.
#pragma once

#include <string>
#include <vector>

#include "geo/geodesy.hpp"
#include "volume/cloud_volume.hpp"
#include "volume/grid_mean.hpp"

namespace cv::core {

// What a section shows: one of the volume's fields, or the extinction the march samples
// (grid-box mean, liquid + ice).
struct SectionField {
  bool march_extinction = false;
  Field field = Field::CloudFraction;
  std::string name() const { return march_extinction ? "extinction" : field_name(field); }
  std::string units() const { return march_extinction ? "1/m" : field_units(field); }
};
// The field a name selects among those the volume holds (and "extinction"), or
// std::invalid_argument "found \"rain\", expected extinction or a field the volume holds: ...".
SectionField section_field(const CloudVolume& volume, const std::string& name);

struct Section {
  std::vector<geo::PathPoint> path;  // the columns, evenly along the great circle
  std::vector<double> alt_m;         // the rows, ascending
  double length_m = 0.0;
  // Per column and row (row fastest: value[i * rows + k]): the field (NaN: no data), and whether
  // the point is cloudy.
  std::vector<double> value;
  std::vector<unsigned char> cloudy;
  std::vector<double> ground_m;      // per column; NaN where the volume has no terrain
  std::size_t rows() const { return alt_m.size(); }
};

// The smallest horizontal cell of the grid (m): a section must be at least this long.
double smallest_cell_m(const VolumeGrid& grid);

// The section of one step from (lat1, lon1) to (lat2, lon2) with `columns` columns at the given
// altitudes. std::invalid_argument naming the end ("--from"/"--to" meaning) when an end lies outside
// the data, or when the path is shorter than one grid cell.
Section vertical_section(const CloudVolume& volume, const TimeStepData& data, const GridMeanExtinction& medium,
                         const SectionField& field, double lat1_deg, double lon1_deg, double lat2_deg, double lon2_deg, int columns,
                         const std::vector<double>& alt_m, const MapOptions& options = {});

}  // namespace cv::core
