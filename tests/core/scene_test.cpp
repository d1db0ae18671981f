// Scene files (round trip, and each class of bad input named in one line), quality presets,
// automatic framing and the scene's sun.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include <glm/glm.hpp>

#include "geo/geodesy.hpp"
#include "geo/solar.hpp"
#include "scene/framing.hpp"
#include "scene/quality.hpp"
#include "scene/scene_json.hpp"
#include "support/march_values.hpp"

namespace {
using namespace cv::core;
namespace fs = std::filesystem;

// Every field set to something other than its default, with values that are not short decimals
// so that a lossy number format would show.
Scene full_scene() {
  Scene s;
  s.data.path = "/data/run 7/cyclone.nc";
  s.data.region_deg = std::array<double, 4>{170.25, -170.125, -12.5, 33.0 / 7.0};
  s.data.levels_hpa = std::array<double, 2>{150.0, 987.654321};
  s.data.horizontal_stride = 3;
  s.data.dz_m = 250.0;
  s.data.diagnose_cloud = true;
  s.data.rh_critical = 0.85;
  s.time_step = 4;
  s.time.valid_utc = "2024-01-15T04:30:00Z";
  s.time.interpolation = TimeInterpolation::Linear;
  Camera c;
  c.lat_deg = -33.123456789012345, c.lon_deg = 151.2, c.alt_m = 3.6e6 / 3.0;
  c.heading_deg = 12.5, c.pitch_deg = -41.0 / 3.0, c.fov_deg = 47.0;
  s.camera = c;
  s.width = 48, s.height = 27;
  s.camera->width = 48, s.camera->height = 27;
  s.sun.mode = SunMode::DateTime;
  s.sun.datetime_utc = "2024-01-15T03:00:00Z";
  s.sun.subsolar_lat_deg = -21.1, s.sun.subsolar_lon_deg = 134.7, s.sun.irradiance = 1.7;
  s.render.quality = "custom";
  // Every march row off the value a file without it reads (a preset's or the scene's default), so
  // a writer that drops a row, or a reader that skips one, fails the round trip.
  Scene defaults;
  apply_quality("default", defaults.render);
  cv::test::set_every_row_off(s.render.march, defaults.render.march);
  s.render.accumulate = 8, s.render.resolution_scale = 0.5, s.render.exposure = 6.25, s.render.auto_exposure = false;
  s.render.budget_ms = 40.0;
  // Every overlay type, every parameter off its default.
  s.overlays = {default_overlay("coastlines"), default_overlay("graticule"), default_overlay("isosurface")};
  s.overlays[0].colors["color"] = {0.25, 0.5, 0.75};
  s.overlays[0].texts["resolution"] = "l";
  s.overlays[0].numbers["line_width_px"] = 2.0;
  s.overlays[1].numbers["step_deg"] = 15.0;
  s.overlays[2].texts["field"] = "temperature";
  s.overlays[2].numbers["value"] = 273.15;
  return s;
}

void expect_equal(const Scene& a, const Scene& b) {
  EXPECT_EQ(a.data.path, b.data.path);
  EXPECT_EQ(a.data.region_deg, b.data.region_deg);
  EXPECT_EQ(a.data.levels_hpa, b.data.levels_hpa);
  EXPECT_EQ(a.data.horizontal_stride, b.data.horizontal_stride);
  EXPECT_EQ(a.data.dz_m, b.data.dz_m);
  EXPECT_EQ(a.data.diagnose_cloud, b.data.diagnose_cloud);
  EXPECT_EQ(a.data.rh_critical, b.data.rh_critical);
  EXPECT_EQ(a.time_step, b.time_step);
  EXPECT_EQ(a.time.valid_utc, b.time.valid_utc);
  EXPECT_EQ(a.time.interpolation, b.time.interpolation);
  ASSERT_EQ(a.camera.has_value(), b.camera.has_value());
  if (a.camera) {
    EXPECT_EQ(a.camera->lat_deg, b.camera->lat_deg);
    EXPECT_EQ(a.camera->lon_deg, b.camera->lon_deg);
    EXPECT_EQ(a.camera->alt_m, b.camera->alt_m);
    EXPECT_EQ(a.camera->heading_deg, b.camera->heading_deg);
    EXPECT_EQ(a.camera->pitch_deg, b.camera->pitch_deg);
    EXPECT_EQ(a.camera->fov_deg, b.camera->fov_deg);
    EXPECT_EQ(a.camera->width, b.camera->width);
    EXPECT_EQ(a.camera->height, b.camera->height);
  }
  EXPECT_EQ(a.width, b.width);
  EXPECT_EQ(a.height, b.height);
  EXPECT_EQ(a.sun.mode, b.sun.mode);
  EXPECT_EQ(a.sun.datetime_utc, b.sun.datetime_utc);
  EXPECT_EQ(a.sun.subsolar_lat_deg, b.sun.subsolar_lat_deg);
  EXPECT_EQ(a.sun.subsolar_lon_deg, b.sun.subsolar_lon_deg);
  EXPECT_EQ(a.sun.irradiance, b.sun.irradiance);
  EXPECT_EQ(a.render.quality, b.render.quality);
  // The march member by member through the table: every row, named in the message.
  for_each_march_setting_pair(a.render.march, b.render.march, [](const SettingRow& row, const auto& x, const auto& y) {
    EXPECT_TRUE(x == y) << "render.march." << row.key << " differs after the round trip";
  });
  EXPECT_EQ(a.render.accumulate, b.render.accumulate);
  EXPECT_EQ(a.render.resolution_scale, b.render.resolution_scale);
  EXPECT_EQ(a.render.exposure, b.render.exposure);
  EXPECT_EQ(a.render.auto_exposure, b.render.auto_exposure);
  EXPECT_EQ(a.render.budget_ms, b.render.budget_ms);
  EXPECT_EQ(a.overlays, b.overlays);
}

TEST(SceneJson, FullyPopulatedSceneRoundTripsExactly) {
  const Scene s = full_scene();
  // Every march row is off what a file without it reads: otherwise a dropped row would pass.
  Scene defaults;
  apply_quality("default", defaults.render);
  for_each_march_setting_pair(s.render.march, defaults.render.march, [](const SettingRow& row, const auto& x, const auto& y) {
    EXPECT_FALSE(x == y) << "render.march." << row.key << " is at its default in full_scene()";
  });
  const std::string text = scene_to_json(s);
  expect_equal(scene_from_json(text), s);
  // And through a file: save, load (an absolute data path stays as it is; a relative ground
  // texture is taken from the scene file's folder, as the data path is).
  const fs::path file = fs::temp_directory_path() / ("cv_scene_roundtrip_" + std::to_string(::getpid()) + ".json");
  save_scene(s, file.string());
  Scene expected = s;
  if (fs::path(s.render.march.medium.ground_texture).is_relative()) {
    expected.render.march.medium.ground_texture = (file.parent_path() / s.render.march.medium.ground_texture).lexically_normal().string();
  }
  expect_equal(load_scene(file.string()), expected);
  fs::remove(file);
}

TEST(SceneJson, AbsentCameraMeansAutomaticAndSurvivesTheRoundTrip) {
  Scene s = full_scene();
  s.camera.reset();
  const Scene back = scene_from_json(scene_to_json(s));
  EXPECT_FALSE(back.camera.has_value());
  EXPECT_FALSE(scene_from_json(R"({"version": 1, "camera": null})").camera.has_value());
}

TEST(SceneJson, MissingKeysTakeTheDefaultsAndTheDefaultPreset) {
  const Scene s = scene_from_json(R"({"version": 1, "data": {"path": "a.nc"}})");
  EXPECT_EQ(s.data.path, "a.nc");
  EXPECT_EQ(s.width, 960);
  EXPECT_EQ(s.sun.mode, SunMode::ValidTime);
  EXPECT_EQ(s.render.quality, "default");
  EXPECT_EQ(s.render.march.quality.sun_steps, 16);
  EXPECT_EQ(s.render.march.quality.octaves, 4);
  EXPECT_EQ(s.render.march.quality.view_step_m, 0.0);  // from the grid
  // A preset named in the file sets the march, and march keys in the file override it.
  const Scene h = scene_from_json(R"({"version": 1, "render": {"quality": "high", "march": {"octaves": 2}}})");
  EXPECT_EQ(h.render.march.quality.sun_steps, 32);
  EXPECT_EQ(h.render.march.quality.octaves, 2);
  EXPECT_EQ(h.render.accumulate, 4);
}

TEST(SceneJson, RelativeDataPathIsTakenFromTheSceneFilesFolder) {
  const fs::path dir = fs::temp_directory_path() / ("cv_scene_rel_" + std::to_string(::getpid())) / "scenes";
  fs::create_directories(dir);
  std::ofstream(dir / "s.json") << R"({"version": 1, "data": {"path": "../data/c.nc"}})";
  EXPECT_EQ(load_scene((dir / "s.json").string()).data.path, (dir.parent_path() / "data" / "c.nc").string());
  fs::remove_all(dir.parent_path());
}

// The one-line message for bad input, exactly.
std::string error_of(const std::string& text) {
  try {
    scene_from_json(text, "scene.json");
  } catch (const SceneError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(SceneJson, BadTypeNamesTheKeyPathWhatWasFoundAndWhatWasExpected) {
  EXPECT_EQ(error_of(R"({"version": 1, "render": {"march": {"sun_steps": "abc"}}})"),
            "scene.json: render.march.sun_steps: found \"abc\", expected an integer 1..1024");
  EXPECT_EQ(error_of(R"({"version": 1, "camera": [1, 2]})"), "scene.json: camera: found [1,2], expected an object { ... }");
  EXPECT_EQ(error_of(R"({"version": 1, "data": {"path": 7}})"), "scene.json: data.path: found 7, expected a string");
  EXPECT_EQ(error_of(R"({"version": 1, "render": {"march": {"octaves": 2.5}}})"),
            "scene.json: render.march.octaves: found 2.5, expected an integer 1..16");
}

TEST(SceneJson, OutOfRangeValuesAreRefused) {
  EXPECT_EQ(error_of(R"({"version": 1, "camera": {"fov_deg": 180}})"),
            "scene.json: camera.fov_deg: found 180, expected a horizontal field of view in degrees, more than 0 and less "
            "than 180");
  EXPECT_EQ(error_of(R"({"version": 1, "width": 0})"), "scene.json: width: found 0, expected an integer 1..16384");
  EXPECT_EQ(error_of(R"({"version": 1, "data": {"region_deg": [0, 10, 20, -20]}})"),
            "scene.json: data.region_deg: found [0.0,10.0,20.0,-20.0], expected south <= north within -90..90");
  EXPECT_EQ(error_of(R"({"version": 1, "sun": {"mode": "datetime", "datetime_utc": "2024-02-30T00:00:00Z"}})"),
            "scene.json: sun.datetime_utc: found \"2024-02-30T00:00:00Z\", expected a UTC date-time YYYY-MM-DDThh:mm:ssZ");
  EXPECT_EQ(error_of(R"({"version": 1, "render": {"quality": "ultra"}})"),
            "scene.json: render.quality: found \"ultra\", expected one of low, default, high, custom");
  EXPECT_EQ(error_of(R"({"version": 1, "data": {"diagnose_cloud": true, "rh_critical": 1}})"),
            "scene.json: data.rh_critical: found 1, expected a critical relative humidity 0.5 <= RH < 1");
  EXPECT_EQ(error_of(R"({"version": 1, "render": {"budget_ms": -5}})"),
            "scene.json: render.budget_ms: found -5, expected a frame-time budget in ms 0..1e7 (0: off)");
}

TEST(SceneJson, UnknownKeysAreNamedSoTyposAreCaught) {
  EXPECT_EQ(error_of(R"({"version": 1, "render": {"march": {"sun_step": 8}}})"),
            "scene.json: render.march.sun_step: unknown key, expected one of view_step_m, sun_steps, octaves, multiple_scattering, diffuse_shape, octave_a, "
            "octave_b, octave_c, octave_gate, droplet_diameter_um, liquid_phase, ice_g, frame, blue_noise, anti_alias, noise_amount, noise_scale_m, "
            "cloud_model, detail_amount, detail_scale_m, atmosphere, globe, ambient, sky_steps, atmo_sun_steps, ground_albedo, ground_texture, ground_model, ocean_wind_m_s, layer_bottom_m, layer_top_m, "
            "layer_reference, tint_liquid, tint_ice, hide_liquid, hide_ice, skip_empty, adaptive_steps, "
            "max_step_optical_depth, min_transmittance, leave_out_night, "
            "max_sun_step_optical_depth, max_sun_step_m");
  EXPECT_EQ(error_of(R"({"version": 1, "render": {"march": {"max_sun_step_m": -1}}})"),
            "scene.json: render.march.max_sun_step_m: found -1, expected a sun step length in metres 0..1e7 (0: the grid's "
            "horizontal cell)");
  EXPECT_EQ(error_of(R"({"version": 1, "camra": {}})"),
            "scene.json: camra: unknown key, expected one of version, data, time_step, time, camera, path, width, height, sun, render, "
            "overlays, views");
}

TEST(SceneJson, VersionIsRequiredAndANewerOneIsRefused) {
  EXPECT_EQ(error_of(R"({"version": 2})"),
            "scene.json: version: found 2, expected 1 or lower (the file was written by a newer cloudviewer)");
  EXPECT_EQ(error_of(R"({"width": 48})"), "scene.json: version: found nothing, expected \"version\": 1");
  EXPECT_EQ(error_of(R"({"version": "1"})"), "scene.json: version: found \"1\", expected an integer >= 1");
}

TEST(SceneJson, MalformedJsonAndAMissingFileGiveOneLine) {
  const std::string bad = error_of("{\"version\": 1,\n \"width\": }");
  EXPECT_EQ(bad.rfind("scene.json: not valid JSON: ", 0), 0u) << bad;
  EXPECT_EQ(bad.find('\n'), std::string::npos) << bad;
  EXPECT_NE(bad.find("line 2"), std::string::npos) << bad;  // where it went wrong
  EXPECT_EQ(error_of("[1, 2]"), "scene.json: found [1,2] at the top, expected a JSON object { ... }");
  try {
    load_scene("/nonexistent/scene.json");
    ADD_FAILURE() << "no error for a missing file";
  } catch (const SceneError& e) {
    EXPECT_STREQ(e.what(), "/nonexistent/scene.json: cannot open the scene file (missing or unreadable)");
  }
}

TEST(Quality, PresetsSetTheMarchAndTheViewStepFollowsTheGrid) {
  VolumeGrid g;
  g.alt_m = {0.0, 500.0, 33};
  RenderSettings r;
  apply_quality("low", r);
  EXPECT_EQ(resolve_view_step_m(r, g), 1000.0);
  EXPECT_EQ(r.march.quality.sun_steps, 8);
  EXPECT_EQ(r.march.quality.octaves, 1);
  apply_quality("default", r);
  EXPECT_EQ(resolve_view_step_m(r, g), 500.0);
  EXPECT_EQ(r.march.quality.sun_steps, 16);
  EXPECT_EQ(r.march.quality.octaves, 4);
  EXPECT_EQ(r.accumulate, 1);
  apply_quality("high", r);
  EXPECT_EQ(resolve_view_step_m(r, g), 250.0);
  EXPECT_EQ(r.accumulate, 4);
  // The floor in metres: a fine grid does not make the default step finer than 50 m.
  g.alt_m.step = 20.0;
  apply_quality("default", r);
  EXPECT_EQ(resolve_view_step_m(r, g), 50.0);
  r.march.quality.view_step_m = 123.0;  // set by hand: used as it is
  EXPECT_EQ(resolve_view_step_m(r, g), 123.0);
  EXPECT_THROW(apply_quality("custom", r), std::invalid_argument);
}

TEST(Framing, AutoCameraLooksAtTheBaseOfTheVolumeFromTheSouth) {
  VolumeGrid g;
  g.lon_deg = {100.0, 0.25, 121};  // 100..130
  g.lat_deg = {0.0, 0.25, 81};     // 0..20
  g.alt_m = {0.0, 500.0, 33};
  const Camera c = auto_camera(g, 48, 27);
  EXPECT_EQ(c.width, 48);
  EXPECT_EQ(c.height, 27);
  EXPECT_DOUBLE_EQ(c.lat_deg, -2.0);
  EXPECT_DOUBLE_EQ(c.lon_deg, 115.0);
  EXPECT_DOUBLE_EQ(c.alt_m, 1.8e6);
  // The view axis points at the centre of the volume's base (to rounding).
  const glm::dvec3 eye = cv::geo::sphere_to_ecef({c.lat_deg, c.lon_deg, c.alt_m}, g.earth_radius_m);
  const glm::dvec3 target = cv::geo::sphere_to_ecef({10.0, 115.0, 0.0}, g.earth_radius_m);
  const glm::dvec3 forward = camera_frame(c).forward;
  const glm::dvec3 to_target = glm::normalize(target - eye);
  EXPECT_LT(std::atan2(glm::length(glm::cross(forward, to_target)), glm::dot(forward, to_target)), 1e-9);
  EXPECT_LT(std::abs(c.heading_deg), 1e-9);  // due north, the volume straight ahead
}

TEST(Framing, IsoDateTimesAndTheSun) {
  EXPECT_EQ(parse_iso_utc("2024-01-15T03:00:00Z"), 1705287600);
  EXPECT_EQ(parse_iso_utc("2000-02-29T23:59:59Z"), 951868799);
  EXPECT_EQ(parse_iso_utc("1969-12-31T00:00"), -86400);
  EXPECT_FALSE(parse_iso_utc("2023-02-29T00:00:00Z"));
  EXPECT_FALSE(parse_iso_utc("yesterday"));
  SunSpec spec;
  spec.mode = SunMode::DateTime;
  spec.datetime_utc = "2024-01-15T03:00:00Z";
  const Sun at = resolve_sun(spec, std::nullopt, 0.0);
  EXPECT_EQ(at.subsolar_lat_deg, cv::geo::subsolar_point(1705287600).lat_deg);
  EXPECT_EQ(at.subsolar_lon_deg, cv::geo::subsolar_point(1705287600).lon_deg);
  spec.mode = SunMode::ValidTime;
  EXPECT_EQ(resolve_sun(spec, 1705287600, 0.0).subsolar_lon_deg, at.subsolar_lon_deg);
  EXPECT_EQ(resolve_sun(spec, std::nullopt, 42.0).subsolar_lon_deg, 42.0);  // no time: noon over the camera
  spec.mode = SunMode::Manual;
  spec.subsolar_lat_deg = 5.0, spec.subsolar_lon_deg = -60.0, spec.irradiance = 2.0;
  const Sun m = resolve_sun(spec, 1705287600, 0.0);
  EXPECT_EQ(m.subsolar_lat_deg, 5.0);
  EXPECT_EQ(m.subsolar_lon_deg, -60.0);
  EXPECT_EQ(m.irradiance, glm::dvec3(2.0));
}

}  // namespace

TEST(SceneJson, OverlaysAreTypedEntriesOrPlainNames) {
  const Scene s = scene_from_json(
      R"({"version": 1, "overlays": ["coastlines", {"type": "graticule", "step_deg": 5, "color": [1, 0, 0]},
          {"type": "isosurface", "field": "temperature", "value": 273.15}]})", "scene.json");
  ASSERT_EQ(s.overlays.size(), 3u);
  EXPECT_EQ(s.overlays[0], default_overlay("coastlines"));
  EXPECT_EQ(s.overlays[1].number("step_deg"), 5.0);
  EXPECT_EQ(s.overlays[1].color("color"), glm::dvec3(1.0, 0.0, 0.0));
  EXPECT_EQ(s.overlays[1].number("line_width_px"), 1.0);  // a key left out keeps its default
  EXPECT_EQ(s.overlays[2].text("field"), "temperature");
  EXPECT_EQ(s.overlays[2].number("value"), 273.15);
}

