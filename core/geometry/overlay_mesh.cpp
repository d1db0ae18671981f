// Overlay geometry and its CPU cast.
#include "geometry/overlay_mesh.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/glm.hpp>

namespace cv::core {

void OverlayMesh::append(const OverlayMesh& other) {
  const auto base = static_cast<std::uint32_t>(positions.size());
  positions.insert(positions.end(), other.positions.begin(), other.positions.end());
  colors.insert(colors.end(), other.colors.begin(), other.colors.end());
  for (std::uint32_t i : other.lines) lines.push_back(base + i);
  for (std::uint32_t i : other.triangles) triangles.push_back(base + i);
  const OverlayInstances& oi = other.instances;
  if (oi.empty()) return;
  OverlayInstances& ti = instances;
  if (ti.empty()) {
    ti = oi;
    return;
  }
  if (ti.glyph_positions == oi.glyph_positions && ti.glyph_triangles == oi.glyph_triangles) {
    ti.origins.insert(ti.origins.end(), oi.origins.begin(), oi.origins.end());
    ti.axis_x.insert(ti.axis_x.end(), oi.axis_x.begin(), oi.axis_x.end());
    ti.axis_y.insert(ti.axis_y.end(), oi.axis_y.begin(), oi.axis_y.end());
    ti.axis_z.insert(ti.axis_z.end(), oi.axis_z.begin(), oi.axis_z.end());
    ti.colors.insert(ti.colors.end(), oi.colors.begin(), oi.colors.end());
    return;
  }
  OverlayMesh glyphs;
  glyphs.instances = oi;
  append(expand_instances(glyphs));
}

OverlayMesh expand_instances(const OverlayMesh& mesh) {
  OverlayMesh out = mesh;
  out.instances = {};
  const OverlayInstances& in = mesh.instances;
  if (in.empty()) return out;
  out.colors.resize(out.positions.size(), glm::vec4(1.0f));
  const std::size_t nv = in.glyph_positions.size();
  out.positions.reserve(out.positions.size() + nv * in.count());
  out.triangles.reserve(out.triangles.size() + in.glyph_triangles.size() * in.count());
  for (std::size_t k = 0; k < in.count(); ++k) {
    const auto base = static_cast<std::uint32_t>(out.positions.size());
    const glm::dvec3 ax(in.axis_x[k]), ay(in.axis_y[k]), az(in.axis_z[k]);
    glm::vec4 color = k < in.colors.size() ? in.colors[k] : glm::vec4(1.0f);
    color.a = 1.0f;  // instances are opaque
    for (const glm::vec3& g : in.glyph_positions) {
      // The order of the GPU's vertex shader (overlay_instanced.vert): origin + x + y + z.
      out.positions.push_back(((in.origins[k] + ax * static_cast<double>(g.x)) + ay * static_cast<double>(g.y)) + az * static_cast<double>(g.z));
      out.colors.push_back(color);
    }
    for (std::uint32_t i : in.glyph_triangles) out.triangles.push_back(base + i);
  }
  return out;
}

Projected project_point(const Camera& cam, const glm::dvec3& rel) {
  const CameraFrame f = camera_frame(cam);
  Projected p;
  const double z = glm::dot(rel, f.forward);
  p.distance_m = glm::length(rel);
  p.in_front = z > 0.0;
  if (!p.in_front) return p;
  const double aspect = static_cast<double>(cam.height) / cam.width;
  const double x = glm::dot(rel, f.right) / z / f.tan_half;           // -1..1 across the image
  const double y = glm::dot(rel, f.up) / z / (f.tan_half * aspect);   // -1..1 bottom to top
  p.x = 0.5 * (x + 1.0) * cam.width;
  p.y = 0.5 * (1.0 - y) * cam.height;
  return p;
}

bool hidden_by_sphere(const glm::dvec3& c, const glm::dvec3& rel, double r0) {
  const double dist = glm::length(rel);
  if (dist <= 0.0) return false;
  const glm::dvec3 d = rel / dist;
  const double b = glm::dot(d, c);
  const double cq = glm::dot(c, c) - r0 * r0;
  const double disc = b * b - cq;
  if (disc < 0.0) return false;
  const double s = std::sqrt(disc);
  // The nearer root, in the form that keeps its digits (-b - s cancels when the camera is near the sphere).
  const double t0 = b < 0.0 ? cq / (-b + s) : -b - s;
  if (t0 < 0.0) return false;  // the sphere behind the camera, or the camera inside it (below ground): nothing hidden
  return t0 < dist - std::max(1.0, 1e-6 * dist);
}

namespace {

struct Hit {
  float distance = 0.0f;
  glm::vec4 color{0.0f};
};

void keep(std::vector<Hit>& hits, std::size_t i, double t, const glm::vec4& color) {
  if (hits[i].distance == 0.0f || t < hits[i].distance) hits[i] = {static_cast<float>(t), color};
}

}  // namespace

OpaqueLayer cast_overlay(const OverlayMesh& given, const Camera& cam, double r0_m) {
  OverlayMesh expanded;
  if (!given.instances.empty()) expanded = expand_instances(given);
  const OverlayMesh& mesh = given.instances.empty() ? given : expanded;
  const int w = cam.width, h = cam.height;
  std::vector<Hit> hits(static_cast<std::size_t>(w) * h);
  const glm::dvec3 c = camera_ecef(cam, r0_m);
  std::vector<glm::dvec3> rel(mesh.positions.size());
  std::vector<Projected> proj(mesh.positions.size());
  for (std::size_t i = 0; i < rel.size(); ++i) rel[i] = mesh.positions[i] - c, proj[i] = project_point(cam, rel[i]);
  std::vector<glm::dvec3> rays(hits.size());
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) rays[static_cast<std::size_t>(y) * w + x] = camera_ray(cam, x, y);
  }
  auto color_of = [&](std::uint32_t v) { return v < mesh.colors.size() ? mesh.colors[v] : glm::vec4(1.0f); };
  // Translucent triangle fragments (alpha below 1), every one per pixel; sorted and cut below.
  std::vector<std::vector<Hit>> translucent(hits.size());
  bool any_translucent = false;
  // Triangles: exact ray intersection over the pixels of the projected bounding box (all pixels when
  // a vertex is behind the camera).
  for (std::size_t k = 0; k + 2 < mesh.triangles.size(); k += 3) {
    const std::uint32_t i0 = mesh.triangles[k], i1 = mesh.triangles[k + 1], i2 = mesh.triangles[k + 2];
    int x0 = 0, x1 = w - 1, y0 = 0, y1 = h - 1;
    if (proj[i0].in_front && proj[i1].in_front && proj[i2].in_front) {
      x0 = std::max(0, static_cast<int>(std::floor(std::min({proj[i0].x, proj[i1].x, proj[i2].x}))) - 1);
      x1 = std::min(w - 1, static_cast<int>(std::ceil(std::max({proj[i0].x, proj[i1].x, proj[i2].x}))) + 1);
      y0 = std::max(0, static_cast<int>(std::floor(std::min({proj[i0].y, proj[i1].y, proj[i2].y}))) - 1);
      y1 = std::min(h - 1, static_cast<int>(std::ceil(std::max({proj[i0].y, proj[i1].y, proj[i2].y}))) + 1);
    }
    const glm::dvec3 a = rel[i0], e1 = rel[i1] - a, e2 = rel[i2] - a;
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        const std::size_t pi = static_cast<std::size_t>(y) * w + x;
        const glm::dvec3& d = rays[pi];
        const glm::dvec3 pv = glm::cross(d, e2);
        const double det = glm::dot(e1, pv);
        if (std::abs(det) < 1e-300) continue;
        const glm::dvec3 tv = -a;
        const double u = glm::dot(tv, pv) / det;
        if (u < 0.0 || u > 1.0) continue;
        const glm::dvec3 qv = glm::cross(tv, e1);
        const double v = glm::dot(d, qv) / det;
        if (v < 0.0 || u + v > 1.0) continue;
        const double t = glm::dot(e2, qv) / det;
        if (t <= 0.0 || hidden_by_sphere(c, t * d, r0_m)) continue;
        // Colour interpolated barycentrically, as the GPU's perspective-correct varyings.
        const glm::vec4 col = static_cast<float>(1.0 - u - v) * color_of(i0) + static_cast<float>(u) * color_of(i1) +
                              static_cast<float>(v) * color_of(i2);
        if (col.a < kOpaqueAlpha) {
          translucent[pi].push_back({static_cast<float>(t), col});
          any_translucent = true;
        } else {
          keep(hits, pi, t, col);
        }
      }
    }
  }
  // Lines: pixels whose centres lie within half a pixel of the projected segment.
  for (std::size_t k = 0; k + 1 < mesh.lines.size(); k += 2) {
    const std::uint32_t i0 = mesh.lines[k], i1 = mesh.lines[k + 1];
    if (!proj[i0].in_front || !proj[i1].in_front) continue;
    const Projected &p0 = proj[i0], &p1 = proj[i1];
    const int x0 = std::max(0, static_cast<int>(std::floor(std::min(p0.x, p1.x) - 1.0)));
    const int x1 = std::min(w - 1, static_cast<int>(std::ceil(std::max(p0.x, p1.x) + 1.0)));
    const int y0 = std::max(0, static_cast<int>(std::floor(std::min(p0.y, p1.y) - 1.0)));
    const int y1 = std::min(h - 1, static_cast<int>(std::ceil(std::max(p0.y, p1.y) + 1.0)));
    const double dx = p1.x - p0.x, dy = p1.y - p0.y, len2 = dx * dx + dy * dy;
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        const double cx = x + 0.5, cy = y + 0.5;
        const double s = len2 > 0.0 ? std::clamp(((cx - p0.x) * dx + (cy - p0.y) * dy) / len2, 0.0, 1.0) : 0.0;
        const double ex = p0.x + s * dx - cx, ey = p0.y + s * dy - cy;
        if (ex * ex + ey * ey > 0.25) continue;
        // The segment's point nearest the pixel's ray, and its distance along the ray.
        const std::size_t pi = static_cast<std::size_t>(y) * w + x;
        const glm::dvec3& d = rays[pi];
        const glm::dvec3 a = rel[i0], u = rel[i1] - rel[i0];
        const double uu = glm::dot(u, u), ud = glm::dot(u, d), au = glm::dot(a, u), ad = glm::dot(a, d);
        const double den = uu - ud * ud;
        const double sg = den > 1e-12 * uu ? std::clamp((ad * ud - au) / den, 0.0, 1.0) : s;
        const glm::dvec3 q = a + sg * u;
        if (hidden_by_sphere(c, q, r0_m)) continue;
        const glm::vec4 col = static_cast<float>(1.0 - sg) * color_of(i0) + static_cast<float>(sg) * color_of(i1);
        // A line has no width: where the pixel's own ray meets the sphere nearer than the line's
        // point, the line is taken there (as the GPU pass does).
        double t = glm::length(q);
        const double b = glm::dot(d, c), cq = glm::dot(c, c) - r0_m * r0_m, disc = b * b - cq;
        if (disc >= 0.0) {
          const double sq = std::sqrt(disc);
          const double tg = b < 0.0 ? cq / (-b + sq) : -b - sq;
          if (tg > 0.0) t = std::min(t, tg);
        }
        keep(hits, pi, t * (1.0 - kLineDistanceBias), col);
      }
    }
  }
  OpaqueLayer out;
  out.distance_m.resize(hits.size());
  out.radiance_rgba.resize(4 * hits.size());
  for (std::size_t i = 0; i < hits.size(); ++i) {
    out.distance_m[i] = hits[i].distance;
    for (int ch = 0; ch < 4; ++ch) out.radiance_rgba[4 * i + ch] = hits[i].distance > 0.0f ? hits[i].color[ch] : 0.0f;
  }
  if (any_translucent) {
    // The nearest kTranslucentLayers fragments in front of the opaque geometry, nearest first (as
    // the GPU pass's depth peeling finds them).
    const int n = kTranslucentLayers;
    out.layers = n;
    out.layer_distance_m.assign(static_cast<std::size_t>(n) * hits.size(), 0.0f);
    out.layer_rgba.assign(4 * out.layer_distance_m.size(), 0.0f);
    for (std::size_t i = 0; i < hits.size(); ++i) {
      std::vector<Hit>& f = translucent[i];
      const float opaque = hits[i].distance;
      std::erase_if(f, [&](const Hit& h) { return opaque > 0.0f && !(h.distance < opaque); });
      std::sort(f.begin(), f.end(), [](const Hit& a, const Hit& b) { return a.distance < b.distance; });
      // One fragment per surface: a pixel on the edge two triangles share is hit by both here (at
      // distances a rounding apart), where the GPU's rasteriser gives it to one of them.
      f.erase(std::unique(f.begin(), f.end(), [](const Hit& a, const Hit& b) { return b.distance - a.distance <= 1e-6f * b.distance; }),
              f.end());
      const std::size_t x = i % static_cast<std::size_t>(w), y = i / static_cast<std::size_t>(w);
      for (std::size_t k = 0; k < std::min(f.size(), static_cast<std::size_t>(n)); ++k) {
        const std::size_t at = (y * static_cast<std::size_t>(n) + k) * static_cast<std::size_t>(w) + x;
        out.layer_distance_m[at] = f[k].distance;
        for (int ch = 0; ch < 4; ++ch) out.layer_rgba[4 * at + ch] = f[k].color[ch];
      }
    }
  }
  return out;
}

}  // namespace cv::core
