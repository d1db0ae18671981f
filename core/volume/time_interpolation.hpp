// The medium between two forecast steps: the renderer's grid-mean extinction at an instant inside a
// step interval, by the nearest step, a linear blend, or each neighbour carried along the model's
// winds (semi-Lagrangian) and then blended. Computed once per instant on the CPU, so the GPU march
// and the CPU reference read the same field (docs/physics.md, "Between forecast steps").
#pragma once

#include <string>
#include <vector>

#include "volume/grid_mean.hpp"

namespace cv::core {

enum class TimeInterpolation { Auto, Nearest, Linear, Advected };
// "auto", "nearest", "linear", "advected" (and back); parse returns false for anything else.
const char* time_interpolation_name(TimeInterpolation m);
bool parse_time_interpolation(const std::string& text, TimeInterpolation& out);

// One step's winds (m/s; eastward, northward, upward), each a field of the grid or empty where the
// file has none. NaN (no data) counts as calm.
struct StepWinds {
  std::vector<float> u, v, w;
  bool horizontal() const { return !u.empty() && !v.empty(); }
};
StepWinds step_winds(const TimeStepData& data);

struct TimeInterpolationReport {
  TimeInterpolation used = TimeInterpolation::Nearest;  // after Auto and the fallback are decided
  std::string warning;       // not empty when `advected` fell back to `linear` (no winds)
  int substeps = 0;          // the most trajectory sub-steps any trajectory took (advected)
  int stride = 1;            // trajectories on every stride-th node of each horizontal axis (advected)
  double max_courant = 0.0;  // the largest wind over the gap, in grid cells (advected)
  bool vertical_wind = false;
  // Per neighbour (earlier, later) and species (liquid, ice): the factor (<= 1) that brought the
  // carried field's area-weighted optical depth back to its source step's where the warp raised it.
  double rescale[2][2] = {{1.0, 1.0}, {1.0, 1.0}};
  double cost_ms = 0.0;      // wall time of the interpolation
};

// Trajectory sub-steps are bounded: beyond it a sub-step moves more than one cell, which costs
// trajectory accuracy but not stability (every value is interpolated from the source field).
constexpr int kMaxAdvectionSubsteps = 64;

// Trajectories run on every node of grids up to this many columns (256 x 256); on larger grids on
// every stride-th node of longitude and latitude (every level), the smallest stride that keeps
// the lattice within it, and the nodes between take the bilinear blend of their lattice nodes'
// displacements (docs/physics.md, "Between forecast steps"). A global 0.25-degree grid: stride 4.
constexpr int kMaxTrajectoryColumns = 65536;
int trajectory_stride(const VolumeGrid& grid);

// The extinction at `fraction` (0: the earlier step e0, 1: the later e1) of a gap of gap_s seconds.
// Auto is advected where both steps have horizontal winds, else linear; advected without winds
// falls back to linear and says so in report.warning. Never negative; finite for any winds and gap.
GridMeanExtinction interpolate_extinction(const VolumeGrid& grid, const GridMeanExtinction& e0, const GridMeanExtinction& e1,
                                          const StepWinds& w0, const StepWinds& w1, double gap_s, double fraction,
                                          TimeInterpolation mode, TimeInterpolationReport* report = nullptr);

// One field carried by the (time-interpolated) winds from step `from` (0 or 1) to `fraction`:
// trilinear at the departure (from 0) or arrival (from 1) point of each node's trajectory, which
// runs in sub-steps of the midpoint rule of at most a cell each where the wind allows (at most
// kMaxAdvectionSubsteps), on the lattice of trajectory_stride. *substeps: the most any trajectory
// took. stride 0: trajectory_stride(grid); 1: every node's own trajectory. Exposed for tests;
// interpolate_extinction carries its fields the same way.
std::vector<float> advect_field(const VolumeGrid& grid, const std::vector<float>& field, const StepWinds& w0,
                                const StepWinds& w1, double gap_s, double fraction, int from, int* substeps = nullptr,
                                double* max_courant = nullptr, int stride = 0);

// The winds at an instant as the angular motion they give a point, in degrees of longitude and
// latitude per second (u / ((R + z) cos lat), v / (R + z)), box-averaged onto every `stride`-th
// node of each horizontal axis so that at most `max_nodes` remain per axis (every level is kept).
// While an advected forecast plays, the field between two instants moves by about this times their
// gap: the viewer's reprojection moves its history with it (docs/physics.md, "Temporal
// reprojection"). Linear in time between the steps; NaN counts as calm (as in the advection).
struct AngularFlow {
  RegularAxis lon_deg, lat_deg;  // the coarse nodes (every stride-th node of the grid's axes)
  int levels = 0;                // the grid's levels
  // (longitude, latitude) rate per coarse node: longitude fastest, then latitude, then level.
  std::vector<float> deg_per_s;
  bool empty() const { return deg_per_s.empty(); }
};
// Empty unless both steps have horizontal winds of the grid's size.
AngularFlow angular_flow(const VolumeGrid& grid, const StepWinds& w0, const StepWinds& w1, double fraction,
                         int max_nodes = 128);

}  // namespace cv::core
