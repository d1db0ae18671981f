// OpenEXR output: the linear radiance and its coverage in one file for compositing.
#pragma once

#include <glm/vec4.hpp>

#include <cstdio>
#include <string>
#include <vector>

namespace cv::render {

// An OpenEXR image (scan lines, ZIP-compressed, 32-bit float channels) of `pixels` (rgb = linear
// radiance, a = transmittance, rows top to bottom): R, G, B the radiance alone (no background, no
// exposure, as --pfm writes it) and, when `with_alpha`, A = 1 - transmittance, so that the file is
// premultiplied as compositing expects it: the image over a plate is RGB + (1 - A) x plate, the
// same sum the renderer makes with its background. What A covers is what the frame drew: with the
// globe and the air (the defaults) A is 1 over the ground and the air's own light is in R, G, B;
// clouds alone over a plate want --no-sky (or render.march.globe and .atmosphere off). Without
// alpha (the path tracer estimates no transmittance) R, G, B alone. Into an open stream (an OutputFile or a member of an OutputGroup,
// so the file is written atomically); core::WriteError when the stream fails.
void encode_exr(std::FILE* f, int width, int height, const std::vector<glm::vec4>& pixels, bool with_alpha);

// The channels of an OpenEXR file read back as float (tests, checks): width, height and each
// channel named in `names` (a channel the file lacks is an error, as is a data window beyond
// 16384 pixels a side, refused before anything is allocated), rows top to bottom.
struct ExrImage {
  int width = 0, height = 0;
  std::vector<std::string> channels;  // every channel the file holds, sorted by name
  std::vector<std::vector<float>> values;  // per name asked for
};
ExrImage read_exr(const std::string& path, const std::vector<std::string>& names);

// Whether `path` is an OpenEXR file that reads whole at width x height with R, G, B (and A when
// `alpha`): a frame a stopped run finished (frames are written atomically, so this catches files
// damaged or written by something else).
bool exr_decodes_at_size(const std::string& path, int width, int height, bool alpha);

}  // namespace cv::render
