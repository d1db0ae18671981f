// The extinction pyramid and the march it drives (CPU reference): every brick bounds what sampling
// can return in it, empty jumps land only on empty space, skipping leaves the image unchanged, and
// steps adapted to optical depth converge faster on a towering cell.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include <glm/glm.hpp>

#include "geo/geodesy.hpp"
#include "reference/raymarcher.hpp"
#include "volume/extinction_pyramid.hpp"
#include "volume/sampler.hpp"

namespace {
using namespace cv::core;
namespace geo = cv::geo;

// Sparse blobs of liquid and ice on a grid: mostly empty, like real cloud fields.
TimeStepData sparse_blobs(const VolumeGrid& g, unsigned seed) {
  TimeStepData d;
  d[Field::ExtinctionLiquid].assign(g.points(), 0.0f);
  d[Field::ExtinctionIce].assign(g.points(), 0.0f);
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> ix(0, g.lon_deg.count - 1), iy(0, g.lat_deg.count - 1), iz(0, g.alt_m.count - 1);
  for (int n = 0; n < 12; ++n) {
    const int x = ix(rng), y = iy(rng), z = iz(rng);
    // A single node here and there (the hardest case for the bound: one node, its bricks only).
    d[n % 2 ? Field::ExtinctionIce : Field::ExtinctionLiquid][g.index(x, y, z)] = 1e-3f * static_cast<float>(n + 1);
  }
  return d;
}

// For random points: the sample never exceeds the finest brick's max, and when the pyramid says
// empty for a random direction, random points along it within the jump distance sample exactly 0.
void expect_bounds(const VolumeGrid& g, const char* name) {
  const TimeStepData d = sparse_blobs(g, 7);
  const GridMeanExtinction m = grid_mean_extinction(g, d);
  const ExtinctionPyramid pyr(g, m.liquid_per_m, m.ice_per_m);
  const VolumeSampler liquid(g, m.liquid_per_m), ice(g, m.ice_per_m);
  auto sample = [&](const glm::dvec3& p) {
    const geo::Geodetic s = geo::ecef_to_sphere(p, g.earth_radius_m);
    return liquid.sample(s.lat_deg, s.lon_deg, s.alt_m, 0.0) + ice.sample(s.lat_deg, s.lon_deg, s.alt_m, 0.0);
  };
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double lon_span = g.lon_deg.step * g.lon_deg.count + 4.0, lat_span = g.lat_deg.step * g.lat_deg.count + 4.0;
  int empty = 0, full = 0, probes = 0;
  for (int n = 0; n < 20000; ++n) {
    const double lon = g.lon_deg.start - 2.0 + u(rng) * lon_span;
    const double lat = std::clamp(g.lat_deg.start - 2.0 + u(rng) * lat_span, -90.0, 90.0);
    const double alt = g.alt_m.start + u(rng) * (g.alt_m.last() - g.alt_m.start);
    const glm::dvec3 p = geo::sphere_to_ecef({lat, lon, alt}, g.earth_radius_m);
    const glm::dvec3 dir = glm::normalize(glm::dvec3(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5));
    const ExtinctionPyramid::Space sp = pyr.at(p, dir);
    const double v = sample(p);
    if (!sp.empty) {
      ++full;
      ASSERT_LE(v, sp.sigma_max_per_m * (1.0 + 1e-6)) << name << " at " << lat << ", " << lon << ", " << alt;
      continue;
    }
    ++empty;
    ASSERT_EQ(v, 0.0) << name << " at " << lat << ", " << lon << ", " << alt;
    for (int k = 0; k < 8; ++k) {
      const glm::dvec3 q = p + u(rng) * sp.extent_m * dir;
      ++probes;
      ASSERT_EQ(sample(q), 0.0) << name << ": a jump of " << sp.extent_m << " m from " << lat << ", " << lon << ", "
                                << alt << " reaches cloud";
    }
  }
  std::printf("%s: %d points in empty bricks (%d probes within the jump), %d in bricks with cloud\n", name, empty,
              probes, full);
  EXPECT_GT(empty, 1000) << name;
  EXPECT_GT(full, 100) << name;
}

TEST(Pyramid, BricksBoundTheSamplesAndJumpsStayInEmptySpace) {
  VolumeGrid regional;  // across the date line, coarse enough that single nodes matter
  regional.lon_deg = {170.0, 0.5, 23};
  regional.lat_deg = {-5.0, 0.5, 17};
  regional.alt_m = {500.0, 500.0, 13};
  expect_bounds(regional, "regional");
  VolumeGrid global;  // wraps in longitude, rows at the poles
  global.lon_deg = {0.0, 10.0, 36};
  global.lat_deg = {-90.0, 10.0, 19};
  global.alt_m = {0.0, 1000.0, 9};
  expect_bounds(global, "global");
}

// A towering cell (optical depth ~ 400 across its core) in a wide empty box.
struct Tower {
  VolumeGrid grid;
  TimeStepData data;
  Tower() {
    grid.lon_deg = {-2.0, 0.05, 81};
    grid.lat_deg = {-2.0, 0.05, 81};
    grid.alt_m = {0.0, 500.0, 31};
    data[Field::ExtinctionLiquid].assign(grid.points(), 0.0f);
    for (int k = 0; k < grid.alt_m.count; ++k)
      for (int j = 0; j < grid.lat_deg.count; ++j)
        for (int i = 0; i < grid.lon_deg.count; ++i) {
          const double x = grid.lon_deg.at(i), y = grid.lat_deg.at(j), z = grid.alt_m.at(k);
          const double r2 = (x * x + y * y) / (0.15 * 0.15);
          if (r2 < 1.0 && z > 1000.0 && z < 12000.0)
            data[Field::ExtinctionLiquid][grid.index(i, j, k)] = static_cast<float>(0.02 * (1.0 - r2));
        }
  }
};

Camera tower_camera() {
  Camera c;  // 100 km south of the tower, looking at it
  c.lat_deg = -0.9;
  c.alt_m = 4000.0;
  c.pitch_deg = 1.0;
  c.fov_deg = 30.0;
  c.width = 24;
  c.height = 14;
  return c;
}

Sun tower_sun() {
  Sun s;
  s.subsolar_lat_deg = 20.0;
  s.subsolar_lon_deg = 40.0;
  return s;
}

TEST(Pyramid, SkippingEmptySpaceLeavesTheImageUnchanged) {
  const Tower t;
  const GridMeanExtinction m = grid_mean_extinction(t.grid, t.data);
  MarchSettings s;
  s.quality.view_step_m = 250.0;
  s.quality.sun_steps = 16;
  s.quality.octaves = 4;
  s.quality.min_transmittance = 0.0;  // no early exits: only skipping differs
  for (int frame : {-1, 5}) {
    s.per_frame.frame = frame;
    s.features.skip_empty = false;
    const ReferenceImage plain = render_reference(t.grid, m, tower_camera(), tower_sun(), s);
    s.features.skip_empty = true;
    const ReferenceImage skip = render_reference(t.grid, m, tower_camera(), tower_sun(), s);
    double max_l = 0.0, worst = 0.0, worst_t = 0.0;
    for (const auto& l : plain.radiance) max_l = std::max(max_l, l.x);
    ASSERT_GT(max_l, 0.0);
    for (std::size_t i = 0; i < plain.radiance.size(); ++i) {
      worst = std::max(worst, glm::length(plain.radiance[i] - skip.radiance[i]) / max_l);
      worst_t = std::max(worst_t, std::abs(plain.transmittance[i] - skip.transmittance[i]));
    }
    std::printf("frame %d: skipping changed radiance by %.3g of the brightest, transmittance by %.3g; view samples "
                "%llu -> %llu (%llu skipped, %llu jumps), sun samples %llu -> %llu\n",
                frame, worst, worst_t, static_cast<unsigned long long>(plain.stats.view_samples),
                static_cast<unsigned long long>(skip.stats.view_samples),
                static_cast<unsigned long long>(skip.stats.view_skipped),
                static_cast<unsigned long long>(skip.stats.bricks_jumped),
                static_cast<unsigned long long>(plain.stats.sun_samples),
                static_cast<unsigned long long>(skip.stats.sun_samples));
    EXPECT_LT(worst, 1e-12);
    EXPECT_LT(worst_t, 1e-12);
    // Every view step position was either sampled or skipped.
    EXPECT_EQ(plain.stats.view_samples, skip.stats.view_samples + skip.stats.view_skipped);
    // The box is mostly empty; what stays is the tower itself (measured: 198 134 -> 55 208).
    EXPECT_LT(skip.stats.view_samples * 3, plain.stats.view_samples);
    // The sun march runs only through the layer that holds cloud (cloud_layer), which already leaves
    // out the empty air above the tower: skipping may find nothing more there.
    EXPECT_LE(skip.stats.sun_samples, plain.stats.sun_samples);
  }
}

}  // namespace

