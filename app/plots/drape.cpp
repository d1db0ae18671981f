// Maps draped on the globe: a ray-sphere intersection per pixel of the camera.
#include "plots/drape.hpp"

#include <algorithm>
#include <cmath>

#include "geo/geodesy.hpp"

namespace cv::plots {

std::optional<std::size_t> column_at(const core::VolumeGrid& g, double lat_deg, double lon_deg) {
  if (!std::isfinite(lat_deg) || !std::isfinite(lon_deg) || g.lon_deg.count < 1 || g.lat_deg.count < 1) return std::nullopt;
  const double east = std::fmod(std::fmod(lon_deg - g.lon_deg.start, 360.0) + 360.0, 360.0);
  long i = std::lround(east / g.lon_deg.step);
  if (g.wraps_lon()) i %= g.lon_deg.count;
  const long j = std::lround((lat_deg - g.lat_deg.start) / g.lat_deg.step);
  if (i < 0 || i >= g.lon_deg.count || j < 0 || j >= g.lat_deg.count) return std::nullopt;
  return g.column(static_cast<int>(i), static_cast<int>(j));
}

void drape_columns(Canvas& c, int x0, int y0, const core::Camera& cam, const core::VolumeGrid& g,
                   const std::function<Rgb(std::size_t column)>& colour) {
  const double r0 = g.earth_radius_m;
  const glm::dvec3 o = core::camera_ecef(cam, r0);
  for (int py = 0; py < cam.height; ++py) {
    for (int px = 0; px < cam.width; ++px) {
      const glm::dvec3 d = core::camera_ray(cam, px, py);
      // |o + t d| = r0: t^2 + 2 b t + (|o|^2 - r0^2) = 0, the nearer root in front of the camera.
      const double b = glm::dot(o, d), q = glm::dot(o, o) - r0 * r0, disc = b * b - q;
      Rgb out{0, 0, 0};
      const double t = disc >= 0.0 ? -b - std::sqrt(disc) : -1.0;
      if (t > 0.0) {
        const glm::dvec3 p = o + t * d;
        const double shade = 0.6 + 0.4 * std::max(0.0, -glm::dot(glm::normalize(p), d));
        const geo::Geodetic ll = geo::ecef_to_sphere(p, r0);
        const std::optional<std::size_t> col = column_at(g, ll.lat_deg, ll.lon_deg);
        const Rgb base = col ? colour(*col) : kGlobe;
        for (int k = 0; k < 3; ++k) out[static_cast<std::size_t>(k)] = static_cast<unsigned char>(std::lround(base[static_cast<std::size_t>(k)] * shade));
      }
      c.set(x0 + px, y0 + py, out);
    }
  }
}

}  // namespace cv::plots
