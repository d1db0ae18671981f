// Light between the two-stream's columns (docs/physics.md, "Light between the columns"): the
// delta-scaled problem's diffusion (P1) on the grid in three dimensions and in independent columns,
// by the same finite volumes, and their ratio per node. The two-stream source is made per column;
// the ratio carries what its columns leave out (light leaving a narrow cloud through its sides,
// light a thick neighbour sends into a thin edge), and the 3-D solution's horizontal flux gives the
// diffuse light a horizontal first moment, while a horizontally uniform cloud keeps its columns'
// solution (the ratio is 1 there and the horizontal flux 0, whatever the closure's own error).
#pragma once

#include <cstddef>
#include <vector>

#include <glm/vec3.hpp>

#include "volume/cloud_volume.hpp"

namespace cv::core {

// The scaled medium and its beam, per grid node (the grid's layout) and per column.
struct LateralMedium {
  std::vector<float> kappa;   // transport coefficient sigma (1 - g), 1/m (0: clear air, left out)
  std::vector<float> scaled;  // delta-scaled extinction sigma (1 - g^2), 1/m
  std::vector<float>
      gcoef;  // the forward share of the diffuse flux the beam drives, sum sigma (1 - g) g / kappa
  std::vector<float> beam;           // the sun's delta-scaled beam E, 0..1
  std::vector<glm::dvec3> beam_dir;  // per column: the beam's direction of travel in (east, north, up)
  std::vector<double> ground;        // per column: the ground's albedo under the column's lowest cloud
  std::vector<double> ground_light;  // per column: its ground's reflected sunlight A mu0 E (empty: none)
};

struct LateralRatio {
  std::vector<float> ratio;  // 3-D over independent-column fluence per node (1 where both vanish)
  std::vector<float> east,
      north;              // the 3-D diffusion's horizontal first moment over the mean, I1 / I0 = 3 F / phi
  int iterations = 0;     // conjugate-gradient iterations of the 3-D solve
  double residual = 0.0;  // its last relative residual
  // The 3-D solution's balance (W per unit irradiance): the beam's light put into the diffuse
  // field, and the net flow out through the cloud's boundaries (the ground's reflected beam counted
  // as a flow in); equal for a solved system.
  double put_in = 0.0, let_out = 0.0;
};

// Clamp of the ratio: a thin edge beside thick cloud may gain several times its column's light.
inline constexpr double kLateralRatioMax = 8.0;

// The two diffusion solutions and their ratio. The diffusion coefficient is 1 / (3 kappa + 1 / H)
// (H the column's cloud depth: a thin layer's light spreads sideways about as far as the layer is
// deep), the beam's light enters as the source sigma' E with the forward flux g E Omega0 (P1 with
// an anisotropic source). The 3-D system is solved by conjugate gradients preconditioned with each
// column's own tridiagonal system (the vertical coupling is the strong one), from the columns'
// solution, to a relative residual of `tolerance` or `max_iterations`; the sums are taken in a
// fixed order, so the result does not depend on the number of threads. Clear air and the grid's
// edges are vacuum (Marshak's condition, no diffuse light enters); below a column's lowest cloud
// lies its ground (a Lambertian surface of the column's albedo lit by the beam); longitudes wrap on
// global grids. The horizontal moments are those of -D grad phi alone: the beam's own forward flux
// g E Omega0 (nonzero in a uniform slab) is P1's estimate of the diffuse light's asymmetry toward
// the sun, which the slab solver measured too large (docs/physics.md). Clear nodes of a cloudy
// column take the ratio and moments of the column's nearest cloudy node; clear columns keep 1, 0.
LateralRatio lateral_ratio(const VolumeGrid& grid, const LateralMedium& m, double tolerance = 1e-6,
                           int max_iterations = 400);

}  // namespace cv::core