namespace {

// Error of an image against a reference: mean over pixels of the radiance difference, relative to
// the reference's brightest pixel.
double mean_error(const ReferenceImage& a, const ReferenceImage& ref) {
  double max_l = 0.0, sum = 0.0;
  for (const auto& l : ref.radiance) max_l = std::max(max_l, l.x);
  for (std::size_t i = 0; i < ref.radiance.size(); ++i) sum += std::abs(a.radiance[i].x - ref.radiance[i].x);
  return sum / static_cast<double>(ref.radiance.size()) / max_l;
}

TEST(Pyramid, AdaptedStepsConvergeFasterOnATowerAtEqualSamples) {
  const Tower t;
  const GridMeanExtinction m = grid_mean_extinction(t.grid, t.data);
  MarchSettings s;
  s.quality.sun_steps = 16;
  s.quality.octaves = 4;
  s.quality.view_step_m = 5.0;  // the reference: a fixed 5 m step (optical depth <= 0.1 per step)
  const ReferenceImage ref = render_reference(t.grid, m, tower_camera(), tower_sun(), s);
  s.features.adaptive_steps = true;
  s.quality.max_step_optical_depth = 0.5;
  int wins = 0, cases = 0;
  for (double step : {2000.0, 1000.0, 500.0}) {
    s.features.adaptive_steps = true;
    s.quality.view_step_m = step;
    const ReferenceImage adaptive = render_reference(t.grid, m, tower_camera(), tower_sun(), s);
    // The fixed step with at least as many view samples as the adaptive march took.
    s.features.adaptive_steps = false;
    ReferenceImage fixed;
    for (s.quality.view_step_m = step; s.quality.view_step_m > 1.0; s.quality.view_step_m *= 0.8) {
      fixed = render_reference(t.grid, m, tower_camera(), tower_sun(), s);
      if (fixed.stats.view_samples >= adaptive.stats.view_samples) break;
    }
    const double e_a = mean_error(adaptive, ref), e_f = mean_error(fixed, ref);
    std::printf("base step %6.0f m adaptive: %7llu view samples, error %.3g | fixed %6.1f m: %7llu samples, error %.3g\n",
                step, static_cast<unsigned long long>(adaptive.stats.view_samples), e_a, s.quality.view_step_m,
                static_cast<unsigned long long>(fixed.stats.view_samples), e_f);
    ++cases;
    wins += e_a < e_f;
    EXPECT_GE(fixed.stats.view_samples, adaptive.stats.view_samples);
  }
  EXPECT_EQ(wins, cases);
}

}  // namespace
