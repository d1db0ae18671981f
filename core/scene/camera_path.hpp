// A flyover's camera path: keyframes on the globe, each with its path time and weather time,
// interpolated smoothly (position on the sphere, altitude in log space, orientation by a
// quaternion spline) and sampled per video frame by `cloudviewer record`.
#pragma once

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <glm/gtc/quaternion.hpp>
#include <glm/vec3.hpp>

#include "frame/camera.hpp"

namespace cv::core {

struct Scene;

// One keyframe: the camera at path time t_s, and the weather's valid time there ("" when the
// path's rate rule, or the scene's own time, gives it).
struct PathKeyframe {
  double t_s = 0.0;
  double lat_deg = 0.0, lon_deg = 0.0, alt_m = 0.0;
  double heading_deg = 0.0, pitch_deg = 0.0, fov_deg = 60.0;
  std::string valid_utc;
};

// How path time maps onto the keyframes: at their own times, or at constant speed along the path
// (the keyframes' times then only order them and set the duration).
enum class PathSpeed { Keyframes, Constant };

struct CameraPath {
  std::vector<PathKeyframe> keyframes;
  // Not 0: the weather runs at this many hours per path second from keyframe 0's valid_utc (the
  // other keyframes then give none). 0: each keyframe's valid_utc, linear in between, or, when no
  // keyframe gives one, the scene's own time (still weather).
  double weather_hours_per_s = 0.0;
  PathSpeed speed = PathSpeed::Keyframes;
  bool ease = false;  // ease in and out over the whole path (a smoothstep of path time)
};

// A path that cannot be used: `key` is the key path below "path" (keyframes[2].t_s), with what was
// found and what was expected, for a one-line message.
struct PathError : std::runtime_error {
  PathError(std::string key_, std::string found_, std::string expected_)
      : std::runtime_error(key_ + ": found " + found_ + ", expected " + expected_),
        key(std::move(key_)), found(std::move(found_)), expected(std::move(expected_)) {}
  std::string key, found, expected;
};

// Where the path is at one time.
struct PathSample {
  Camera camera;  // position, heading, pitch and fov (width and height left at their defaults)
  std::optional<std::int64_t> weather_unix_s;  // the weather's valid time; nothing: the scene's own
};

// The path made ready to sample: tangents and, for constant speed, the arc-length table. The
// constructor checks the path (PathError).
class PathEvaluator {
 public:
  explicit PathEvaluator(const CameraPath& path);

  double start_s() const { return t_.front(); }
  double end_s() const { return t_.back(); }
  double duration_s() const { return t_.back() - t_.front(); }
  const CameraPath& path() const { return path_; }

  PathSample at(double t_s) const;
  // The weather's valid time at path time t_s in seconds since 1970 (not rounded), if the path gives one.
  std::optional<double> weather_at(double t_s) const;
  // The keyframe parameter (path time on the keyframes' own clock) that path time t_s maps to
  // after easing and constant-speed reparametrisation; t_s itself without either.
  double parameter_at(double t_s) const;

  // The interpolated pieces at keyframe parameter tau (no easing or reparametrisation): the unit
  // position, the altitude, the orientation (x right, y up, z backward in Earth-centred axes).
  glm::dvec3 direction_at(double tau) const;
  double altitude_at(double tau) const;
  glm::dquat orientation_at(double tau) const;

 private:
  int segment(double tau) const;
  CameraPath path_;
  std::vector<double> t_;               // keyframe times
  std::vector<glm::dvec3> p_, dp_;      // unit positions and their tangents (per second)
  std::vector<double> u_, du_;          // log altitude and its tangents
  std::vector<double> fov_, dfov_;
  std::vector<glm::dquat> q_, dq_;      // orientations (sign-aligned) and tangents
  std::vector<std::optional<double>> weather_;  // per keyframe, seconds since 1970
  std::vector<double> arc_tau_, arc_len_;       // constant speed: parameter against distance travelled
};

// Video frames of a path at fps: frame k at path time start + k / fps, up to the end inclusive.
int path_frame_count(const PathEvaluator& path, double fps);
double path_frame_time_s(const PathEvaluator& path, int frame, double fps);

// The scene at path time t_s: the camera from the path (at the scene's size), the time from the
// path's weather when it gives one (whole seconds, rounded), the path itself kept.
Scene scene_at_path_time(const Scene& scene, const PathEvaluator& path, double t_s);

// The altitude offset of the log-altitude spline: altitude a is interpolated as log(a + this), so a
// descent from orbit slows near the ground and an altitude of 0 is allowed.
inline constexpr double kPathAltitudeOffsetM = 1.0;

}  // namespace cv::core
