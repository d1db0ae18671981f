// The machine a timing belongs to: the GL renderer, vendor and version, without how the context
// was made (a window and a headless context on one GPU time the same).
#pragma once

#include <string>

#include "render/context.hpp"

namespace cv::render {

inline std::string machine_id(const GlInfo& info) { return info.renderer + " by " + info.vendor + " (" + info.version + ")"; }

}  // namespace cv::render
