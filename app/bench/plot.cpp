// The log-log error/time plot (see plot.hpp): axes, decade ticks with exponent labels, points by
// kind, the Pareto front as a polyline through its points.
#include "bench/plot.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>

namespace cv::bench {

namespace {

using Color = std::array<std::uint8_t, 3>;

// 3x5 glyphs, one row per 3 bits (high bit left), for the tick labels "1e-3" and the like.
int glyph_row(char c, int row) {
  static const char* chars = "0123456789e-";
  static const int rows[][5] = {
      {7, 5, 5, 5, 7}, {2, 6, 2, 2, 7}, {7, 1, 7, 4, 7}, {7, 1, 7, 1, 7}, {5, 5, 7, 1, 1}, {7, 4, 7, 1, 7},
      {7, 4, 7, 5, 7}, {7, 1, 1, 1, 1}, {7, 5, 7, 5, 7}, {7, 5, 7, 1, 7}, {0, 7, 7, 4, 7}, {0, 0, 7, 0, 0},
  };
  for (int i = 0; chars[i]; ++i) {
    if (chars[i] == c) return rows[i][row];
  }
  return 0;
}

// "e-3" for 10^-3 (snprintf: GCC 12 warns falsely on "e" + std::to_string under -O3).
std::string exponent_label(int d) {
  char b[16];
  std::snprintf(b, sizeof b, "e%d", d);
  return b;
}

class Canvas {
 public:
  Canvas(int w, int h) : img_{w, h, std::vector<std::uint8_t>(static_cast<std::size_t>(w) * h * 3, 255)} {}
  void set(int x, int y, Color c) {
    if (x < 0 || y < 0 || x >= img_.width || y >= img_.height) return;
    auto* p = &img_.rgb[(static_cast<std::size_t>(y) * img_.width + x) * 3];
    p[0] = c[0], p[1] = c[1], p[2] = c[2];
  }
  void line(int x0, int y0, int x1, int y1, Color c) {  // Bresenham
    const int dx = std::abs(x1 - x0), dy = -std::abs(y1 - y0), sx = x0 < x1 ? 1 : -1, sy = y0 < y1 ? 1 : -1;
    int err = dx + dy;
    for (;;) {
      set(x0, y0, c);
      if (x0 == x1 && y0 == y1) break;
      const int e2 = 2 * err;
      if (e2 >= dy) err += dy, x0 += sx;
      if (e2 <= dx) err += dx, y0 += sy;
    }
  }
  void square(int x, int y, int r, Color c) {
    for (int j = -r; j <= r; ++j)
      for (int i = -r; i <= r; ++i) set(x + i, y + j, c);
  }
  void text(int x, int y, const std::string& s, Color c) {  // 3x5 glyphs, 1 px apart
    for (char ch : s) {
      for (int r = 0; r < 5; ++r)
        for (int b = 0; b < 3; ++b)
          if (glyph_row(ch, r) & (4 >> b)) set(x + b, y + r, c);
      x += 4;
    }
  }
  Rgb8Image take() { return std::move(img_); }

 private:
  Rgb8Image img_;
};

}  // namespace

Rgb8Image plot_error_vs_time(const std::vector<PlotPoint>& pts, const std::vector<std::size_t>& front, int width,
                             int height) {
  Canvas cv(width, height);
  auto ok = [](const TimeError& p) { return std::isfinite(p.time) && std::isfinite(p.error) && p.time > 0 && p.error > 0; };
  double tmin = 1e300, tmax = -1e300, emin = 1e300, emax = -1e300;
  for (const auto& q : pts) {
    if (!ok(q.p)) continue;
    tmin = std::min(tmin, std::log10(q.p.time)), tmax = std::max(tmax, std::log10(q.p.time));
    emin = std::min(emin, std::log10(q.p.error)), emax = std::max(emax, std::log10(q.p.error));
  }
  if (tmin > tmax) tmin = tmax = emin = emax = 0.0;  // nothing to plot: empty axes over one decade
  // Whole decades around the data, at least one wide.
  tmin = std::floor(tmin), tmax = std::max(std::ceil(tmax), tmin + 1);
  emin = std::floor(emin), emax = std::max(std::ceil(emax), emin + 1);
  const int left = 30, right = width - 8, top = 8, bottom = height - 18;
  auto px = [&](double t) { return left + static_cast<int>(std::lround((std::log10(t) - tmin) / (tmax - tmin) * (right - left))); };
  auto py = [&](double e) { return bottom - static_cast<int>(std::lround((std::log10(e) - emin) / (emax - emin) * (bottom - top))); };
  const Color axis{0, 0, 0}, grid{225, 225, 225};
  for (int d = static_cast<int>(tmin); d <= static_cast<int>(tmax); ++d) {
    const int x = px(std::pow(10.0, d));
    cv.line(x, top, x, bottom, grid);
    cv.line(x, bottom, x, bottom + 3, axis);
    const std::string s = exponent_label(d);
    cv.text(x - static_cast<int>(s.size()) * 2, bottom + 6, s, axis);
  }
  for (int d = static_cast<int>(emin); d <= static_cast<int>(emax); ++d) {
    const int y = py(std::pow(10.0, d));
    cv.line(left, y, right, y, grid);
    cv.line(left - 3, y, left, y, axis);
    const std::string s = exponent_label(d);
    cv.text(left - 5 - static_cast<int>(s.size()) * 4, y - 2, s, axis);
  }
  cv.line(left, top, left, bottom, axis);
  cv.line(left, bottom, right, bottom, axis);
  const Color front_c{220, 30, 30};
  for (std::size_t i = 1; i < front.size(); ++i) {
    const TimeError a = pts[front[i - 1]].p, b = pts[front[i]].p;
    cv.line(px(a.time), py(a.error), px(b.time), py(b.error), front_c);
  }
  const Color kinds[4] = {{40, 90, 200}, {20, 150, 60}, {230, 140, 0}, {140, 60, 200}};
  for (const auto& q : pts) {
    if (ok(q.p)) cv.square(px(q.p.time), py(q.p.error), 2, kinds[std::clamp(q.kind, 0, 3)]);
  }
  for (std::size_t i : front) {  // the front's points ringed in red
    const int x = px(pts[i].p.time), y = py(pts[i].p.error);
    for (int k = -4; k <= 4; ++k) {
      cv.set(x + k, y - 4, front_c), cv.set(x + k, y + 4, front_c), cv.set(x - 4, y + k, front_c), cv.set(x + 4, y + k, front_c);
    }
  }
  return cv.take();
}

}  // namespace cv::bench
