// Comparing two sources (two models, runs or times): the common grid, chosen explicitly (by default
// the coarser spacing of the two on each axis, over the region and altitudes both hold), each
// source read onto it through the march's sampler, their derived maps, where cloud is in A only,
// B only or both, and the differences B - A of cover, optical depth, base and top.
#pragma once

#include <string>
#include <vector>

#include "volume/cloud_volume.hpp"

namespace cv::core {

// The region both grids hold (degrees; longitudes in A's convention) and the altitudes both span.
struct Overlap {
  double lat_lo = 0, lat_hi = 0, lon_lo = 0, lon_hi = 0, alt_lo = 0, alt_hi = 0;
  bool empty = true;
};
Overlap grid_overlap(const VolumeGrid& a, const VolumeGrid& b);

// The common grid over the overlap with each axis at the coarser of the two spacings, and a line
// that says so ("common grid 13 x 9 x 20: the coarser of A (0.5 deg) and B (1.25 deg) ...").
VolumeGrid common_grid(const VolumeGrid& a, const VolumeGrid& b, const Overlap& o);
std::string common_grid_text(const VolumeGrid& common, const VolumeGrid& a, const VolumeGrid& b);

// A step's cloud fields (fraction, liquid and ice extinction) and ground read onto `to` by the
// sampler (trilinear, no data NaN), with its maps derived there.
TimeStepData resample_step(const VolumeGrid& from, const TimeStepData& data, const VolumeGrid& to);

enum class Presence : unsigned char { None = 0, OnlyA = 1, OnlyB = 2, Both = 3 };

struct Comparison {
  VolumeGrid grid;                 // the common grid
  TimeStepData a, b;               // both sources on it, with their maps
  std::vector<Presence> columns;   // per column: where a column holds cloud (a cloudy base)
  std::vector<Presence> points;    // per node of the common grid: derive_maps' cloudy rule
  // B - A per column; NaN where either has no data (and for base and top, where either has no cloud).
  std::vector<float> d_cover, d_optical_depth, d_base_m, d_top_m;
};
Comparison compare_steps(const VolumeGrid& grid_a, const TimeStepData& a, const VolumeGrid& grid_b, const TimeStepData& b,
                         const VolumeGrid& common, const MapOptions& options = {});

// The medium of the rendered difference view, on the common grid: at each node, cloud in A only as
// liquid (A's grid-mean extinction), in B only as ice (B's), in both as half the larger of the two
// in each, so that a tint per component (march.tint_liquid / tint_ice) colours the three and
// agreement takes the tints' mean. Cloud fraction 1 wherever there is extinction (in-cloud =
// grid-mean); nodes cloudy in neither (Comparison::points) are clear. A's ground, its maps derived.
TimeStepData presence_medium(const Comparison& c);

}  // namespace cv::core
