// The analysts' plot raster.
#include "plots/plot_canvas.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "overlays/overlays.hpp"

namespace cv::plots {

Canvas::Canvas(int width, int height, Rgb bg) : w_(width), h_(height), rgb_(static_cast<std::size_t>(width) * height * 3) {
  for (std::size_t i = 0; i < rgb_.size(); i += 3) rgb_[i] = bg[0], rgb_[i + 1] = bg[1], rgb_[i + 2] = bg[2];
}

Rgb Canvas::at(int x, int y) const {
  const std::size_t i = (static_cast<std::size_t>(y) * w_ + x) * 3;
  return {rgb_[i], rgb_[i + 1], rgb_[i + 2]};
}

void Canvas::set(int x, int y, Rgb c) {
  if (x < 0 || y < 0 || x >= w_ || y >= h_) return;
  const std::size_t i = (static_cast<std::size_t>(y) * w_ + x) * 3;
  rgb_[i] = c[0], rgb_[i + 1] = c[1], rgb_[i + 2] = c[2];
}

void Canvas::line(double x0, double y0, double x1, double y1, Rgb c) {
  const int n = static_cast<int>(std::ceil(std::max(std::abs(x1 - x0), std::abs(y1 - y0)))) + 1;
  for (int i = 0; i <= n; ++i) {
    const double f = static_cast<double>(i) / n;
    set(static_cast<int>(std::lround(x0 + f * (x1 - x0))), static_cast<int>(std::lround(y0 + f * (y1 - y0))), c);
  }
}

void Canvas::box(int x0, int y0, int x1, int y1, Rgb c) {
  line(x0, y0, x1, y0, c);
  line(x1, y0, x1, y1, c);
  line(x1, y1, x0, y1, c);
  line(x0, y1, x0, y0, c);
}

double Canvas::text_width(double px, const std::string& s) { return s.empty() ? 0.0 : (6.0 * s.size() - 2.0) * px / 6.0; }

void Canvas::text(double x, double y, double px, const std::string& s, Rgb c, Align align) {
  const double k = px / 6.0;  // glyphs are 6 units high
  const double w = text_width(px, s);
  const double left = align == Align::Left ? x : align == Align::Centre ? x - 0.5 * w : x - w;
  for (const auto& seg : overlays::label_strokes(s)) line(left + seg[0] * k, y - seg[1] * k, left + seg[2] * k, y - seg[3] * k, c);
}

namespace {
Rgb to8(double r, double g, double b) {
  auto q = [](double v) { return static_cast<unsigned char>(std::lround(255.0 * std::clamp(v, 0.0, 1.0))); };
  return {q(r), q(g), q(b)};
}
}  // namespace

Rgb sequential_colour(double t) {
  const glm::vec4 v = overlays::colormap(t);
  return to8(v.r, v.g, v.b);
}

Rgb diverging_colour(double t) {
  t = std::clamp(std::isfinite(t) ? t : 0.5, 0.0, 1.0);
  // Blue (0.13, 0.32, 0.75) to white at 0.5 to red (0.75, 0.15, 0.12), linear in each half.
  if (t < 0.5) {
    const double f = t / 0.5;
    return to8(0.13 + f * 0.87, 0.32 + f * 0.68, 0.75 + f * 0.25);
  }
  const double f = (t - 0.5) / 0.5;
  return to8(1.0 - f * 0.25, 1.0 - f * 0.85, 1.0 - f * 0.88);
}

std::string tick_text(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

void colour_bar(Canvas& c, int x0, int y0, int x1, int y1, double lo, double hi, const std::string& title,
                const std::function<Rgb(double)>& colour) {
  for (int y = y0; y <= y1; ++y) {
    const double t = y1 == y0 ? 0.0 : static_cast<double>(y1 - y) / (y1 - y0);
    for (int x = x0; x <= x1; ++x) c.set(x, y, colour(t));
  }
  const Rgb ink{20, 20, 20};
  c.box(x0, y0, x1, y1, ink);
  for (int i = 0; i <= 4; ++i) {
    const double t = i / 4.0;
    const double y = y1 - t * (y1 - y0);
    c.line(x1, y, x1 + 4, y, ink);
    c.text(x1 + 7, y + 4, 9, tick_text(lo + t * (hi - lo)), ink);
  }
  c.text(x0, y0 - 8, 9, title, ink);
}

}  // namespace cv::plots
