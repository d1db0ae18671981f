// Checks a viewer screenshot is not blank: clouds present means a spread of pixel values and many
// pixels away from the empty-sky colour. Usage: screenshot_check FILE.png [--same-as OTHER.png]; with
// --same-as it also requires every channel within one 8-bit step of OTHER (e.g. `render`'s image).
#include <stb_image.h>

#include <cmath>
#include <cstdio>
#include <algorithm>
#include <set>
#include <string>
#include <vector>

#include "render/image_output.hpp"

int main(int argc, char** argv) {
  if (argc != 2 && !(argc == 4 && std::string(argv[2]) == "--same-as")) {
    std::fprintf(stderr, "usage: screenshot_check FILE.png [--same-as OTHER.png]\n");
    return 2;
  }
  int w = 0, h = 0, n = 0;
  unsigned char* px = stbi_load(argv[1], &w, &h, &n, 3);
  if (!px) {
    std::fprintf(stderr, "%s: cannot read the PNG (%s)\n", argv[1], stbi_failure_reason());
    return 1;
  }
  // The empty-sky colour as the viewer draws it: no radiance, full transmittance, exposure 4.
  cv::render::ToneSettings tone;
  tone.exposure = 4.0;
  const std::vector<unsigned char> sky = cv::render::tonemap_srgb8({glm::vec4(0.0f, 0.0f, 0.0f, 1.0f)}, tone);
  double sum = 0.0, sum2 = 0.0;
  std::set<int> levels;
  long away = 0;
  const long count = static_cast<long>(w) * h;
  for (long i = 0; i < count; ++i) {
    const unsigned char* p = px + i * 3;
    const double y = 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
    sum += y;
    sum2 += y * y;
    levels.insert(static_cast<int>(y));
    away += std::abs(p[0] - sky[0]) + std::abs(p[1] - sky[1]) + std::abs(p[2] - sky[2]) > 24;
  }
  if (argc == 4) {
    int w2 = 0, h2 = 0;
    unsigned char* other = stbi_load(argv[3], &w2, &h2, &n, 3);
    if (!other || w2 != w || h2 != h) {
      std::fprintf(stderr, "%s: cannot read it, or it is not %d x %d\n", argv[3], w, h);
      return 1;
    }
    int worst = 0;
    for (long i = 0; i < count * 3; ++i) worst = std::max(worst, std::abs(int(px[i]) - int(other[i])));
    stbi_image_free(other);
    std::printf("largest channel difference from %s: %d\n", argv[3], worst);
    if (worst > 1) {
      std::fprintf(stderr, "%s differs from %s by up to %d steps (expected at most 1)\n", argv[1], argv[3], worst);
      return 1;
    }
  }
  stbi_image_free(px);
  const double mean = sum / count, sd = std::sqrt(std::max(0.0, sum2 / count - mean * mean));
  const double away_frac = static_cast<double>(away) / count;
  std::printf("%s: %d x %d, luma mean %.1f sd %.1f, %zu distinct levels, %.1f %% of pixels away from the sky colour\n",
              argv[1], w, h, mean, sd, levels.size(), 100.0 * away_frac);
  const bool ok = sd > 10.0 && levels.size() >= 32 && away_frac > 0.05;
  if (!ok) std::fprintf(stderr, "%s looks blank: expected luma sd > 10, >= 32 levels and > 5 %% non-sky pixels\n", argv[1]);
  return ok ? 0 : 1;
}