TEST(SceneJson, BadOverlaysAreNamedWithWhatWasExpected) {
  EXPECT_EQ(error_of(R"({"version": 1, "overlays": ["roads"]})"),
            "scene.json: overlays[0]: found \"roads\", expected one of coastlines, borders, rivers, graticule, isosurface, wind, arrows, section");
  EXPECT_EQ(error_of(R"({"version": 1, "overlays": [{"step_deg": 5}]})"),
            "scene.json: overlays[0].type: found nothing, expected one of coastlines, borders, rivers, graticule, isosurface, wind, arrows, section");
  EXPECT_EQ(error_of(R"({"version": 1, "overlays": ["coastlines", {"type": "graticule", "step_deg": 0}]})"),
            "scene.json: overlays[1].step_deg: found 0, expected a number 0.5..90 (degrees)");
  EXPECT_EQ(error_of(R"({"version": 1, "overlays": [{"type": "graticule", "colour": [1, 1, 1]}]})"),
            "scene.json: overlays[0].colour: unknown key, expected one of type, color, step_deg, line_width_px, label_px");
  EXPECT_EQ(error_of(R"({"version": 1, "overlays": [{"type": "coastlines", "color": [1, 1]}]})"),
            "scene.json: overlays[0].color: found [1,1], expected [r, g, b], each 0..1000");
  EXPECT_EQ(error_of(R"({"version": 1, "overlays": "coastlines"})"),
            "scene.json: overlays: found \"coastlines\", expected an array of overlays (names or {\"type\": ...} objects)");
}

