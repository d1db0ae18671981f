// Camera path interpolation: cubic Hermite splines whose tangents are shared at the keyframes (so
// the path is C1), on unit position vectors, log altitude (monotone, so it never dips below the
// lower of two keyframes) and sign-aligned quaternions, each normalised after interpolation.
#include "scene/camera_path.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "geo/geodesy.hpp"
#include "scene/framing.hpp"
#include "scene/instant.hpp"
#include "scene/scene.hpp"

namespace cv::core {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.10g", v);
  return buf;
}

std::string at_key(std::size_t i, const char* key) { return "keyframes[" + std::to_string(i) + "]." + key; }

// Hermite basis on s in [0, 1] for an interval of length h: value and tangents at both ends.
template <class T>
T hermite(const T& a, const T& ma, const T& b, const T& mb, double h, double s) {
  const double s2 = s * s, s3 = s2 * s;
  return (2 * s3 - 3 * s2 + 1) * a + (s3 - 2 * s2 + s) * h * ma + (-2 * s3 + 3 * s2) * b + (s3 - s2) * h * mb;
}

// Tangents of a smooth (not monotone) spline through values at times t: at inner keyframes the
// derivative of the parabola through the three neighbours (weighted by the interval lengths, so
// uneven keyframe spacing does not kink the path), one-sided at the ends.
template <class T>
std::vector<T> smooth_tangents(const std::vector<double>& t, const std::vector<T>& v) {
  const std::size_t n = v.size();
  std::vector<T> m(n);
  for (std::size_t i = 0; i < n; ++i) {
    if (i == 0) {
      m[i] = (v[1] - v[0]) / (t[1] - t[0]);
    } else if (i + 1 == n) {
      m[i] = (v[i] - v[i - 1]) / (t[i] - t[i - 1]);
    } else {
      const double h0 = t[i] - t[i - 1], h1 = t[i + 1] - t[i];
      const T d0 = (v[i] - v[i - 1]) / h0, d1 = (v[i + 1] - v[i]) / h1;
      m[i] = (h1 * d0 + h0 * d1) / (h0 + h1);
    }
  }
  return m;
}

// Tangents of a monotone cubic (Fritsch-Butland): zero at a local extremum, a weighted harmonic
// mean of the neighbouring slopes elsewhere, so each interval stays between its two values.
std::vector<double> monotone_tangents(const std::vector<double>& t, const std::vector<double>& v) {
  const std::size_t n = v.size();
  std::vector<double> d(n - 1), m(n);
  for (std::size_t i = 0; i + 1 < n; ++i) d[i] = (v[i + 1] - v[i]) / (t[i + 1] - t[i]);
  m[0] = d[0];
  m[n - 1] = d[n - 2];
  for (std::size_t i = 1; i + 1 < n; ++i) {
    if (d[i - 1] * d[i] <= 0.0) {
      m[i] = 0.0;
    } else {
      const double h0 = t[i] - t[i - 1], h1 = t[i + 1] - t[i];
      const double w1 = 2 * h1 + h0, w2 = h1 + 2 * h0;
      m[i] = (w1 + w2) / (w1 / d[i - 1] + w2 / d[i]);
    }
  }
  return m;
}

glm::dquat camera_quat(const PathKeyframe& k) {
  Camera c;
  c.lat_deg = k.lat_deg, c.lon_deg = k.lon_deg, c.heading_deg = k.heading_deg, c.pitch_deg = k.pitch_deg;
  const CameraFrame f = camera_frame(c);
  // Columns right, up, -forward: a proper rotation (camera_frame's up is right x forward).
  return glm::normalize(glm::quat_cast(glm::dmat3(f.right, f.up, -f.forward)));
}

double smoothstep(double x) { return x * x * (3.0 - 2.0 * x); }

}  // namespace

