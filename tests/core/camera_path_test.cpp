// Camera paths (issue 16): keyframes hit exactly, C1 by finite differences, no orientation flip over
// a pole or across the date line, altitude never below the keyframes' minimum, weather time, and
// the scene file's `path` key read, written and refused with the key named.
#include <gtest/gtest.h>

#include <cmath>

#include <glm/glm.hpp>

#include "frame/camera.hpp"
#include "geo/geodesy.hpp"
#include "scene/camera_path.hpp"
#include "scene/framing.hpp"
#include "scene/scene_json.hpp"

namespace cv::core {
namespace {

PathKeyframe key(double t, double lat, double lon, double alt, double heading, double pitch, double fov = 60.0) {
  PathKeyframe k;
  k.t_s = t, k.lat_deg = lat, k.lon_deg = lon, k.alt_m = alt, k.heading_deg = heading, k.pitch_deg = pitch, k.fov_deg = fov;
  return k;
}

// A descent from orbit, unevenly spaced in time, turning and narrowing.
CameraPath descent() {
  CameraPath p;
  p.keyframes = {key(0, 10, 150, 2e7, 0, -90, 70), key(3, 30, 170, 2e6, 20, -60, 60), key(4, 40, 175, 2e5, 40, -30, 50),
                 key(9, 45, 178, 8e3, 80, -10, 45)};
  return p;
}

glm::dvec3 position(const Camera& c) { return geo::sphere_to_ecef({c.lat_deg, c.lon_deg, c.alt_m}); }
glm::dvec3 forward(const Camera& c) { return camera_frame(c).forward; }
glm::dvec3 right(const Camera& c) { return camera_frame(c).right; }
double angle_deg(const glm::dvec3& a, const glm::dvec3& b) {
  return std::acos(std::clamp(glm::dot(glm::normalize(a), glm::normalize(b)), -1.0, 1.0)) * 180.0 / 3.14159265358979323846;
}

TEST(CameraPath, KeyframesAreHitExactly) {
  const CameraPath p = descent();
  const PathEvaluator e(p);
  for (const PathKeyframe& k : p.keyframes) {
    const Camera c = e.at(k.t_s).camera;
    EXPECT_NEAR(c.lat_deg, k.lat_deg, 1e-9);
    EXPECT_NEAR(std::remainder(c.lon_deg - k.lon_deg, 360.0), 0.0, 1e-9);
    EXPECT_NEAR(c.alt_m, k.alt_m, 1e-6 * k.alt_m);
    EXPECT_NEAR(c.fov_deg, k.fov_deg, 1e-9);
    // The view, not the numbers: heading is undefined looking straight down, so compare the axes.
    const Camera want = [&] {
      Camera w;
      w.lat_deg = k.lat_deg, w.lon_deg = k.lon_deg, w.heading_deg = k.heading_deg, w.pitch_deg = k.pitch_deg;
      return w;
    }();
    EXPECT_LT(angle_deg(forward(c), forward(want)), 1e-6);
    EXPECT_LT(angle_deg(right(c), right(want)), 1e-6);
  }
}

// Left and right difference quotients agree at the keyframes (and between them) for the position,
// the view direction and the field of view. A path through the keyframes with a kink (linear
// interpolation, or tangents not shared) has quotients that differ by O(1) there.
TEST(CameraPath, IsC1ByFiniteDifferences) {
  const PathEvaluator e(descent());
  const double eps = 1e-5;
  for (double t : {3.0, 4.0, 1.5, 6.0}) {
    const Camera a = e.at(t - eps).camera, b = e.at(t).camera, c = e.at(t + eps).camera;
    const glm::dvec3 left = (position(b) - position(a)) / eps, rightd = (position(c) - position(b)) / eps;
    EXPECT_LT(glm::length(left - rightd), 1e-3 * glm::length(left) + 1.0) << "position kinks at t = " << t;
    const glm::dvec3 fl = (forward(b) - forward(a)) / eps, fr = (forward(c) - forward(b)) / eps;
    EXPECT_LT(glm::length(fl - fr), 1e-3 * glm::length(fl) + 1e-4) << "view direction kinks at t = " << t;
    const double vl = (b.fov_deg - a.fov_deg) / eps, vr = (c.fov_deg - b.fov_deg) / eps;
    EXPECT_LT(std::abs(vl - vr), 1e-3 * std::abs(vl) + 1e-4) << "fov kinks at t = " << t;
  }
}

// A control for the test above: the quotients it compares do differ at a kink (the position's
// left and right speeds are not equal at a keyframe where a path of straight chords turns).
TEST(CameraPath, FiniteDifferencesSeeAKink) {
  const PathEvaluator e(descent());
  auto chord = [&](double t) {  // straight lines between the keyframes' positions
    const auto& k = e.path().keyframes;
    std::size_t i = 0;
    while (i + 2 < k.size() && t > k[i + 1].t_s) ++i;
    const double f = (t - k[i].t_s) / (k[i + 1].t_s - k[i].t_s);
    const glm::dvec3 a = geo::sphere_to_ecef({k[i].lat_deg, k[i].lon_deg, k[i].alt_m});
    const glm::dvec3 b = geo::sphere_to_ecef({k[i + 1].lat_deg, k[i + 1].lon_deg, k[i + 1].alt_m});
    return a + f * (b - a);
  };
  const double eps = 1e-5, t = 3.0;
  const glm::dvec3 left = (chord(t) - chord(t - eps)) / eps, rightd = (chord(t + eps) - chord(t)) / eps;
  EXPECT_GT(glm::length(left - rightd), 1e-3 * glm::length(left) + 1.0);
}

// Over the north pole: from 80N 0E heading north to 80N 180E heading south (still flying the same
// way). The view turns smoothly: no step between samples is much larger than the average step.
TEST(CameraPath, NoFlipOverAPole) {
  CameraPath p;
  p.keyframes = {key(0, 80, 0, 5e5, 0, -30), key(5, 89.5, 0, 5e5, 0, -30), key(10, 80, 180, 5e5, 180, -30)};
  const PathEvaluator e(p);
  const int n = 2000;
  double total = 0.0, worst = 0.0, worst_right = 0.0, max_lat = -90.0;
  Camera prev = e.at(0).camera;
  for (int i = 1; i <= n; ++i) {
    const Camera c = e.at(10.0 * i / n).camera;
    const double step = angle_deg(forward(prev), forward(c));
    total += step;
    worst = std::max(worst, step);
    worst_right = std::max(worst_right, angle_deg(right(prev), right(c)));
    max_lat = std::max(max_lat, c.lat_deg);
    prev = c;
  }
  EXPECT_GT(max_lat, 89.4);  // it does go over the pole
  EXPECT_LT(worst, 5.0 * total / n + 1e-6) << "the view jumps by " << worst << " degrees in one step";
  EXPECT_LT(worst_right, 0.5) << "the image turns by " << worst_right << " degrees in one step";
  // Ends on the far side looking south along 180E, as keyframed.
  const Camera end = e.at(10).camera;
  EXPECT_NEAR(end.lat_deg, 80.0, 1e-9);
  EXPECT_LT(angle_deg(forward(end), forward([] {
              Camera w;
              w.lat_deg = 80, w.lon_deg = 180, w.heading_deg = 180, w.pitch_deg = -30;
              return w;
            }())),
            1e-6);
}

// Across the date line: 170E to 170W goes the short way (20 degrees), not round the globe, and the
// heading (given as 90 and as -270, the same direction) does not spin.
TEST(CameraPath, NoFlipAcrossTheDateLine) {
  CameraPath p;
  p.keyframes = {key(0, 0, 170, 1e5, 90, -20), key(4, 0, -170, 1e5, -270, -20)};
  const PathEvaluator e(p);
  Camera prev = e.at(0).camera;
  double worst = 0.0;
  for (int i = 1; i <= 400; ++i) {
    const Camera c = e.at(4.0 * i / 400).camera;
    EXPECT_GE(std::abs(geo::wrap_lon_deg(c.lon_deg)), 169.999) << "the path left the short way at sample " << i;
    worst = std::max(worst, angle_deg(forward(prev), forward(c)));
    prev = c;
  }
  EXPECT_LT(worst, 0.2);  // the view moves only with the 20-degree flight, never a turn
}

// The altitude stays within the keyframes' range, above the lowest keyframe and the ground, also
// where a smooth (not monotone) spline through these values would undershoot: a steep descent to
// a low keyframe followed by a level stretch.
TEST(CameraPath, AltitudeNeverBelowTheKeyframesMinimum) {
  CameraPath p;
  p.keyframes = {key(0, 40, 170, 3.6e7, 0, -90), key(2, 40, 171, 500, 0, -20), key(6, 40, 172, 400, 0, -20), key(7, 40, 173, 2e4, 0, -20)};
  const PathEvaluator e(p);
  double lowest = 1e300;
  for (int i = 0; i <= 7000; ++i) lowest = std::min(lowest, e.at(7.0 * i / 7000).camera.alt_m);
  EXPECT_GE(lowest, 400.0 - 1e-6);
  // A descent from orbit slows near the ground: the first half of the time to the low keyframe
  // covers far more than half of the height.
  EXPECT_LT(e.at(1.0).camera.alt_m, 0.1 * 3.6e7);
}

TEST(CameraPath, WeatherTimeFromKeyframesOrRate) {
  CameraPath p;
  p.keyframes = {key(0, 40, 170, 1e6, 0, -60), key(10, 41, 171, 1e6, 0, -60)};
  p.keyframes[0].valid_utc = "2024-01-15T00:00:00Z";
  p.keyframes[1].valid_utc = "2024-01-15T05:00:00Z";
  const std::int64_t t0 = *parse_iso_utc("2024-01-15T00:00:00Z");
  EXPECT_EQ(*PathEvaluator(p).at(4.0).weather_unix_s, t0 + 2 * 3600);
  p.keyframes[1].valid_utc.clear();
  p.weather_hours_per_s = 0.25;
  EXPECT_EQ(*PathEvaluator(p).at(4.0).weather_unix_s, t0 + 3600);
  p.keyframes[0].valid_utc.clear();
  p.weather_hours_per_s = 0.0;
  EXPECT_FALSE(PathEvaluator(p).at(4.0).weather_unix_s.has_value());  // the scene's own time
}

TEST(CameraPath, ConstantSpeedAndEase) {
  CameraPath p;
  // Keyframes at uneven times: 2 s for the first 10 degrees, 8 s for the next 10.
  p.keyframes = {key(0, 0, 0, 1e5, 90, 0), key(2, 0, 10, 1e5, 90, 0), key(10, 0, 20, 1e5, 90, 0)};
  p.speed = PathSpeed::Constant;
  const PathEvaluator e(p);
  EXPECT_NEAR(e.at(5.0).camera.lon_deg, 10.0, 0.05);  // half the time, half the way
  const double d1 = glm::length(position(e.at(1.0).camera) - position(e.at(0.0).camera));
  const double d2 = glm::length(position(e.at(9.0).camera) - position(e.at(8.0).camera));
  EXPECT_NEAR(d1 / d2, 1.0, 1e-3);
  p.speed = PathSpeed::Keyframes;
  p.ease = true;
  const PathEvaluator eased(p);
  // Eased: it starts at rest (the first 0.1 s covers far less than a tenth of the first second's way).
  const double start = glm::length(position(eased.at(0.1).camera) - position(eased.at(0.0).camera));
  const double first = glm::length(position(eased.at(1.0).camera) - position(eased.at(0.0).camera));
  EXPECT_LT(start, 0.05 * first);
  EXPECT_NEAR(eased.at(10.0).camera.lon_deg, 20.0, 1e-9);
}

TEST(CameraPath, FramesCoverThePathInclusive) {
  const PathEvaluator e(descent());  // 9 s
  EXPECT_EQ(path_frame_count(e, 30.0), 271);
  EXPECT_DOUBLE_EQ(path_frame_time_s(e, 270, 30.0), 9.0);
}

// The scene file: written and read back to the same path; bad paths are named by key.
TEST(CameraPath, SceneFileRoundTrip) {
  Scene s;
  s.path = descent();
  s.path->weather_hours_per_s = 0.5;
  s.path->keyframes[0].valid_utc = "2024-01-15T00:00:00Z";
  s.path->speed = PathSpeed::Constant;
  s.path->ease = true;
  const Scene back = scene_from_json(scene_to_json(s), "s.json");
  ASSERT_TRUE(back.path);
  ASSERT_EQ(back.path->keyframes.size(), 4u);
  EXPECT_EQ(back.path->keyframes[2].alt_m, 2e5);
  EXPECT_EQ(back.path->keyframes[3].heading_deg, 80.0);
  EXPECT_EQ(back.path->keyframes[0].valid_utc, "2024-01-15T00:00:00Z");
  EXPECT_EQ(back.path->weather_hours_per_s, 0.5);
  EXPECT_EQ(back.path->speed, PathSpeed::Constant);
  EXPECT_TRUE(back.path->ease);
  EXPECT_EQ(scene_to_json(back), scene_to_json(s));
  EXPECT_FALSE(scene_from_json(scene_to_json(Scene{}), "s.json").path);
}

std::string scene_with_path(const std::string& path) { return R"({"version": 1, "path": )" + path + "}"; }
std::string error_of(const std::string& text) {
  try {
    scene_from_json(text, "fly.json");
  } catch (const SceneError& e) {
    return e.what();
  }
  return "no error";
}

TEST(CameraPath, BadPathsAreNamedByKey) {
  EXPECT_EQ(error_of(scene_with_path(R"({"keyframes": [{"t_s": 0, "lat_deg": 0, "lon_deg": 0, "alt_m": 1000}]})")),
            "fly.json: path.keyframes: found 1 keyframe, expected at least 2 keyframes (a path needs a start and an end)");
  EXPECT_EQ(error_of(scene_with_path(R"({"keyframes": [{"t_s": 0, "lat_deg": 0, "lon_deg": 0, "alt_m": 1000},
                                                       {"t_s": 0, "lat_deg": 1, "lon_deg": 0, "alt_m": 1000}]})")),
            "fly.json: path.keyframes[1].t_s: found 0, expected more than keyframe 0's 0 s (path times must increase)");
  EXPECT_EQ(error_of(scene_with_path(R"({"keyframes": [{"t_s": 0, "lat_deg": 0, "lon_deg": 0, "alt_m": 1000},
                                                       {"t_s": 1, "lat_deg": 1, "lon_deg": 0, "alt_m": -5}]})")),
            "fly.json: path.keyframes[1].alt_m: found -5, expected an altitude in metres 0..4e8 (not below the ground)");
  EXPECT_EQ(error_of(scene_with_path(R"({"keyframes": [{"t_s": 0, "lat_deg": 0, "lon_deg": 0},
                                                       {"t_s": 1, "lat_deg": 1, "lon_deg": 0, "alt_m": 5}]})")),
            "fly.json: path.keyframes[0].alt_m: found nothing, expected a number (t_s, lat_deg, lon_deg and alt_m are required)");
  EXPECT_EQ(error_of(scene_with_path(R"({"keyframes": [{"t_s": 0, "lat_deg": 0, "lon_deg": 0, "alt_m": 1, "valid_utc": "2024-01-15T00:00:00Z"},
                                                       {"t_s": 1, "lat_deg": 1, "lon_deg": 0, "alt_m": 5}]})")),
            "fly.json: path.keyframes[1].valid_utc: found nothing, expected every keyframe with a valid_utc or none (keyframe 0 has "
            "one), or weather_hours_per_s");
  EXPECT_EQ(error_of(scene_with_path(R"({"keyframes": [{"t_s": 0, "lat_deg": 0, "lon_deg": 0, "alt_m": 1},
                                                       {"t_s": 1, "lat_deg": 1, "lon_deg": 0, "alt_m": 5}], "weather_hours_per_s": 1})")),
            "fly.json: path.keyframes[0].valid_utc: found nothing, expected the weather's start time (weather_hours_per_s runs from it)");
  EXPECT_EQ(error_of(scene_with_path(R"({"keyframes": [{"t_s": 0, "lat_deg": 0, "lon_deg": 0, "alt_m": 1, "roll_deg": 3},
                                                       {"t_s": 1, "lat_deg": 1, "lon_deg": 0, "alt_m": 5}]})")),
            "fly.json: path.keyframes[0].roll_deg: unknown key, expected one of t_s, lat_deg, lon_deg, alt_m, heading_deg, pitch_deg, "
            "fov_deg, valid_utc");
  EXPECT_EQ(error_of(scene_with_path(R"({"keyframes": [{"t_s": 0, "lat_deg": 0, "lon_deg": 0, "alt_m": 1},
                                                       {"t_s": 1, "lat_deg": 0, "lon_deg": 179, "alt_m": 5}]})")),
            "fly.json: path.keyframes[1].lat_deg: found 179.0 degrees from keyframe 0's position, expected keyframes closer together on "
            "the globe (add one between them)");
  EXPECT_EQ(error_of(scene_with_path(R"({"keyframes": [], "speed": "fast"})")),
            "fly.json: path.speed: found \"fast\", expected \"keyframes\" or \"constant\"");
}

}  // namespace
}  // namespace cv::core
