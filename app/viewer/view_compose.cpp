// Several views on the screen: each Presenter draws into its rectangle (view_compose.hpp).
#include "viewer/view_compose.hpp"

#include <stdexcept>

namespace cv::viewer {

void compose_views(const std::vector<const render::Presenter*>& presenters, const std::vector<render::ToneSettings>& tones,
                   ViewLayout layout, double divider, int width, int height) {
  const int n = static_cast<int>(presenters.size());
  if (tones.size() != presenters.size()) throw std::invalid_argument("compose_views: one tone per view expected");
  const std::vector<ViewRect> rects = view_rects(layout, n, width, height);
  for (int i = 0; i < n; ++i) {
    const ViewRect r = rects[static_cast<std::size_t>(i)];
    const ViewRect v = visible_rect(layout, n, i, width, height, divider);
    if (v.w <= 0 || v.h <= 0) continue;
    // GL's window rows run bottom up; the rectangles' top down.
    const std::array<int, 4> clip = {v.x, height - v.y - v.h, v.w, v.h};
    presenters[static_cast<std::size_t>(i)]->draw(tones[static_cast<std::size_t>(i)], r.x, height - r.y - r.h, r.w, r.h,
                                                  v == r ? std::nullopt : std::optional<std::array<int, 4>>(clip));
  }
}

}  // namespace cv::viewer