PathEvaluator::PathEvaluator(const CameraPath& path) : path_(path) {
  const auto& k = path_.keyframes;
  if (k.size() < 2) {
    throw PathError("keyframes", std::to_string(k.size()) + " keyframe" + (k.size() == 1 ? "" : "s"),
                    "at least 2 keyframes (a path needs a start and an end)");
  }
  const bool rule = path_.weather_hours_per_s != 0.0;
  for (std::size_t i = 0; i < k.size(); ++i) {
    const PathKeyframe& f = k[i];
    if (!std::isfinite(f.t_s) || (i > 0 && !(f.t_s > k[i - 1].t_s))) {
      throw PathError(at_key(i, "t_s"), num(f.t_s),
                      i == 0 ? "a finite path time in seconds"
                             : "more than keyframe " + std::to_string(i - 1) + "'s " + num(k[i - 1].t_s) + " s (path times must increase)");
    }
    if (!(f.alt_m >= 0.0 && f.alt_m <= 4e8)) throw PathError(at_key(i, "alt_m"), num(f.alt_m), "an altitude in metres 0..4e8 (not below the ground)");
    if (!(f.lat_deg >= -90.0 && f.lat_deg <= 90.0)) throw PathError(at_key(i, "lat_deg"), num(f.lat_deg), "a latitude in degrees -90..90");
    if (!std::isfinite(f.lon_deg)) throw PathError(at_key(i, "lon_deg"), num(f.lon_deg), "a longitude in degrees");
    if (!std::isfinite(f.heading_deg)) throw PathError(at_key(i, "heading_deg"), num(f.heading_deg), "a heading in degrees");
    if (!(f.pitch_deg >= -90.0 && f.pitch_deg <= 90.0)) throw PathError(at_key(i, "pitch_deg"), num(f.pitch_deg), "a pitch in degrees -90..90");
    if (!(f.fov_deg > 0.0 && f.fov_deg < 180.0)) throw PathError(at_key(i, "fov_deg"), num(f.fov_deg), "a field of view in degrees, more than 0 and less than 180");
    const auto when = f.valid_utc.empty() ? std::nullopt : parse_iso_utc(f.valid_utc);
    if (!f.valid_utc.empty() && !when) throw PathError(at_key(i, "valid_utc"), "\"" + f.valid_utc + "\"", "a UTC date-time YYYY-MM-DDThh:mm:ssZ");
    if (rule && i > 0 && when) {
      throw PathError(at_key(i, "valid_utc"), "\"" + f.valid_utc + "\"",
                      "none: with weather_hours_per_s the rate gives every keyframe after the first its time");
    }
    if (!rule && when.has_value() != !k[0].valid_utc.empty()) {
      throw PathError(at_key(i, "valid_utc"), when ? "\"" + f.valid_utc + "\"" : "nothing",
                      std::string("every keyframe with a valid_utc or none (keyframe 0 has ") + (k[0].valid_utc.empty() ? "none" : "one") +
                          "), or weather_hours_per_s");
    }
    weather_.push_back(when ? std::optional<double>(static_cast<double>(*when)) : std::nullopt);
  }
  if (rule && k[0].valid_utc.empty()) {
    throw PathError(at_key(0, "valid_utc"), "nothing", "the weather's start time (weather_hours_per_s runs from it)");
  }
  if (!std::isfinite(path_.weather_hours_per_s) || std::abs(path_.weather_hours_per_s) > 1e6) {
    throw PathError("weather_hours_per_s", num(path_.weather_hours_per_s), "hours of weather per path second, -1e6..1e6 (0: none)");
  }

  for (const PathKeyframe& f : k) {
    t_.push_back(f.t_s);
    p_.push_back(geo::sphere_to_ecef({f.lat_deg, f.lon_deg, 0.0}, 1.0));
    u_.push_back(std::log(f.alt_m + kPathAltitudeOffsetM));
    fov_.push_back(f.fov_deg);
    glm::dquat q = camera_quat(f);
    if (!q_.empty() && glm::dot(q, q_.back()) < 0.0) q = -q;  // the same rotation, on the near side: no flip
    q_.push_back(q);
  }
  dp_ = smooth_tangents(t_, p_);
  du_ = monotone_tangents(t_, u_);
  dfov_ = monotone_tangents(t_, fov_);
  {
    std::vector<glm::dvec4> qv, dqv;
    for (const glm::dquat& q : q_) qv.emplace_back(q.x, q.y, q.z, q.w);
    dqv = smooth_tangents(t_, qv);
    for (const glm::dvec4& d : dqv) dq_.push_back(glm::dquat(d.w, d.x, d.y, d.z));
  }
  // A chord spline normalised onto the sphere needs its chord to stay clear of the centre: keyframes
  // far apart on the globe (or orientations far apart) need one between them.
  for (std::size_t i = 0; i + 1 < k.size(); ++i) {
    const double h = t_[i + 1] - t_[i];
    for (int j = 1; j < 64; ++j) {
      const double s = j / 64.0;
      const glm::dvec3 p = hermite(p_[i], dp_[i], p_[i + 1], dp_[i + 1], h, s);
      if (glm::length(p) < 0.5) {
        char found[160];
        std::snprintf(found, sizeof found, "%.1f degrees from keyframe %zu's position",
                      std::acos(std::clamp(glm::dot(p_[i], p_[i + 1]), -1.0, 1.0)) / kDeg, i);
        throw PathError(at_key(i + 1, "lat_deg"), found, "keyframes closer together on the globe (add one between them)");
      }
      const glm::dquat q = hermite(q_[i], dq_[i], q_[i + 1], dq_[i + 1], h, s);
      if (glm::length(q) < 0.5) {
        throw PathError(at_key(i + 1, "heading_deg"), "a turn too far from keyframe " + std::to_string(i) + "'s view",
                        "smaller turns between keyframes (add one between them)");
      }
    }
  }
  if (path_.speed == PathSpeed::Constant) {  // distance travelled (Earth-centred metres) against the parameter
    const int per_segment = 256;
    const int n = per_segment * static_cast<int>(k.size() - 1);
    glm::dvec3 prev{};
    double len = 0.0;
    for (int j = 0; j <= n; ++j) {
      const double tau = t_.front() + (t_.back() - t_.front()) * j / n;
      const glm::dvec3 x = direction_at(tau) * (geo::kEarthRadiusM + altitude_at(tau));
      if (j > 0) len += glm::length(x - prev);
      prev = x;
      arc_tau_.push_back(tau);
      arc_len_.push_back(len);
    }
  }
}

