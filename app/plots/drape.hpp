// 2-D maps of a grid's columns draped on the globe (issue 17, item 3: the difference maps of
// `compare --render-maps`): each pixel of a camera's view whose ray meets the sphere takes the
// colour of the grid column under it, shaded by the surface's tilt to the view, so the map reads as
// part of the globe the 3-D views show (the same camera frames both).
#pragma once

#include <cstddef>
#include <functional>
#include <optional>

#include "frame/camera.hpp"
#include "plots/plot_canvas.hpp"
#include "volume/cloud_volume.hpp"

namespace cv::plots {

// The globe outside the grid: a slate grey, apart from kNoData's light grey.
inline const Rgb kGlobe{95, 105, 120};

// The column of `g` nearest (lat, lon) (longitude taken modulo 360), or nothing outside the grid.
std::optional<std::size_t> column_at(const core::VolumeGrid& g, double lat_deg, double lon_deg);

// Draws the view of `cam` (its width x height) into `c` with its top left at (x0, y0): where a
// pixel's ray meets the sphere of the grid's radius inside the grid, colour(column) times the
// shade 0.6 + 0.4 cos(angle between the surface normal and the way back to the camera); elsewhere
// on the sphere kGlobe in the same shade, off the sphere black (space).
void drape_columns(Canvas& c, int x0, int y0, const core::Camera& cam, const core::VolumeGrid& g,
                   const std::function<Rgb(std::size_t column)>& colour);

}  // namespace cv::plots
