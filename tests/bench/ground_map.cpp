// Loads a ground image as the globe sees it (render::load_albedo_map) and writes what it became:
// OUT_albedo.png (the land albedo, sRGB-encoded, water drawn black) and OUT_water.png (the water
// fraction, white = water), with the time the load took and the water's share of the texels.
//   bench_ground_map [IMAGE] [OUT_PREFIX]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "render/albedo_map.hpp"
#include "render/image_output.hpp"

int main(int argc, char** argv) {
  using namespace cv;
  const std::string image = argc > 1 ? argv[1] : render::kNaturalEarthRelief;
  const std::string out = argc > 2 ? argv[2] : "ground";
  try {
    const auto t0 = std::chrono::steady_clock::now();
    const core::AlbedoMap m = render::load_albedo_map(image);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    const std::size_t n = static_cast<std::size_t>(m.width) * m.height;
    std::vector<unsigned char> albedo(3 * n), water(3 * n);
    double wet = 0.0;
    auto enc = [](double v) {
      v = std::clamp(v, 0.0, 1.0);
      return static_cast<unsigned char>(std::lround(255.0 * (v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055)));
    };
    for (std::size_t i = 0; i < n; ++i) {
      const float w = m.rgba[4 * i + 3];
      wet += w;
      for (int k = 0; k < 3; ++k) {
        albedo[3 * i + k] = enc((1.0 - w) * m.rgba[4 * i + k]);
        water[3 * i + k] = static_cast<unsigned char>(std::lround(255.0 * w));
      }
    }
    render::write_png(out + "_albedo.png", m.width, m.height, albedo);
    render::write_png(out + "_water.png", m.width, m.height, water);
    std::printf("%s: %d x %d, loaded in %.0f ms, water %.1f %% of the texels; wrote %s_albedo.png, %s_water.png\n", image.c_str(),
                m.width, m.height, ms, 100.0 * wet / static_cast<double>(n), out.c_str(), out.c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  }
  return 0;
}
