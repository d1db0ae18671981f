// Several views on the screen (issue 17): each view's accumulated mean drawn into its part of the
// window, tonemapped, by its own Presenter (the single view's draw), in the layout's rectangles
// (views.hpp). The viewer composes the window this way, and the GPU test composes into a texture
// and holds every region to the view drawn alone.
#pragma once

#include <vector>

#include "render/presenter.hpp"
#include "viewer/views.hpp"

namespace cv::viewer {

// Draws view i (presenters[i], tonemapped with tones[i]) into its rectangle of the bound framebuffer
// (width x height pixels), clipped to the part that shows (visible_rect: its side of a swipe divider).
void compose_views(const std::vector<const render::Presenter*>& presenters, const std::vector<render::ToneSettings>& tones,
                   ViewLayout layout, double divider, int width, int height);

}  // namespace cv::viewer
