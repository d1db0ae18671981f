// A min/max pyramid of extinction over bricks of the grid, for empty-space skipping and steps
// adapted to optical depth: each brick bounds every value trilinear sampling can return inside it.
#pragma once

#include <cstddef>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "volume/cloud_volume.hpp"

namespace cv::core {

class ExtinctionPyramid {
 public:
  static constexpr int kFinestNodes = 4;  // grid nodes per brick side at level 0; doubles per level
  static constexpr int kMaxLevels = 4;

  struct Level {
    int nodes = kFinestNodes;  // grid nodes per brick side
    int nx = 0, ny = 0, nz = 0;  // bricks per axis
    // (min, max) of liquid + ice extinction (1/m) over the brick's nodes dilated by one node on
    // every side: a sample inside the brick interpolates nodes floor(f) and floor(f) + 1, the
    // sampler shifts the last row and level down by one, and float positions may round across a
    // face; all those nodes are within the dilation.
    std::vector<glm::vec2> min_max;
    std::size_t index(int x, int y, int z) const {
      return (std::size_t(z) * std::size_t(ny) + std::size_t(y)) * std::size_t(nx) + std::size_t(x);
    }
  };

  ExtinctionPyramid() = default;
  // liquid and ice: grid-mean extinction per node (longitude fastest), either may be empty.
  ExtinctionPyramid(const VolumeGrid& grid, const std::vector<float>& liquid_per_m, const std::vector<float>& ice_per_m,
                    int levels = 3);

  const std::vector<Level>& levels() const { return levels_; }

  // What a ray through a point (direction dir, unit) learns about the space ahead (double-precision
  // twin of space_at in shaders/kernel/march.glsl, which tests hold it against): empty with the distance it may jump (m), or
  // not empty with the finest brick's largest extinction and the distance (m) over which that
  // brick still holds it.
  struct Space {
    bool empty = false;
    double extent_m = 0.0;
    double sigma_max_per_m = 0.0;
  };
  Space at(const glm::dvec3& ecef_m, const glm::dvec3& dir) const;

 private:
  VolumeGrid grid_;
  bool wraps_ = false, global_lat_ = false;
  std::vector<Level> levels_;  // finest first
};

}  // namespace cv::core