// Several views in the viewer (issue 17): the scene file keeps them, and its reader names what is wrong.
TEST(SceneJson, ViewsRoundTripAndTheirPathsAreTakenFromTheSceneFilesFolder) {
  const Scene s = scene_from_json(
      R"({"version": 1, "views": {"layout": "grid", "linked": false, "compare": [{"time": 2}, {"path": "b.nc", "time": "2024-01-15T06:00:00Z"},
          {"path": "c.cvvol"}]}})", "scene.json");
  ASSERT_TRUE(s.views);
  EXPECT_EQ(s.views->layout, "grid");
  EXPECT_FALSE(s.views->linked);
  ASSERT_EQ(s.views->compare.size(), 3u);
  EXPECT_EQ(s.views->compare[0].path, "");
  EXPECT_EQ(s.views->compare[0].time, "2");
  EXPECT_EQ(s.views->compare[1].path, "b.nc");
  EXPECT_EQ(s.views->compare[1].time, "2024-01-15T06:00:00Z");
  EXPECT_EQ(s.views->compare[2].time, "");
  const Scene again = scene_from_json(scene_to_json(s), "again.json");
  ASSERT_TRUE(again.views);
  EXPECT_EQ(again.views->linked, false);
  ASSERT_EQ(again.views->compare.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(again.views->compare[i].path, s.views->compare[i].path);
    EXPECT_EQ(again.views->compare[i].time, s.views->compare[i].time);
  }
  EXPECT_NE(scene_to_json(s).find("\"time\": 2\n"), std::string::npos) << "a step is written as a number";
  // None: written as null, read back as none.
  EXPECT_FALSE(scene_from_json(scene_to_json(Scene{}), "none.json").views);
  // A swipe of two, the divider kept.
  const Scene w = scene_from_json(R"({"version": 1, "views": {"layout": "swipe", "divider": 0.3, "compare": [{"time": 1}]}})", "w.json");
  EXPECT_EQ(w.views->divider, 0.3);

  const fs::path dir = fs::temp_directory_path() / ("cv_scene_views_" + std::to_string(::getpid())) / "scenes";
  fs::create_directories(dir);
  std::ofstream(dir / "s.json") << R"({"version": 1, "views": {"compare": [{"path": "../data/b.nc"}, {"time": 1}]}})";
  const Scene l = load_scene((dir / "s.json").string());
  EXPECT_EQ(l.views->compare[0].path, (dir.parent_path() / "data" / "b.nc").string());
  EXPECT_EQ(l.views->compare[1].path, "");  // the scene's own file stays the scene's own
  fs::remove_all(dir.parent_path());
}

