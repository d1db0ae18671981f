// The whole-layer night test (core/reference/earth_shadow): whenever it says the layer is in the
// Earth's shadow, no point of the layer over the domain is sunlit by the marchers' own per-sample
// test; it does say so on the night side; and night leaves the reference image as it was.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <utility>

#include <glm/glm.hpp>

#include "geo/geodesy.hpp"
#include "physics/physics.hpp"
#include "reference/earth_shadow.hpp"
#include "bench/standard_scenes.hpp"
#include "reference/raymarcher.hpp"

#include "night_sun.hpp"

namespace {
using namespace cv::core;
using namespace cv::bench;
namespace geo = cv::geo;
namespace p64 = cv::physics::f64;
using cv::test::sun_at;
using cv::test::sun_just_down;
// Whether the raymarchers' per-sample test finds a point sunlit (raymarcher.cpp march_sample).
bool sunlit(const glm::dvec3& p, double r0, const glm::dvec3& to_sun) {
  const glm::dvec3 up = glm::normalize(p);
  const double alt = glm::length(p) - r0, mu = glm::dot(to_sun, up), nu = glm::length(glm::cross(to_sun, up));
  double e0, e1;
  return !(p64::ray_sphere_rel_nu(r0, alt, mu, nu, 0.0, e0, e1) && e1 > 0.0);
}

TEST(EarthShadow, NeverCallsALitLayerDark) {
  VolumeGrid g;
  g.lon_deg = {170.0, 0.5, 31};  // 170..185 E: across the date line
  g.lat_deg = {50.0, 0.5, 21};   // 50..60 N
  g.alt_m = {0.0, 500.0, 25};
  CloudLayer layer;
  layer.empty = false;
  layer.bottom_m = 1000.0;
  layer.top_m = 11000.0;
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int dark = 0, lit = 0;
  for (double azimuth : {0.0, 90.0, 135.0, 180.0, 270.0}) {
    for (double theta = 88.0; theta <= 110.0; theta += 0.25) {
      const glm::dvec3 sun = sun_at(55.0, 177.5, theta, azimuth);
      if (!layer_in_earth_shadow(g, layer, sun)) {
        ++lit;
        continue;
      }
      ++dark;
      // Random points over the domain and its border cell, at the layer's top (the hardest) and inside it.
      for (int n = 0; n < 4000; ++n) {
        const double lon = 169.5 + 16.0 * u(rng), lat = 49.5 + 11.0 * u(rng);
        const double alt = n % 2 ? layer.top_m : layer.bottom_m + u(rng) * (layer.top_m - layer.bottom_m);
        ASSERT_FALSE(sunlit(geo::sphere_to_ecef({lat, lon, alt}, g.earth_radius_m), g.earth_radius_m, sun))
            << "azimuth " << azimuth << " theta " << theta << " at " << lat << ", " << lon << ", " << alt;
      }
    }
  }
  // Both answers occur: the sweep crosses the terminator of the box.
  EXPECT_GT(dark, 20);
  EXPECT_GT(lit, 20);
  // The antisolar point at the box's centre: night. The subsolar point inside: day.
  EXPECT_TRUE(layer_in_earth_shadow(g, layer, sun_at(55.0, 177.5, 180.0, 0.0)));
  EXPECT_FALSE(layer_in_earth_shadow(g, layer, sun_at(55.0, 177.5, 0.0, 0.0)));
  // A global grid always has a lit side; an empty layer has nothing to leave out.
  VolumeGrid global = g;
  global.lon_deg = {0.0, 1.0, 360};
  EXPECT_FALSE(layer_in_earth_shadow(global, layer, sun_at(55.0, 177.5, 180.0, 0.0)));
  EXPECT_FALSE(layer_in_earth_shadow(g, CloudLayer{}, sun_at(55.0, 177.5, 180.0, 0.0)));
}

// The lowest sun over the domain bounds every point's sun cosine from below (it sizes llvmpipe's
// dispatches for the longest sun march), stays within the sampling margin of the true lowest, and
// is -1 where the sun can be anywhere (global grid, antisolar point inside).
// The sun cosines over 20 000 random points of the box below and its border cell (lowest, highest).
std::pair<double, double> sampled_sun_cosines(std::mt19937& rng, const glm::dvec3& sun) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  double lowest = 1.0, highest = -1.0;
  for (int n = 0; n < 20000; ++n) {
    const double lon = 169.5 + 16.0 * u(rng), lat = 49.5 + 11.0 * u(rng);
    const double c = glm::dot(geo::sphere_to_ecef({lat, lon, 0.0}, 1.0), sun);
    lowest = std::min(lowest, c), highest = std::max(highest, c);
  }
  return {lowest, highest};
}
VolumeGrid box_across_the_date_line() {
  VolumeGrid g;
  g.lon_deg = {170.0, 0.5, 31};
  g.lat_deg = {50.0, 0.5, 21};
  g.alt_m = {0.0, 500.0, 25};
  return g;
}

