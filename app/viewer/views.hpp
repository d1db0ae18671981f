// Several views in the viewer (issue 17, side by side): where each view lies in the window (a grid
// of 2 or 4, or two views on either side of a swipe divider), which view a mouse event goes to, and
// the link of cameras and time between views. Plain C++ (no ImGui, no GL), as keyframes.hpp, so
// the tests drive it; the viewer (viewer.cpp) and the GPU composition (view_compose.hpp) call it.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "frame/camera.hpp"

namespace cv::viewer {

constexpr int kMaxViews = 4;

enum class ViewLayout { Grid, Swipe };

// "grid" or "swipe"; nothing for any other word.
std::optional<ViewLayout> parse_view_layout(const std::string& name);
const char* view_layout_name(ViewLayout layout);

// A rectangle of the window in framebuffer pixels, origin at the top left, rows down (as mouse
// positions are given).
struct ViewRect {
  int x = 0, y = 0, w = 0, h = 0;
  bool contains(double px, double py) const { return px >= x && px < x + w && py >= y && py < y + h; }
  bool operator==(const ViewRect& o) const { return x == o.x && y == o.y && w == o.w && h == o.h; }
};

// Where view i of n is rendered, and its size: in a grid, one view fills the window, two stand side
// by side (left W/2 pixels wide, right the rest), three or four make a 2 x 2 grid (the first row
// H/2 high); with a swipe divider every view covers the whole window (only two are allowed).
std::vector<ViewRect> view_rects(ViewLayout layout, int n, int width, int height);

// The swipe divider's column: views left of it show view 0, from it on view 1. `divider` is the
// fraction of the width, 0..1.
int swipe_column(int width, double divider);

// The part of view i that shows: its whole rectangle in a grid, its side of the divider in a swipe.
ViewRect visible_rect(ViewLayout layout, int n, int i, int width, int height, double divider);

// The view under pixel (x, y), or -1 outside the window.
int view_at(ViewLayout layout, int n, int width, int height, double divider, double x, double y);

// Which view the mouse acts on. A drag stays with the view it started in (the cursor may cross into
// another view while a button is held); a press within kGrab pixels of the swipe divider drags the
// divider instead; the wheel goes to the view under the cursor.
struct MouseRouter {
  static constexpr double kGrab = 4.0;
  int captured = -1;              // the view a held button started in
  bool dragging_divider = false;  // a held button started on the divider
  // This frame's mouse: position, whether a button went down this frame, whether one is held. Moves
  // `divider` while it is dragged (kept within 0..1) and returns the view that takes this frame's
  // drag and wheel, or -1 (the divider is being dragged, or the cursor is outside the window).
  int route(ViewLayout layout, int n, int width, int height, double& divider, double x, double y, bool pressed, bool held);
};

// One view's camera and time as the link sees them.
struct ViewCursor {
  core::Camera camera;
  double t = 0.0;  // unix seconds when the view's source has UTC valid times, else its step index
  double t_first = 0.0, t_last = 0.0;  // the source's span in the same unit
  bool utc = true;
};

// The link between views. The viewer reads every view's cursor before a frame's interactions
// (begin), lets the mouse, the keys, the panels and playback change any view, reads them again and
// calls sync: when a view's camera changed, every linked view takes its position, heading, pitch
// and field of view (each keeps its own pixel size); when a view's time changed by d, every linked
// view's time moves by d (views of the same instant stay on one instant; views of one source at two
// times keep their difference), held within its source's span. Times in UTC and step indices are
// not mixed: a change in one unit moves only the views in that unit.
class LinkedViews {
 public:
  bool link_camera = true, link_time = true;
  std::vector<ViewCursor> views;

  void begin() { before_ = views; }
  // Returns, per view, whether the link changed it (the viewer writes those back).
  std::vector<bool> sync();

 private:
  std::vector<ViewCursor> before_;
};

bool same_view_camera(const core::Camera& a, const core::Camera& b);  // position, orientation and fov

}  // namespace cv::viewer