int PathEvaluator::segment(double tau) const {
  const auto it = std::upper_bound(t_.begin(), t_.end(), tau);
  const int i = static_cast<int>(it - t_.begin()) - 1;
  return std::clamp(i, 0, static_cast<int>(t_.size()) - 2);
}

glm::dvec3 PathEvaluator::direction_at(double tau) const {
  tau = std::clamp(tau, t_.front(), t_.back());
  const int i = segment(tau);
  const double h = t_[i + 1] - t_[i];
  return glm::normalize(hermite(p_[i], dp_[i], p_[i + 1], dp_[i + 1], h, (tau - t_[i]) / h));
}

double PathEvaluator::altitude_at(double tau) const {
  tau = std::clamp(tau, t_.front(), t_.back());
  const int i = segment(tau);
  const double h = t_[i + 1] - t_[i];
  return std::max(0.0, std::exp(hermite(u_[i], du_[i], u_[i + 1], du_[i + 1], h, (tau - t_[i]) / h)) - kPathAltitudeOffsetM);
}

glm::dquat PathEvaluator::orientation_at(double tau) const {
  tau = std::clamp(tau, t_.front(), t_.back());
  const int i = segment(tau);
  const double h = t_[i + 1] - t_[i];
  return glm::normalize(hermite(q_[i], dq_[i], q_[i + 1], dq_[i + 1], h, (tau - t_[i]) / h));
}