TEST(SceneJson, BadViewsAreNamedWithWhatWasExpected) {
  EXPECT_EQ(error_of(R"({"version": 1, "views": {"layout": "tiles"}})"),
            "scene.json: views.layout: found \"tiles\", expected \"grid\" or \"swipe\"");
  EXPECT_EQ(error_of(R"({"version": 1, "views": {"compare": [{"time": 1}, {"time": 2}, {"time": 3}, {"time": 4}]}})"),
            "scene.json: views.compare: found [{\"time\":1},{\"time\":2},{\"time\":3},{\"t..., expected an array of at most 3 views "
            "{\"path\": FILE, \"time\": UTC time or step}");
  EXPECT_EQ(error_of(R"({"version": 1, "views": {"compare": [{"time": "soon"}]}})"),
            "scene.json: views.compare[0].time: found \"soon\", expected a UTC time YYYY-MM-DDThh:mm:ssZ or a step index >= 0");
  EXPECT_EQ(error_of(R"({"version": 1, "views": {"compare": [{"time": -1}]}})"),
            "scene.json: views.compare[0].time: found -1, expected a UTC time YYYY-MM-DDThh:mm:ssZ or a step index >= 0");
  EXPECT_EQ(error_of(R"({"version": 1, "views": {"compare": [{}]}})"),
            "scene.json: views.compare[0].path: found neither path nor time, expected a file, a time of the scene's file, or both");
  EXPECT_EQ(error_of(R"({"version": 1, "views": {"compare": [{"file": "b.nc"}]}})"),
            "scene.json: views.compare[0].file: unknown key, expected one of path, time");
  EXPECT_EQ(error_of(R"({"version": 1, "views": {"layout": "swipe", "compare": [{"time": 1}, {"time": 2}]}})"),
            "scene.json: views.layout: found \"swipe\" with 3 view(s), expected exactly one view in compare (a swipe divider splits two views)");
  EXPECT_EQ(error_of(R"({"version": 1, "views": {"divider": 2}})"), "scene.json: views.divider: found 2, expected a fraction of the width 0..1");
  EXPECT_EQ(error_of(R"({"version": 1, "views": {"linked": "yes"}})"), "scene.json: views.linked: found \"yes\", expected true or false");
}

TEST(OverlayFlag, ParsesNameAndTypedParameters) {
  const OverlaySpec g = parse_overlay_flag("graticule:step_deg=15,color=1,0.5,0");
  EXPECT_EQ(g.type, "graticule");
  EXPECT_EQ(g.number("step_deg"), 15.0);
  EXPECT_EQ(g.color("color"), glm::dvec3(1.0, 0.5, 0.0));
  EXPECT_EQ(parse_overlay_flag("coastlines"), default_overlay("coastlines"));
  auto message = [](const std::string& arg) {
    try {
      parse_overlay_flag(arg);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message("roads"),
            "--overlay roads: found \"roads\", expected one of coastlines, borders, rivers, graticule, isosurface, wind, arrows, section");
  EXPECT_EQ(message("graticule:step_deg=0"),
            "--overlay graticule:step_deg=0: found \"0\" for step_deg, expected a number 0.5..90 (degrees)");
  EXPECT_EQ(message("graticule:spacing=5"),
            "--overlay graticule:spacing=5: found the key \"spacing\", expected one of color, step_deg, line_width_px, label_px for graticule");
  EXPECT_EQ(message("graticule:5"), "--overlay graticule:5: found \"5\", expected key=value");
}
