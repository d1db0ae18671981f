// A small raster for the analysts' plots (sections, time series, difference maps): lines, boxes,
// the overlays layer's stroke font and colour map, and a colour bar, into 8-bit RGB for encode_png.
// Shared by the headless commands (app/cli) and the viewer's section and series panels.
#pragma once

#include <array>
#include <functional>
#include <string>
#include <vector>

namespace cv::plots {

using Rgb = std::array<unsigned char, 3>;

class Canvas {
 public:
  Canvas(int width, int height, Rgb background);
  int width() const { return w_; }
  int height() const { return h_; }
  const std::vector<unsigned char>& rgb() const { return rgb_; }
  Rgb at(int x, int y) const;
  void set(int x, int y, Rgb c);
  void line(double x0, double y0, double x1, double y1, Rgb c);
  void box(int x0, int y0, int x1, int y1, Rgb c);  // outline, corners included
  // Text in the overlays' stroke font, px high, its left end at x (or centred, or right-aligned),
  // its baseline at y.
  enum class Align { Left, Centre, Right };
  void text(double x, double y, double px, const std::string& s, Rgb c, Align align = Align::Left);
  static double text_width(double px, const std::string& s);

 private:
  int w_, h_;
  std::vector<unsigned char> rgb_;
};

// The overlays' colour map (overlays::colormap, t in 0..1) as 8-bit RGB.
Rgb sequential_colour(double t);
// Blue (t = 0) through white (0.5) to red (1): for differences about zero.
Rgb diverging_colour(double t);

// A vertical colour bar in the box (x0, y0)-(x1, y1), `colour(t)` from lo at the bottom to hi at the
// top, five labelled ticks at its right and the title above.
void colour_bar(Canvas& c, int x0, int y0, int x1, int y1, double lo, double hi, const std::string& title,
                const std::function<Rgb(double)>& colour);

// A tick label: %.3g, with "0" for a value within 1e-12 of the range of zero.
std::string tick_text(double v);

// A plot's area on a canvas, its corners inclusive.
struct Area {
  int x0, y0, x1, y1;
  int w() const { return x1 - x0 + 1; }
  int h() const { return y1 - y0 + 1; }
};

inline const Rgb kInk{20, 20, 20}, kPaper{255, 255, 255}, kNoData{170, 170, 170}, kGround{110, 84, 60};

}  // namespace cv::plots
