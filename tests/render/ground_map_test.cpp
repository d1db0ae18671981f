// The globe's ground as render::load_albedo_map makes it: the GSHHS land-sea mask at known points
// (open sea, desert, lakes, ice sheets), the map's land colours as albedos of their surface types,
// the rasteriser's coverage fractions and nesting, the fallback without GSHHS, the "map" model, and
// a bad image as one clear error.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>

#include "render/albedo_map.hpp"
#include "render/land_sea_mask.hpp"

namespace {
using namespace cv;

bool have_relief() { return std::filesystem::exists(render::kNaturalEarthRelief); }
bool have_gshhs() { return std::filesystem::exists(std::string(render::kGshhsDir) + "/c/GSHHS_c_L1.shp"); }

// The texel of (lat, lon) in degrees.
std::size_t texel(const core::AlbedoMap& m, double lat, double lon) {
  const int x = std::min(m.width - 1, static_cast<int>((lon + 180.0) / 360.0 * m.width));
  const int y = std::min(m.height - 1, static_cast<int>((90.0 - lat) / 180.0 * m.height));
  return static_cast<std::size_t>(y) * m.width + x;
}
float water_at(const core::AlbedoMap& m, double lat, double lon) { return m.rgba[4 * texel(m, lat, lon) + 3]; }
glm::vec3 land_at(const core::AlbedoMap& m, double lat, double lon) {
  const std::size_t i = texel(m, lat, lon);
  return {m.rgba[4 * i], m.rgba[4 * i + 1], m.rgba[4 * i + 2]};
}

struct Place {
  const char* name;
  double lat, lon;
  bool water;
};

TEST(GroundMap, TheLandSeaMaskIsRightAtKnownPlaces) {
  if (!have_relief() || !have_gshhs()) GTEST_SKIP() << "python-cartopy-data is not installed (scripts/setup installs it)";
  const core::AlbedoMap m = render::load_albedo_map(render::kNaturalEarthRelief);
  const Place places[] = {
      {"mid-Pacific", 0.0, -150.0, true},       {"South Atlantic", -30.0, -15.0, true}, {"Southern Ocean", -60.0, 90.0, true},
      {"Arctic Ocean", 85.0, 0.0, true},        {"Caspian Sea", 42.0, 50.5, true},      {"Lake Victoria", -1.0, 33.0, true},
      {"Lake Superior", 47.6, -87.5, true},     {"Sahara", 23.0, 10.0, false},          {"Amazonia", -8.0, -60.0, false},
      {"Siberia", 62.0, 100.0, false},          {"Greenland interior", 72.0, -40.0, false},
      {"East Antarctica", -80.0, 90.0, false},  {"Antarctica at 0 E", -80.0, 0.5, false}, {"Australia", -25.0, 133.0, false},
  };
  for (const Place& p : places) {
    const float w = water_at(m, p.lat, p.lon);
    std::printf("%-20s (%6.1f, %7.1f): water fraction %.3f\n", p.name, p.lat, p.lon, w);
    if (p.water) {
      EXPECT_GT(w, 0.99f) << p.name;
    } else {
      EXPECT_LT(w, 0.01f) << p.name;
    }
  }
  // The map draws neither Lake Victoria nor Superior: their water comes from GSHHS (level 2).
  EXPECT_EQ(render::nearest_map_surface(glm::vec3(225, 228, 190)), render::MapSurface::Grass);
}

TEST(GroundMap, LandColoursBecomeTheAlbedosOfTheirSurfaceTypes) {
  if (!have_relief()) GTEST_SKIP() << "python-cartopy-data is not installed";
  const core::AlbedoMap m = render::load_albedo_map(render::kNaturalEarthRelief);
  const glm::vec3 sahara = land_at(m, 23.0, 10.0), amazon = land_at(m, -8.0, -60.0), greenland = land_at(m, 72.0, -40.0),
                  antarctica = land_at(m, -80.0, 90.0), plains = land_at(m, 41.0, -93.0);
  auto show = [](const char* n, glm::vec3 a) { std::printf("%-20s albedo %.3f %.3f %.3f\n", n, a.x, a.y, a.z); };
  show("Sahara", sahara), show("Amazonia", amazon), show("US corn belt", plains), show("Greenland", greenland),
      show("East Antarctica", antarctica);
  // Sand desert: 0.2-0.5 in the visible, reddest (MODIS over the Sahara; broadband 0.3-0.45).
  EXPECT_GT(sahara.x, 0.3f);
  EXPECT_LT(sahara.x, 0.5f);
  EXPECT_GT(sahara.z, 0.15f);
  EXPECT_GT(sahara.x, sahara.z);
  // Forest: 0.02-0.08 in the visible, green the brightest.
  EXPECT_LT(amazon.x, 0.05f);
  EXPECT_GT(amazon.y, amazon.x);
  EXPECT_LT(amazon.y, 0.08f);
  // Crops and grass: below 0.15.
  EXPECT_LT(plains.y, 0.15f);
  // Dry snow on the ice sheets: 0.8-0.97 (0.96-0.98 in the visible at the South Pole).
  for (glm::vec3 a : {greenland, antarctica}) {
    EXPECT_GT(a.y, 0.8f);
    EXPECT_LE(a.y, 0.97f);
  }
  // The Tibetan plateau, painted the same grey-blue as snow-covered Arctic islands: its alpine
  // steppe and bare ground (the tundra and rock type, 0.15-0.20 broadband), not a blend with snow.
  // It was 0.33-0.47 green before the latitude bound on snow (snow_lightness_scale).
  for (const auto& [lat, lon] : {std::pair{33.0, 88.0}, std::pair{31.0, 85.0}, std::pair{35.0, 92.0}, std::pair{30.0, 88.0}}) {
    const glm::vec3 a = land_at(m, lat, lon);
    std::printf("Tibet (%.0f N, %.0f E) albedo %.3f %.3f %.3f\n", lat, lon, a.x, a.y, a.z);
    EXPECT_GT(a.y, 0.07f) << lat << " " << lon;
    EXPECT_LT(a.y, 0.25f) << lat << " " << lon;
  }
  // Every texel's land albedo stays in the span of the types' albedos, with the relief's shading.
  float lo = 1.0f, hi = 0.0f;
  for (std::size_t i = 0; i < m.rgba.size(); i += 4) {
    for (int k = 0; k < 3; ++k) lo = std::min(lo, m.rgba[i + k]), hi = std::max(hi, m.rgba[i + k]);
  }
  std::printf("land albedo over the map: %.3f .. %.3f\n", lo, hi);
  EXPECT_GE(lo, 0.75f * 0.025f);
  EXPECT_LE(hi, 0.97f);
}

TEST(GroundMap, GreyHighGroundIsSnowOnlyTowardThePoles) {
  // The relief's grey of high ground (the Tibetan plateau's texel at 33 N, 88 E; Svalbard's and
  // Ellesmere's are within a few levels of it): tundra and rock at low latitudes, a blend with snow
  // poleward of 65 degrees as before, between the two from 55 to 65.
  const glm::vec3 grey(213, 214, 215);
  const float at_33 = render::land_albedo_of_map_colour(grey, 33.0).y, at_60 = render::land_albedo_of_map_colour(grey, -60.0).y,
              at_80 = render::land_albedo_of_map_colour(grey, 80.0).y;
  std::printf("grey high ground: green albedo %.3f at 33 N, %.3f at 60 S, %.3f at 80 N\n", at_33, at_60, at_80);
  const float rock = render::map_surface(render::MapSurface::Tundra).albedo.y;
  EXPECT_LT(at_33, 1.5f * rock);
  EXPECT_GT(at_80, 0.3f);
  EXPECT_GT(at_60, at_33);
  EXPECT_LT(at_60, at_80);
  EXPECT_EQ(render::snow_lightness_scale(std::nan("")), render::snow_lightness_scale(0.0));
  // The ice sheets' own colour is snow at any latitude (the bound is on colours darker than it).
  for (double lat : {0.0, 45.0, 72.0, -80.0}) {
    EXPECT_GT(render::land_albedo_of_map_colour(render::map_surface(render::MapSurface::Snow).map_srgb, lat).y, 0.85f) << lat;
  }
}

TEST(GroundMap, TheRasteriserCoversFractionsAndNestsLakesAndIslands) {
  // 10-degree texels; land lon 0..20, lat 0..20 with a lake lon 10..20, lat 0..10 holding an island
  // lon 10..15, lat 0..10; and a strip lon 30..35 (half a texel); and land on both sides of 180.
  auto square = [](int level, double w, double e, double s, double n) {
    render::ShorePolygon p;
    p.level = level;
    p.rings.push_back({w, s, e, s, e, n, w, n});
    return p;
  };
  const std::vector<render::ShorePolygon> polys = {square(1, 0, 20, 0, 20),   square(2, 10, 20, 0, 10), square(3, 10, 15, 0, 10),
                                                   square(1, 30, 35, 0, 10),  square(1, 170, 180, 40, 50),
                                                   square(1, -180, -170, 40, 50)};
  const render::WaterFraction f = render::rasterise_water(polys, 36, 18, 4);
  auto at = [&](double lat, double lon) {
    return f.water[static_cast<std::size_t>((90.0 - lat) / 10.0) * 36 + static_cast<std::size_t>((lon + 180.0) / 10.0)];
  };
  EXPECT_EQ(at(15, 5), 0.0f);     // land
  EXPECT_EQ(at(5, 5), 0.0f);      // land
  EXPECT_EQ(at(5, 15), 0.5f);     // half lake (water), half island in it (land)
  EXPECT_EQ(at(5, 35), 0.5f);     // the strip covers half the texel
  EXPECT_EQ(at(-5, 5), 1.0f);     // sea
  EXPECT_EQ(at(45, 175), 0.0f);   // east of ...
  EXPECT_EQ(at(45, -175), 0.0f);  // ... and west of the date line
  EXPECT_EQ(at(45, -165), 1.0f);
  EXPECT_EQ(render::gshhs_resolution_for(720), 'c');
  EXPECT_EQ(render::gshhs_resolution_for(2048), 'l');
  EXPECT_EQ(render::gshhs_resolution_for(21600), 'h');
}

TEST(GroundMap, WithoutGshhsTheMapsSeaColourIsWaterAndItIsSaidOnce) {
  if (!have_relief()) GTEST_SKIP() << "python-cartopy-data is not installed";
  testing::internal::CaptureStderr();
  const core::AlbedoMap m = render::load_albedo_map(render::kNaturalEarthRelief, false, "/nonexistent/gshhs");
  const core::AlbedoMap again = render::load_albedo_map(render::kNaturalEarthRelief, false, "/nonexistent/gshhs");
  const std::string said = testing::internal::GetCapturedStderr();
  std::printf("stderr: %s", said.c_str());
  EXPECT_NE(said.find("no GSHHS shorelines under /nonexistent/gshhs"), std::string::npos);
  EXPECT_EQ(said.find('\n'), said.size() - 1) << "said once, on one line";
  EXPECT_EQ(water_at(m, 0.0, -150.0), 1.0f);
  EXPECT_EQ(water_at(m, 23.0, 10.0), 0.0f);
  EXPECT_EQ(water_at(m, -1.0, 33.0), 0.0f);  // the map draws no Lake Victoria
  EXPECT_EQ(m.rgba, again.rgba);
}

TEST(GroundMap, TheMapModelTakesTheImagesColoursAsAlbedoWithoutWater) {
  if (!have_relief()) GTEST_SKIP() << "python-cartopy-data is not installed";
  const core::AlbedoMap m = render::load_albedo_map(render::kNaturalEarthRelief, true);
  double water = 0.0;
  for (std::size_t i = 3; i < m.rgba.size(); i += 4) water += m.rgba[i];
  EXPECT_EQ(water, 0.0);
  // The mid-Pacific's light blue (115, 164, 198) decoded to linear, as before.
  const glm::vec3 sea = land_at(m, 0.0, -150.0);
  EXPECT_NEAR(sea.z, std::pow((198.0 / 255.0 + 0.055) / 1.055, 2.4), 1e-6);
  EXPECT_GT(sea.y, 0.3f);
}

TEST(GroundMap, AGroundTextureThatIsNoImageIsOneClearError) {
  const std::string path = (std::filesystem::temp_directory_path() / ("cv_not_an_image_" + std::to_string(::getpid()) + ".png")).string();
  std::ofstream(path) << "not an image\n";
  try {
    render::load_albedo_map(path);
    ADD_FAILURE() << "no error";
  } catch (const render::GroundImageError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind(path + ": cannot read the ground image", 0), 0u) << what;
    EXPECT_NE(what.find("expected an equirectangular PNG or JPEG"), std::string::npos) << what;
  }
  std::filesystem::remove(path);
}

}  // namespace
