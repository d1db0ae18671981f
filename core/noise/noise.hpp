// Tileable 3-D noise for sub-grid cloud detail, generated at start-up: a low-frequency
// Perlin-Worley texture and a high-frequency Worley fBm texture, both periodic in all three axes,
// deterministic for a seed, values in [0, 1]. The CPU reference samples these arrays and the GPU
// raymarcher uploads the same ones, so both erode the clouds identically.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

namespace cv::core {

// A periodic cube of n^3 texels, x fastest; texel (i, j, k) holds the noise at tile coordinates
// (i, j, k) / n, and coordinate 1 is coordinate 0 again.
struct NoiseTexture {
  int n = 0;
  std::vector<float> texels;
  float at(int i, int j, int k) const { return texels[(static_cast<std::size_t>(k) * n + j) * n + i]; }
  // Trilinear with wrap-around at tile coordinates t (any real; taken modulo 1), in double, through
  // the same texel addressing (shaders/common/erosion.glsl) as the GPU.
  double sample(const glm::dvec3& t) const;
};

struct ErosionNoise {
  NoiseTexture low;   // Perlin fBm dilated by inverted-Worley fBm ("Perlin-Worley")
  NoiseTexture high;  // inverted-Worley fBm, repeated 4 times per low-frequency tile
  // The modelled cloud's table over these tiles (detail_table): (threshold, ramp mean) per cover;
  // empty until a caller that draws the modelled cloud makes it (with_detail_table).
  std::vector<float> detail;
};

// The modelled cloud's table (shaders/common/detail.glsl): for each cover c = (k / CV_DETAIL_COVERS)^2
// (k = 0..CV_DETAIL_COVERS), the threshold t(c) of the noise n = detail_noise_mix(low, high) above
// which a share c of the tile lies, and the tile's mean m(c) of detail_ramp(n, t(c), s) for each
// cloud type's softness s (detail_softness). The tile's distribution of n is taken over `samples`
// uniform random points of the low-frequency tile (a fixed sequence), interpolated as the kernel
// interpolates the textures. CV_DETAIL_TYPES rows (stratiform, cumuliform, cirriform) of
// CV_DETAIL_COVERS + 1 entries, (t, m) per entry, rows one after the other; then the types' first
// moments per phase (the cell-mean correction), then the same (t, m) rows for each of the
// CV_DETAIL_SLICES horizontal slices of the tile's height, from the points in that slice (the
// tile's entries where fewer than 256 of them lie above the threshold): a texture of
// CV_DETAIL_COVERS + 1 by CV_DETAIL_ROWS texels. t(0) is the largest n (no cloud), t(1) the smallest.
std::vector<float> detail_table(const NoiseTexture& low, const NoiseTexture& high, std::size_t samples = std::size_t(1) << 22,
                                unsigned threads = 0);
// noise with its detail table made (once: an existing table is kept).
inline ErosionNoise& with_detail_table(ErosionNoise& noise) {
  if (noise.detail.empty()) noise.detail = detail_table(noise.low, noise.high);
  return noise;
}

// Generates both textures (low_n^3 and high_n^3 texels), using up to `threads` threads
// (0: the hardware's count).
ErosionNoise make_erosion_noise(int low_n = 64, int high_n = 32, std::uint32_t seed = 1, unsigned threads = 0);

// The continuous noises the textures are built from, periodic with `period` lattice cells in each
// axis: p is in lattice cells. Exposed for tests (tiling and range).
double perlin_periodic(const glm::dvec3& p, int period, std::uint32_t seed);  // about [-1, 1]
double worley_periodic(const glm::dvec3& p, int period, std::uint32_t seed);  // F1 distance, cells

// Where the noise is anchored for a volume: a point near the data (its centre on the sphere),
// exactly representable in float so the GPU and the CPU measure from the same point, and that
// point's own position in tiles of period_m metres, fract(anchor / period), in double.
struct NoiseAnchor {
  glm::dvec3 ecef_m{0.0};
  glm::dvec3 frac{0.0};
};
NoiseAnchor noise_anchor(const glm::dvec3& centre_ecef_m, double period_m);

}  // namespace cv::core
