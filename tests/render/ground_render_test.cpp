// The globe's water as the march kernel renders it (CPU reference, the kernel in double): open sea
// at nadir under an overhead sun outside the glint in the physical range, the glint at the mirror
// point as Cox-Munk's closed form; and the comparison, a sunlit cloud of optical depth 50
// against the sea beside it, with the relief's colours as albedo (before) and with water (now).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "physics/physics.hpp"
#include "reference/raymarcher.hpp"
#include "render/albedo_map.hpp"
#include "render/land_sea_mask.hpp"

namespace {
using namespace cv;
constexpr double kPi = 3.14159265358979323846;
namespace p64 = physics::f64;

bool have_data() {
  return std::filesystem::exists(render::kNaturalEarthRelief) && std::filesystem::exists(std::string(render::kGshhsDir) + "/c/GSHHS_c_L1.shp");
}

// A 2 x 2 degree slab of cloud 1-2 km up over the mid-Pacific (0, -150), extinction sigma (1/m):
// optical depth 1000 sigma; sigma 0 is the clear sea.
struct Slab {
  core::VolumeGrid grid;
  core::TimeStepData data;
  explicit Slab(float sigma) {
    grid.lon_deg = {-153.0, 0.05, 121};
    grid.lat_deg = {-3.0, 0.05, 121};
    grid.alt_m = {500.0, 100.0, 21};
    data[core::Field::ExtinctionLiquid].assign(grid.points(), 0.0f);
    for (int k = 0; k < grid.alt_m.count; ++k)
      for (int j = 0; j < grid.lat_deg.count; ++j)
        for (int i = 0; i < grid.lon_deg.count; ++i) {
          const double z = grid.alt_m.at(k);
          if (std::abs(grid.lon_deg.at(i) + 150.0) <= 1.0 && std::abs(grid.lat_deg.at(j)) <= 1.0 && z >= 1000.0 && z <= 2000.0)
            data[core::Field::ExtinctionLiquid][grid.index(i, j, k)] = sigma;
        }
  }
};

core::Camera nadir_over(double lat, double lon, double alt_m, double fov_deg, int w, int h) {
  core::Camera c;
  c.lat_deg = lat, c.lon_deg = lon, c.alt_m = alt_m, c.heading_deg = 90.0, c.pitch_deg = -90.0, c.fov_deg = fov_deg;
  c.width = w, c.height = h;
  return c;
}

core::Sun sun_over(double lat, double lon) {
  core::Sun s;
  s.subsolar_lat_deg = lat;
  s.subsolar_lon_deg = lon;
  s.irradiance = glm::dvec3(1.0);
  return s;
}

core::MarchSettings globe_settings(bool atmosphere) {
  core::MarchSettings s;
  s.quality.view_step_m = 50.0;
  s.quality.sun_steps = 16;
  s.quality.octaves = 4;
  s.features.atmosphere = atmosphere;
  s.features.globe = true;
  s.medium.ambient = atmosphere ? 1.0 : 0.0;
  s.medium.ground_texture = render::kNaturalEarthRelief;
  return s;
}

TEST(GroundRender, OpenSeaAtNadirUnderAnOverheadSunStaysInThePhysicalRange) {
  if (!have_data()) GTEST_SKIP() << "python-cartopy-data is not installed (scripts/setup installs it)";
  const core::AlbedoMap map = render::load_albedo_map(render::kNaturalEarthRelief);
  const Slab clear(0.0f);
  const double mss = p64::cox_munk_mss(core::MarchSettings{}.medium.ocean_wind_m_s);
  // Without air, so the pixel is the ground's own light: pi L / (E mu_s) is its reflectance factor.
  // The sun over (0, -150); a camera 2000 km up at nadir there sees the glint at its centre, and,
  // 40 degrees off nadir (looking 40 degrees from straight down), sea outside it.
  const core::MarchSettings s = globe_settings(false);
  const core::Sun sun = sun_over(0.0, -150.0);
  for (double off_deg : {0.0, 40.0}) {
    core::Camera cam = nadir_over(0.0, -150.0, 2.0e6, 1.0, 3, 3);
    cam.pitch_deg = -90.0 + off_deg;
    const auto img = core::render_reference(clear.grid, clear.data, cam, sun, s, nullptr, &map);
    const glm::dvec3 l = img.radiance[4];
    // Where that pixel's ray meets the ground: the view and sun angles there.
    const double tv = std::asin(std::min(1.0, (6371000.0 + cam.alt_m) / 6371000.0 * std::sin(off_deg * kPi / 180.0)));
    const double central = tv - off_deg * kPi / 180.0;  // the ground point's angle from the sub-camera point
    const double mu_s = std::cos(central), mu_v = std::cos(tv), nu = std::cos(tv - central);
    const glm::dvec3 r = l * kPi / mu_s;
    const glm::dvec3 expect = p64::water_radiance(p64::CV_WATER_BODY, mu_s, mu_v, nu, mss, glm::dvec3(1.0), glm::dvec3(0.0)) * kPi / mu_s;
    std::printf("%2.0f deg off nadir (view %.1f deg, sun %.1f deg at the ground): reflectance %.4f %.4f %.4f (water_radiance %.4f %.4f %.4f)\n",
                off_deg, tv * 180.0 / kPi, central * 180.0 / kPi, r.x, r.y, r.z, expect.x, expect.y, expect.z);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(r[k], expect[k], 2e-3 * expect[k] + 1e-6);
    if (off_deg == 0.0) {
      // In the glint: Cox & Munk's peak, Fresnel 0.0204 over 4 mss (0.13 at 7 m/s), plus the body.
      EXPECT_NEAR(r.y, p64::fresnel_water(1.0) / (4.0 * mss) + p64::CV_WATER_BODY.y, 2e-3);
    } else {
      // Outside the glint: open water's few per cent at most, blue brightest.
      for (int k = 0; k < 3; ++k) {
        EXPECT_GT(r[k], 0.0);
        EXPECT_LT(r[k], 0.07);
      }
      EXPECT_GT(r.z, r.x);
    }
  }
}

// The measurement: at nadir under an overhead sun, the radiance of a sunlit cloud of optical
// depth 50 against the sea beside it, the way a user sees it (air, sky light, the default quality's
// 4 octaves), with the relief's colours as albedo ("map", before) and with water ("physical").
// The sea is sampled at view angles of 15, 30 and 45 degrees from nadir: in the glint's flank and
// outside it.
TEST(GroundRender, CloudOfOpticalDepth50AgainstTheSeaBesideIt) {
  if (!have_data()) GTEST_SKIP() << "python-cartopy-data is not installed (scripts/setup installs it)";
  const Slab slab(0.05f);
  // 600 km up over the slab's centre, a row across it eastward (heading 90: columns run east).
  const int w = 181;
  const core::Camera cam = nadir_over(0.0, -150.0, 6.0e5, 100.0, w, 1);
  const core::Sun sun = sun_over(0.0, -150.0);
  const double tan_half = std::tan(50.0 * kPi / 180.0);
  auto column_at = [&](double view_deg) {
    return static_cast<int>(std::lround((std::tan(view_deg * kPi / 180.0) / tan_half + 1.0) * 0.5 * w - 0.5));
  };
  const int cloud = column_at(0.0);
  double ratio_now_45 = 0.0, ratio_before_15 = 0.0, ratio_two_stream_15 = 0.0, cloud_two_stream = 0.0;
  // The map's colours and the octave sum (before), water with the octave sum, water with the
  // two-stream source (the product's default now).
  for (int variant = 0; variant < 3; ++variant) {
    const bool map_colours = variant == 0;
    core::MarchSettings s = globe_settings(true);
    s.medium.ground_map_colours = map_colours;
    s.medium.ms_two_stream = variant == 2;
    const core::AlbedoMap map = render::load_albedo_map(render::kNaturalEarthRelief, map_colours);
    const auto img = core::render_reference(slab.grid, slab.data, cam, sun, s, nullptr, &map);
    // Luminance (Rec. 709 weights of the linear radiance, per unit irradiance).
    auto lum = [](glm::dvec3 l) { return 0.2126 * l.x + 0.7152 * l.y + 0.0722 * l.z; };
    const glm::dvec3 c_rgb = img.radiance[static_cast<std::size_t>(cloud)];
    const double lc = lum(c_rgb);
    if (variant == 2) cloud_two_stream = lc;
    std::printf("%-22s cloud (tau 50, nadir): rgb %.4f %.4f %.4f, luminance %.4f\n",
                variant == 0 ? "map, octaves" : variant == 1 ? "physical, octaves" : "physical, two-stream", c_rgb.x, c_rgb.y,
                c_rgb.z, lc);
    for (double view : {15.0, 30.0, 45.0}) {
      const int c = column_at(view);
      ASSERT_GT(img.cloud_depth_m[static_cast<std::size_t>(c)], 1e38);  // the sea, no cloud in front
      const glm::dvec3 s_rgb = img.radiance[static_cast<std::size_t>(c)];
      const double ls = lum(s_rgb);
      std::printf("  sea %2.0f deg from nadir: rgb %.4f %.4f %.4f, luminance %.4f; cloud/sea: luminance %.2f, rgb %.2f %.2f %.2f\n", view,
                  s_rgb.x, s_rgb.y, s_rgb.z, ls, lc / ls, c_rgb.x / s_rgb.x, c_rgb.y / s_rgb.y, c_rgb.z / s_rgb.z);
      if (map_colours && view == 15.0) ratio_before_15 = lc / ls;
      if (variant == 1 && view == 45.0) ratio_now_45 = lc / ls;
      if (variant == 2 && view == 15.0) ratio_two_stream_15 = lc / ls;
    }
    EXPECT_LT(img.cloud_depth_m[static_cast<std::size_t>(cloud)], 1e6);  // the cloud
  }
  // Before, the sea outshone the cloud (the issue measured 0.30); outside the glint it is now the
  // dark background it is.
  EXPECT_LT(ratio_before_15, 1.0);
  EXPECT_GT(ratio_now_45, 1.0);
  // With the two-stream source the cloud reflects what a thick cloud does: a nadir reflectance factor
  // pi L / E (overhead sun, through the air) near the 0.75-0.85 a plane-parallel water cloud of
  // optical depth 50 reflects, where the octave sum gave 0.18; so it outshines even the glint's flank.
  std::printf("two-stream cloud: nadir reflectance factor %.3f; cloud/sea at 15 deg %.2f\n", kPi * cloud_two_stream,
              ratio_two_stream_15);
  EXPECT_GT(kPi * cloud_two_stream, 0.6);
  EXPECT_LT(kPi * cloud_two_stream, 0.95);
  EXPECT_GT(ratio_two_stream_15, 4.0);
}

}  // namespace
