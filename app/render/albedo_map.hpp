// Loading the globe's ground: an equirectangular image (the Natural Earth relief from Debian's
// python-cartopy-data) decoded with stb_image into land albedo and water fraction for the GPU and
// the CPU reference alike.
#pragma once

#include <memory>
#include <stdexcept>
#include <string>

#include <glm/vec3.hpp>

#include "frame/albedo_map.hpp"
#include "io/input_file.hpp"
#include "render/land_sea_mask.hpp"

namespace cv::render {

// Where python-cartopy-data installs the Natural Earth relief (720 x 360, lon -180..180).
constexpr const char* kNaturalEarthRelief = "/usr/share/cartopy/data/raster/natural_earth/50-natural-earth-1-downsampled.png";

// A ground image that cannot be used (not an image, too small): bad input, one line naming the file.
class GroundImageError : public core::InputError {
 public:
  using core::InputError::InputError;
};
// Ground images larger than this are refused before they are decoded.
inline constexpr std::uint64_t kMaxGroundImageBytes = 512u << 20;

// Decodes an 8-bit image (PNG, JPEG, ...) into the globe's ground. map_colours (ground_model "map"):
// its sRGB colours decoded to linear albedo everywhere, no water. Otherwise ("physical"): the water
// fraction from the GSHHS shorelines under gshhs_dir (gshhs_water_fraction; where they are not
// installed, said once on stderr, the texels of the map's own sea colour are water), and each land
// colour the albedo of the surface type it paints (land_albedo_of_map_colour). Throws
// GroundImageError naming the file and what was wrong.
core::AlbedoMap load_albedo_map(const std::string& path, bool map_colours = false, const std::string& gshhs_dir = kGshhsDir);

// The surface types the Natural Earth relief paints, each with its map colour and albedo
// (docs/physics.md, "Ground albedo").
enum class MapSurface { Forest, Grass, Shrub, Desert, Tundra, Snow, Water, Count };
struct MapSurfaceEntry {
  const char* name;
  glm::vec3 map_srgb;  // the map's colour for it, 0..255
  glm::vec3 albedo;    // linear albedo, red 0.67, green 0.55, blue 0.47 um
};
const MapSurfaceEntry& map_surface(MapSurface s);

// The nearest surface type of a map colour (8-bit sRGB, 0..255), by its chroma first and its
// lightness second (the map's relief shading changes lightness).
MapSurface nearest_map_surface(glm::vec3 srgb);

// The land albedo a map colour (8-bit sRGB, 0..255) stands for: the surface types' albedos blended
// by the colour's closeness to theirs, times the colour's lightness against theirs (the relief
// shading) within 0.75..1.25; at most 0.97. Every result lies in the span of the types' albedos
// widened by that factor. A colour nearest the map's sea colour stands for no land: grass (the
// loader gives such texels the land of their neighbours where they have any). A colour darker than
// the ice sheets' is read as snow only as far as the latitude allows (snow_lightness_scale).
glm::vec3 land_albedo_of_map_colour(glm::vec3 srgb, double lat_deg);

// How many levels of 255 below the ice sheets' lightness a map colour may lie and still be read as
// snow, by latitude: 40 (as every other type) poleward of 65 degrees, 10 equatorward of 55, linear
// between. The relief paints high ground the same grey-blue at 33 N (the Tibetan plateau, free of
// snow most of the year) and at 80 N (Ellesmere Island, under snow ten months); the colour cannot
// tell them apart, the latitude can (docs/physics.md, "The ground: land albedo and water").
double snow_lightness_scale(double lat_deg);

// load_albedo_map(path, map_colours) shared: a map still held by someone (the renderer, the
// viewer's prefetcher) is not loaded again. Throws as load_albedo_map does.
std::shared_ptr<const core::AlbedoMap> shared_albedo_map(const std::string& path, bool map_colours);

// The texture a scene's ground_texture setting names: empty means the Natural Earth relief where it
// is installed (else the constant albedo), "none" the constant albedo, anything else is a path.
std::string resolve_ground_texture(const std::string& setting);

}  // namespace cv::render
