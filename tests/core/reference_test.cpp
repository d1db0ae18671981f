// The CPU reference raymarcher against closed forms: a homogeneous layer seen from above.
#include <gtest/gtest.h>

#include <cmath>

#include "physics/physics.hpp"
#include "reference/raymarcher.hpp"

namespace {
using namespace cv::core;

// A homogeneous liquid layer from 1 to 2 km over a 2 x 2 degree box around (0, 0).
struct Layer {
  VolumeGrid grid;
  TimeStepData data;
  explicit Layer(double sigma_per_m) {
    grid.lon_deg = {-1.0, 0.5, 5};
    grid.lat_deg = {-1.0, 0.5, 5};
    grid.alt_m = {1000.0, 100.0, 11};
    data[Field::ExtinctionLiquid].assign(grid.points(), static_cast<float>(sigma_per_m));
  }
};

// One pixel looking straight down from 10 km over (0, 0).
Camera nadir() {
  Camera c;
  c.alt_m = 10000.0;
  c.pitch_deg = -90.0;
  c.fov_deg = 1e-3;
  c.width = c.height = 1;
  return c;
}

TEST(Reference, TransmittanceOfAHomogeneousLayerIsExact) {
  const double sigma = 1e-3;
  Layer l(sigma);
  MarchSettings s;
  const auto img = render_reference(l.grid, l.data, nadir(), Sun{}, s);
  // The closed form with the extinction the volume holds (float32).
  const double stored = static_cast<double>(static_cast<float>(sigma));
  EXPECT_NEAR(img.transmittance[0], std::exp(-stored * 1000.0), 1e-12);
}

TEST(Reference, SingleScatteringMatchesTheClosedFormAndConvergesWithTheStep) {
  // Sun at the zenith, camera at the nadir: light scatters straight back (mu = -1). A point at
  // depth s sees the sun through sigma s and the camera through sigma s, so
  //   L = E p(-1) sigma int_0^H exp(-2 sigma s) ds = E p(-1) (1 - exp(-2 sigma H)) / 2.
  const double sigma = 2e-3, h = 1000.0;
  Layer l(sigma);
  const double p_back = cv::physics::f64::phase_mie(-1.0, cv::physics::f64::mie_params(20.0));
  const double expected = p_back * (1.0 - std::exp(-2.0 * sigma * h)) / 2.0;
  double previous = 1.0;
  for (double step : {100.0, 50.0, 25.0}) {
    MarchSettings s;
    s.quality.view_step_m = step;
    s.quality.sun_steps = 64;
    const auto img = render_reference(l.grid, l.data, nadir(), Sun{}, s);
    const double err = std::abs(img.radiance[0].x - expected) / expected;
    std::printf("view step %5.1f m: relative error %.3g\n", step, err);
    EXPECT_LT(err, 5e-3);
    EXPECT_LT(err, previous / 3.0);  // second order in the step
    previous = err;
  }
}

TEST(Reference, TheEarthsShadowAndAnEmptySky) {
  Layer l(1e-3);
  Sun night;
  night.subsolar_lon_deg = 180.0;  // the sun on the far side of the Earth
  const auto dark = render_reference(l.grid, l.data, nadir(), night, MarchSettings{});
  EXPECT_EQ(dark.radiance[0].x, 0.0);
  EXPECT_NEAR(dark.transmittance[0], std::exp(-static_cast<double>(1e-3f) * 1000.0), 1e-12);
  // No cloud at all: nothing scattered, nothing absorbed, never a NaN, across a whole image.
  Layer empty(0.0);
  Camera wide = nadir();
  wide.pitch_deg = -30.0;
  wide.fov_deg = 90.0;
  wide.width = 16;
  wide.height = 9;
  const auto img = render_reference(empty.grid, empty.data, wide, Sun{}, MarchSettings{});
  for (std::size_t i = 0; i < img.radiance.size(); ++i) {
    ASSERT_EQ(img.radiance[i].x, 0.0);
    ASSERT_EQ(img.transmittance[i], 1.0);
  }
}

TEST(Reference, OctavesBrightenAThickCloudAndNothingIsNaN) {
  Layer l(0.05);  // optical depth 50
  MarchSettings one, eight;
  eight.quality.octaves = 8;
  const auto a = render_reference(l.grid, l.data, nadir(), Sun{}, one);
  const auto b = render_reference(l.grid, l.data, nadir(), Sun{}, eight);
  ASSERT_TRUE(std::isfinite(a.radiance[0].x) && std::isfinite(b.radiance[0].x));
  EXPECT_GT(b.radiance[0].x, a.radiance[0].x);
  EXPECT_LT(a.transmittance[0], 1e-6 + 1e-12);
}

}  // namespace

namespace {

TEST(Reference, LookingStraightDownTheHeadingStillTurnsTheImage) {
  // Heading 90 (east): "right" is south, whether the camera looks down exactly or almost.
  for (double pitch : {-90.0, -89.999}) {
    Camera c;
    c.heading_deg = 90.0;
    c.pitch_deg = pitch;
    const CameraFrame f = camera_frame(c);
    EXPECT_NEAR(f.right.z, -1.0, 1e-4) << pitch;  // at (0, 0) north is +z
  }
}

}  // namespace