TEST(EarthShadow, TheSmallestSunCosineBoundsEveryPointOfTheDomain) {
  const VolumeGrid g = box_across_the_date_line();
  std::mt19937 rng(9);
  for (double azimuth : {0.0, 120.0, 250.0}) {
    for (double theta : {0.0, 20.0, 60.0, 85.0, 95.0}) {
      const glm::dvec3 sun = sun_at(55.0, 177.5, theta, azimuth);
      const double bound = smallest_sun_cosine(g, sun);
      const double lowest = sampled_sun_cosines(rng, sun).first;
      EXPECT_LE(bound, lowest) << "theta " << theta << " azimuth " << azimuth;
      EXPECT_GT(bound, lowest - 0.01) << "theta " << theta << " azimuth " << azimuth;
    }
  }
  EXPECT_EQ(smallest_sun_cosine(g, sun_at(55.0, 177.5, 180.0, 0.0)), -1.0);  // antisolar point at the centre
  VolumeGrid global = g;
  global.lon_deg = {0.0, 1.0, 360};
  EXPECT_EQ(smallest_sun_cosine(global, sun_at(55.0, 177.5, 0.0, 0.0)), -1.0);
}

// The highest sun over the domain bounds every point's sun cosine from above (it tells a render
// that its whole domain is at dawn or dusk), stays within the sampling margin of the true highest,
// and is 1 where the sun can stand overhead (global grid, subsolar point inside).
TEST(EarthShadow, TheLargestSunCosineBoundsEveryPointOfTheDomain) {
  const VolumeGrid g = box_across_the_date_line();
  std::mt19937 rng(11);
  for (double azimuth : {0.0, 120.0, 250.0}) {
    for (double theta : {20.0, 60.0, 85.0, 90.0, 95.0, 170.0}) {
      const glm::dvec3 sun = sun_at(55.0, 177.5, theta, azimuth);
      const double bound = largest_sun_cosine(g, sun);
      const double highest = sampled_sun_cosines(rng, sun).second;
      EXPECT_GE(bound, highest) << "theta " << theta << " azimuth " << azimuth;
      EXPECT_LT(bound, highest + 0.01) << "theta " << theta << " azimuth " << azimuth;
    }
  }
  EXPECT_EQ(largest_sun_cosine(g, sun_at(55.0, 177.5, 0.0, 0.0)), 1.0);  // subsolar point at the centre
  VolumeGrid global = g;
  global.lon_deg = {0.0, 1.0, 360};
  EXPECT_EQ(largest_sun_cosine(global, sun_at(55.0, 177.5, 180.0, 0.0)), 1.0);
}

// The words for where the sun stands: above the horizon (dawn or dusk), below it to 18 degrees
// (twilight), further down (night).
TEST(EarthShadow, TheLowSunIsSaidAsDawnTwilightOrNight) {
  EXPECT_EQ(low_sun_words(0.8), "the sun stands at most 0.8 degrees above the horizon over the data (dawn or dusk there)");
  EXPECT_EQ(low_sun_words(-3.25), "the sun stands below the horizon over all the data, at least 3.2 degrees below it (twilight there)");
  EXPECT_EQ(low_sun_words(-42.8), "the sun stands below the horizon over all the data, at least 42.8 degrees below it (night there)");
}

TEST(EarthShadow, NightLeavesTheReferenceImageAsThePerSampleTestMadeIt) {
  StandardScene sc = standard_scene("cumulus_field", 32, 18);
  sc.sun = sun_just_down(sc);
  sc.march.features.atmosphere = sc.march.features.globe = true;
  sc.march.medium.ambient = 1.0;
  const GridMeanExtinction medium = grid_mean_extinction(sc.grid, sc.data);
  sc.march.features.leave_out_night = false;
  const ReferenceImage per_sample = render_reference(sc.grid, medium, sc.camera, sc.sun, sc.march);
  sc.march.features.leave_out_night = true;
  const ReferenceImage night = render_reference(sc.grid, medium, sc.camera, sc.sun, sc.march);
  EXPECT_FALSE(per_sample.stats.sun_down);
  EXPECT_TRUE(night.stats.sun_down);
  double brightest = 0.0;
  for (std::size_t i = 0; i < night.radiance.size(); ++i) {
    ASSERT_EQ(night.radiance[i], per_sample.radiance[i]) << i;
    ASSERT_EQ(night.transmittance[i], per_sample.transmittance[i]) << i;
    brightest = std::max(brightest, night.radiance[i].z);
  }
  EXPECT_GT(brightest, 0.0) << "the twilight sky should show";
  EXPECT_EQ(night.stats.sun_samples, 0u);
  std::printf("cumulus_field at night: same image; sun samples %llu per sample, %llu left out\n",
              static_cast<unsigned long long>(per_sample.stats.sun_samples),
              static_cast<unsigned long long>(night.stats.sun_samples));
}

}  // namespace
