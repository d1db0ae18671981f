// Ground images, decoded with stb_image: land albedo from the map's colours and water from GSHHS.
#include "render/albedo_map.hpp"

#include <stb_image.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <utility>
#include <memory>
#include <mutex>

#include <glm/glm.hpp>

namespace cv::render {

namespace {

double srgb_to_linear(double v) { return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4); }

glm::dvec3 linear_of(glm::vec3 srgb255) {
  return {srgb_to_linear(srgb255.x / 255.0), srgb_to_linear(srgb255.y / 255.0), srgb_to_linear(srgb255.z / 255.0)};
}

// The Natural Earth I relief's colours (sampled from the 720 x 360 image over regions of each type:
// Amazon, Congo, taiga; European and American farmland, pampas; Sahel, steppe, outback; Sahara,
// Arabia; tundra and high plateaus; Greenland and Antarctica; the open sea) and the albedo of each
// surface type in red, green and blue (docs/physics.md, "Ground albedo", gives the sources).
constexpr std::array<MapSurfaceEntry, static_cast<std::size_t>(MapSurface::Count)> kSurfaces = {{
    {"forest", {168.0f, 196.0f, 170.0f}, {0.030f, 0.055f, 0.025f}},
    {"grassland and cropland", {228.0f, 231.0f, 189.0f}, {0.070f, 0.090f, 0.045f}},
    {"shrubland, steppe and savanna", {224.0f, 213.0f, 187.0f}, {0.150f, 0.130f, 0.080f}},
    {"sand desert", {241.0f, 234.0f, 214.0f}, {0.420f, 0.320f, 0.210f}},
    {"tundra and bare rock", {218.0f, 220.0f, 212.0f}, {0.140f, 0.130f, 0.110f}},
    {"snow and ice sheet", {229.0f, 235.0f, 243.0f}, {0.880f, 0.920f, 0.940f}},
    {"water (the map's sea)", {122.0f, 172.0f, 207.0f}, {0.0f, 0.0f, 0.0f}},
}};

constexpr std::size_t kWater = static_cast<std::size_t>(MapSurface::Water);
constexpr std::size_t kSnow = static_cast<std::size_t>(MapSurface::Snow);
constexpr double kLightnessScale = 40.0;

// Squared distances of a colour to each type's: chroma (the colour less its mean) over 4 levels,
// lightness (the mean) over 40, so the relief shading moves a colour little. A colour darker than
// the ice sheets' is measured against snow over `snow_darker` levels instead (snow_lightness_scale).
std::array<double, kSurfaces.size()> distances(glm::vec3 c, double snow_darker = kLightnessScale) {
  std::array<double, kSurfaces.size()> d{};
  const double m = (c.x + c.y + c.z) / 3.0;
  for (std::size_t k = 0; k < kSurfaces.size(); ++k) {
    const glm::vec3 a = kSurfaces[k].map_srgb;
    const double ma = (a.x + a.y + a.z) / 3.0;
    const glm::dvec3 dc = (glm::dvec3(c) - m) - (glm::dvec3(a) - ma);
    const double scale = k == kSnow && m < ma ? snow_darker : kLightnessScale;
    d[k] = glm::dot(dc, dc) / (4.0 * 4.0) + (m - ma) * (m - ma) / (scale * scale);
  }
  return d;
}

}  // namespace

const MapSurfaceEntry& map_surface(MapSurface s) { return kSurfaces.at(static_cast<std::size_t>(s)); }

MapSurface nearest_map_surface(glm::vec3 srgb) {
  const auto d = distances(srgb);
  return static_cast<MapSurface>(std::min_element(d.begin(), d.end()) - d.begin());
}

double snow_lightness_scale(double lat_deg) {
  const double a = std::abs(lat_deg);
  if (!(a > 55.0)) return 10.0;  // NaN too
  if (a >= 65.0) return kLightnessScale;
  return 10.0 + (a - 55.0) / 10.0 * (kLightnessScale - 10.0);
}

glm::vec3 land_albedo_of_map_colour(glm::vec3 srgb, double lat_deg) {
  const auto d = distances(srgb, snow_lightness_scale(lat_deg));
  if (std::min_element(d.begin(), d.end()) - d.begin() == static_cast<std::ptrdiff_t>(kWater)) return map_surface(MapSurface::Grass).albedo;
  // Gaussian weights, relative to the nearest land type (so a colour far from all still has one).
  double dmin = 1e300;
  for (std::size_t k = 0; k < kWater; ++k) dmin = std::min(dmin, d[k]);
  glm::dvec3 albedo(0.0);
  double lightness = 0.0, sum = 0.0;
  for (std::size_t k = 0; k < kWater; ++k) {
    const double w = std::exp(-0.5 * (d[k] - dmin));
    const glm::dvec3 lin = linear_of(kSurfaces[k].map_srgb);
    albedo += w * glm::dvec3(kSurfaces[k].albedo);
    lightness += w * (lin.x + lin.y + lin.z);
    sum += w;
  }
  albedo /= sum;
  lightness /= sum;
  const glm::dvec3 lin = linear_of(srgb);
  const double shade = std::clamp((lin.x + lin.y + lin.z) / std::max(lightness, 1e-6), 0.75, 1.25);
  return glm::vec3(glm::min(albedo * shade, glm::dvec3(0.97)));
}