double PathEvaluator::parameter_at(double t_s) const {
  const double t0 = t_.front(), T = duration_s();
  double x = std::clamp((t_s - t0) / T, 0.0, 1.0);
  if (path_.ease) x = smoothstep(x);
  if (path_.speed != PathSpeed::Constant || !(arc_len_.back() > 0.0)) return t0 + x * T;
  const double target = x * arc_len_.back();
  const auto it = std::lower_bound(arc_len_.begin(), arc_len_.end(), target);
  if (it == arc_len_.begin()) return arc_tau_.front();
  if (it == arc_len_.end()) return arc_tau_.back();
  const std::size_t j = static_cast<std::size_t>(it - arc_len_.begin());
  const double a = arc_len_[j - 1], b = arc_len_[j];
  const double f = b > a ? (target - a) / (b - a) : 0.0;
  return arc_tau_[j - 1] + f * (arc_tau_[j] - arc_tau_[j - 1]);
}

std::optional<double> PathEvaluator::weather_at(double t_s) const {
  if (path_.weather_hours_per_s != 0.0) {
    return *weather_[0] + path_.weather_hours_per_s * 3600.0 * (std::clamp(t_s, t_.front(), t_.back()) - t_.front());
  }
  if (!weather_[0]) return std::nullopt;
  const double tau = std::clamp(parameter_at(t_s), t_.front(), t_.back());
  const int i = segment(tau);
  const double f = (tau - t_[i]) / (t_[i + 1] - t_[i]);
  return *weather_[i] + f * (*weather_[i + 1] - *weather_[i]);
}

PathSample PathEvaluator::at(double t_s) const {
  const double tau = parameter_at(t_s);
  PathSample s;
  const glm::dvec3 p = direction_at(tau);
  const geo::Geodetic g = geo::ecef_to_sphere(p, 1.0);
  s.camera.lat_deg = g.lat_deg, s.camera.lon_deg = g.lon_deg;
  s.camera.alt_m = altitude_at(tau);
  {
    const double c = std::clamp(tau, t_.front(), t_.back());
    const int i = segment(c);
    const double h = t_[i + 1] - t_[i];
    s.camera.fov_deg = hermite(fov_[i], dfov_[i], fov_[i + 1], dfov_[i + 1], h, (c - t_[i]) / h);
  }
  // Heading and pitch of the interpolated view at the interpolated position: the camera has no roll,
  // so the forward axis decides, and where it points straight up or down, the right axis.
  const glm::dmat3 m = glm::mat3_cast(orientation_at(tau));
  const glm::dvec3 right = m[0], forward = -m[2];
  const geo::EnuFrame e = geo::sphere_enu(s.camera.lat_deg, s.camera.lon_deg);
  const double fu = std::clamp(glm::dot(forward, e.up), -1.0, 1.0);
  s.camera.pitch_deg = std::asin(fu) / kDeg;
  const double fe = glm::dot(forward, e.east), fn = glm::dot(forward, e.north);
  if (std::hypot(fe, fn) > 1e-9) {
    s.camera.heading_deg = std::atan2(fe, fn) / kDeg;
  } else {
    s.camera.heading_deg = std::atan2(-glm::dot(right, e.north), glm::dot(right, e.east)) / kDeg;
  }
  if (const auto w = weather_at(t_s)) s.weather_unix_s = std::llround(*w);
  return s;
}

int path_frame_count(const PathEvaluator& path, double fps) {
  return static_cast<int>(std::floor(path.duration_s() * fps + 1e-9)) + 1;
}

double path_frame_time_s(const PathEvaluator& path, int frame, double fps) { return path.start_s() + frame / fps; }

Scene scene_at_path_time(const Scene& scene, const PathEvaluator& path, double t_s) {
  Scene s = scene;
  const PathSample p = path.at(t_s);
  Camera c = p.camera;
  c.width = scene.width, c.height = scene.height;
  s.camera = c;
  if (p.weather_unix_s) s.time.valid_utc = format_iso_utc(*p.weather_unix_s);
  return s;
}

}  // namespace cv::core
