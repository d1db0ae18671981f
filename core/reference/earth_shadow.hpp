// Whether the sun is below the horizon for a whole cloud layer: then no sample of it can be
// sunlit, and both marchers leave out every sun march and octave sum for the frame (ambient sky
// light still applies). Decided once per frame on the CPU, conservatively.
#pragma once

#include <string>

#include <glm/vec3.hpp>

#include "volume/grid_mean.hpp"

namespace cv::core {

// True only when every point of the layer (altitudes layer.bottom_m..top_m) over the grid's
// domain, the one-cell border a regional grid fades into included, lies in the Earth's shadow
// (the sphere of grid.earth_radius_m, sun at infinity along to_sun, a unit vector). Global grids
// always have a lit side: false. Empty layers: false (there is nothing to leave out).
//
// A point at radius r is in the shadow when its angular distance from the antisolar point is
// below asin(R / r); the layer's top is the hardest. The largest distance over a lon/lat box lies
// on its boundary unless the subsolar point is inside (then it is lit), so the boundary is sampled
// densely and the result kept off the threshold by the sampling spacing plus a float margin.
bool layer_in_earth_shadow(const VolumeGrid& grid, const CloudLayer& layer, const glm::dvec3& to_sun);

// A lower bound of the cosine between the local vertical and the sun direction over the grid's
// domain (the border cell included): the lowest the sun stands anywhere a sample can hold cloud.
// -1 for global grids and when the antisolar point is inside the box. Sampled as above, with the
// largest angle raised by the spacing and the float margin. Bounds the length of a sun march
// (max_sun_march_steps), so a high sun does not size llvmpipe's dispatches for a grazing one.
double smallest_sun_cosine(const VolumeGrid& grid, const glm::dvec3& to_sun);

// An upper bound of the cosine between the local vertical and the sun direction over the grid's
// domain (the border cell included): the highest the sun stands anywhere over the data. 1 for
// global grids and when the subsolar point is inside the box. Sampled as above, with the smallest
// angle lowered by the spacing and the float margin. Tells a render whose whole domain is at dawn
// or dusk (the sun within a few degrees of the horizon everywhere), where the image is mostly
// twilight.
double largest_sun_cosine(const VolumeGrid& grid, const glm::dvec3& to_sun);

// Below this elevation everywhere over the data (degrees), the domain is at dawn or dusk: the clouds
// are lit at a grazing angle through the air's reddest light and the automatic exposure brightens a
// twilight sky, so `render` and the viewer say so and name the teaching sun (local noon).
constexpr double kTwilightElevationDeg = 5.0;

// The highest the sun stands over the grid's domain, degrees above the horizon (an upper bound,
// from largest_sun_cosine).
double highest_sun_elevation_deg(const VolumeGrid& grid, const glm::dvec3& to_sun);

// How a tool says where the sun stands, from that highest elevation: "the sun stands at most 0.8
// degrees above the horizon over the data (dawn or dusk there)", or below the horizon everywhere
// (twilight down to 18 degrees below it, night further down).
std::string low_sun_words(double highest_deg);

}  // namespace cv::core