core::AlbedoMap load_albedo_map(const std::string& path, bool map_colours, const std::string& gshhs_dir) {
  int w = 0, h = 0, channels = 0;
  // Read as a regular file of bounded size (a FIFO or /dev/zero would be read forever), its
  // declared size checked against the memory limit before it is decoded.
  std::string bytes;
  try {
    bytes = core::read_regular_file(path, "the ground image", kMaxGroundImageBytes);
  } catch (const core::InputError& e) {
    throw GroundImageError(e.what());
  }
  if (bytes.size() > static_cast<std::size_t>(std::numeric_limits<int>::max())) throw GroundImageError(path + ": the ground image is too large");
  const auto* raw = reinterpret_cast<const stbi_uc*>(bytes.data());
  const int len = static_cast<int>(bytes.size());
  if (stbi_info_from_memory(raw, len, &w, &h, &channels)) {
    try {
      // The decoded image, then the map of four floats per texel.
      core::require_within_memory_limit(path, "the ground image of " + std::to_string(w) + " x " + std::to_string(h) + " pixels",
                                        core::checked_product({static_cast<std::uint64_t>(w), static_cast<std::uint64_t>(h), 3 + 16 + 16}));
    } catch (const core::InputError& e) {
      throw GroundImageError(e.what());
    }
  }
  std::unique_ptr<unsigned char, void (*)(void*)> data(stbi_load_from_memory(raw, len, &w, &h, &channels, 3), stbi_image_free);
  if (!data) {
    throw GroundImageError(path + ": cannot read the ground image (" + stbi_failure_reason() +
                           "), expected an equirectangular PNG or JPEG");
  }
  if (w < 2 || h < 2) throw GroundImageError(path + ": the ground image is " + std::to_string(w) + " x " + std::to_string(h) +
                                             " pixels, expected at least 2 x 2");
  core::AlbedoMap m;
  m.width = w;
  m.height = h;
  const std::size_t n = static_cast<std::size_t>(w) * h;
  m.rgba.assign(4 * n, 0.0f);
  const unsigned char* px = data.get();
  if (map_colours) {
    // The image's sRGB colours as linear albedo, no water: the model before water and land types.
    float lut[256];
    for (int i = 0; i < 256; ++i) lut[i] = static_cast<float>(srgb_to_linear(i / 255.0));
    for (std::size_t i = 0; i < n; ++i) {
      for (int k = 0; k < 3; ++k) m.rgba[4 * i + k] = lut[px[3 * i + k]];
    }
    m.id = core::albedo_map_id(m);
    return m;
  }
  // Land: each colour's surface type. Texels of the map's sea colour take the mean land of their
  // land-coloured neighbours (two passes: coastlines of GSHHS and the map differ by a texel or
  // two), else grass.
  std::vector<char> sea(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    const glm::vec3 c(px[3 * i], px[3 * i + 1], px[3 * i + 2]);
    sea[i] = nearest_map_surface(c) == MapSurface::Water;
    const double lat = 90.0 - (static_cast<double>(i / static_cast<std::size_t>(w)) + 0.5) * 180.0 / h;
    const glm::vec3 a = land_albedo_of_map_colour(c, lat);
    for (int k = 0; k < 3; ++k) m.rgba[4 * i + k] = a[k];
  }
  std::vector<char> unfilled = sea;
  for (int pass = 0; pass < 2; ++pass) {
    std::vector<char> next = unfilled;
    std::vector<float> rgba = m.rgba;
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const std::size_t i = static_cast<std::size_t>(y) * w + x;
        if (!unfilled[i]) continue;
        glm::dvec3 s(0.0);
        int count = 0;
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) {
            const int yy = y + dy;
            if (yy < 0 || yy >= h) continue;
            const std::size_t j = static_cast<std::size_t>(yy) * w + (x + dx + w) % w;
            if (unfilled[j]) continue;
            s += glm::dvec3(m.rgba[4 * j], m.rgba[4 * j + 1], m.rgba[4 * j + 2]);
            ++count;
          }
        }
        if (count == 0) continue;
        for (int k = 0; k < 3; ++k) rgba[4 * i + k] = static_cast<float>(s[k] / count);
        next[i] = 0;
      }
    }
    m.rgba.swap(rgba);
    unfilled.swap(next);
  }
  // Water: the GSHHS shorelines, else (said once per run) the map's sea colour.
  std::optional<WaterFraction> water;
  std::string why = "no GSHHS shorelines under " + gshhs_dir + " (Debian package python-cartopy-data)";
  try {
    water = gshhs_water_fraction(w, h, gshhs_dir);
  } catch (const std::exception& e) {
    why = e.what();
  }
  if (water) {
    for (std::size_t i = 0; i < n; ++i) m.rgba[4 * i + 3] = water->water[i];
  } else {
    static std::once_flag said;
    std::call_once(said, [&] { std::fprintf(stderr, "cloudviewer: %s; water is where the ground image has the map's sea colour\n", why.c_str()); });
    for (std::size_t i = 0; i < n; ++i) m.rgba[4 * i + 3] = sea[i] ? 1.0f : 0.0f;
  }
  m.id = core::albedo_map_id(m);
  return m;
}

std::shared_ptr<const core::AlbedoMap> shared_albedo_map(const std::string& path, bool map_colours) {
  static std::mutex lock;
  static std::map<std::pair<std::string, bool>, std::weak_ptr<const core::AlbedoMap>> loaded;
  std::lock_guard<std::mutex> hold(lock);
  auto& slot = loaded[{path, map_colours}];
  if (auto held = slot.lock()) return held;
  auto map = std::make_shared<const core::AlbedoMap>(load_albedo_map(path, map_colours));
  slot = map;
  return map;
}

std::string resolve_ground_texture(const std::string& setting) {
  if (setting == "none") return "";
  if (!setting.empty()) return setting;
  return std::filesystem::exists(kNaturalEarthRelief) ? kNaturalEarthRelief : "";
}

}  // namespace cv::render
