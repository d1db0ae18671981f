// Several views: layout, mouse routing and the link of cameras and time (views.hpp).
#include "viewer/views.hpp"

#include <algorithm>
#include <cmath>

namespace cv::viewer {

std::optional<ViewLayout> parse_view_layout(const std::string& name) {
  if (name == "grid") return ViewLayout::Grid;
  if (name == "swipe") return ViewLayout::Swipe;
  return std::nullopt;
}

const char* view_layout_name(ViewLayout layout) { return layout == ViewLayout::Swipe ? "swipe" : "grid"; }

std::vector<ViewRect> view_rects(ViewLayout layout, int n, int width, int height) {
  std::vector<ViewRect> r(static_cast<std::size_t>(std::max(0, n)));
  const int left = width / 2, top = height / 2;
  for (int i = 0; i < n; ++i) {
    ViewRect& v = r[static_cast<std::size_t>(i)];
    if (layout == ViewLayout::Swipe || n == 1) {
      v = {0, 0, width, height};
    } else if (n == 2) {
      v = i == 0 ? ViewRect{0, 0, left, height} : ViewRect{left, 0, width - left, height};
    } else {
      const int col = i % 2, row = i / 2;
      v = {col == 0 ? 0 : left, row == 0 ? 0 : top, col == 0 ? left : width - left, row == 0 ? top : height - top};
    }
  }
  return r;
}

int swipe_column(int width, double divider) {
  return static_cast<int>(std::clamp(std::lround(std::clamp(divider, 0.0, 1.0) * width), 0L, static_cast<long>(width)));
}

ViewRect visible_rect(ViewLayout layout, int n, int i, int width, int height, double divider) {
  const ViewRect r = view_rects(layout, n, width, height)[static_cast<std::size_t>(i)];
  if (layout != ViewLayout::Swipe || n < 2) return r;
  const int d = swipe_column(width, divider);
  if (i == 0) return {0, 0, d, height};
  if (i == 1) return {d, 0, width - d, height};
  return {0, 0, 0, 0};  // a swipe shows two views
}

int view_at(ViewLayout layout, int n, int width, int height, double divider, double x, double y) {
  for (int i = 0; i < n; ++i) {
    if (visible_rect(layout, n, i, width, height, divider).contains(x, y)) return i;
  }
  return -1;
}

int MouseRouter::route(ViewLayout layout, int n, int width, int height, double& divider, double x, double y, bool pressed,
                       bool held) {
  if (pressed) {
    dragging_divider = layout == ViewLayout::Swipe && n >= 2 && y >= 0.0 && y < height &&
                       std::abs(x - swipe_column(width, divider)) <= kGrab;
    captured = dragging_divider ? -1 : view_at(layout, n, width, height, divider, x, y);
  } else if (!held) {
    dragging_divider = false;
    captured = -1;
  }
  if (dragging_divider) {
    if (width > 0) divider = std::clamp(x / width, 0.0, 1.0);
    return -1;
  }
  if (held && captured >= 0) return captured;
  return view_at(layout, n, width, height, divider, x, y);
}

bool same_view_camera(const core::Camera& a, const core::Camera& b) {
  return a.lat_deg == b.lat_deg && a.lon_deg == b.lon_deg && a.alt_m == b.alt_m && a.heading_deg == b.heading_deg &&
         a.pitch_deg == b.pitch_deg && a.fov_deg == b.fov_deg;
}

std::vector<bool> LinkedViews::sync() {
  std::vector<bool> changed(views.size(), false);
  if (before_.size() != views.size()) {  // views were added or removed: nothing to compare with
    before_ = views;
    return changed;
  }
  // The first view whose camera changed leads (one view takes a frame's interaction).
  if (link_camera) {
    for (std::size_t i = 0; i < views.size(); ++i) {
      if (same_view_camera(views[i].camera, before_[i].camera)) continue;
      const core::Camera& lead = views[i].camera;
      for (std::size_t k = 0; k < views.size(); ++k) {
        if (k == i || same_view_camera(views[k].camera, lead)) continue;
        core::Camera& c = views[k].camera;
        c.lat_deg = lead.lat_deg, c.lon_deg = lead.lon_deg, c.alt_m = lead.alt_m;
        c.heading_deg = lead.heading_deg, c.pitch_deg = lead.pitch_deg, c.fov_deg = lead.fov_deg;
        changed[k] = true;
      }
      break;
    }
  }
  if (link_time) {
    for (std::size_t i = 0; i < views.size(); ++i) {
      const double d = views[i].t - before_[i].t;
      if (d == 0.0) continue;
      for (std::size_t k = 0; k < views.size(); ++k) {
        if (k == i || views[k].utc != views[i].utc) continue;
        const double t = std::clamp(before_[k].t + d, views[k].t_first, views[k].t_last);
        if (t != views[k].t) {
          views[k].t = t;
          changed[k] = true;
        }
      }
      break;
    }
  }
  before_ = views;
  return changed;
}

}  // namespace cv::viewer
