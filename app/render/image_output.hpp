// Turning linear radiance into pictures: exposure and a filmic tonemap to 8-bit sRGB PNG, and the
// linear values themselves as PFM (float) for analysis. Both written atomically.
#pragma once

#include <cstdio>
#include <string>
#include <optional>
#include <vector>

#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

namespace cv::render {

struct ToneSettings {
  double exposure = 1.0;                                     // radiance multiplier before the curve
  // Seen through the clouds' transmittance in the tonemapped image only: linear output (PFM) is
  // the radiance alone.
  glm::dvec3 background{0.015, 0.02, 0.035};
};

// Bilinear upscaling of an iw x ih image (rgb radiance, a transmittance; rows top to bottom) to
// ow x oh in linear radiance, pixel centres mapped onto texel centres and clamped at the edges; a
// weight of 0 takes the nearer texel alone. Written in float exactly as the viewer's present.frag,
// so the viewer shows what `render` writes.
std::vector<glm::vec4> upscale_linear(const std::vector<glm::vec4>& in, int iw, int ih, int ow, int oh);

// The automatic exposure of a linear image (rgb radiance; a is not used): the exposure that puts
// the 99th percentile of the luminance of its lit pixels (Rec. 709 luminance > 0, finite) at 0.8 on
// the filmic curve, so the brightest cloud tops are bright without clipping and a stray hot pixel
// (the top 1 %) does not darken the rest. An image with no lit pixel gets kDefaultExposure.
inline constexpr double kDefaultExposure = 4.0;
double auto_exposure(const std::vector<glm::vec4>& linear);
// The same, or nothing when the image has no lit pixel (night over the whole frame).
std::optional<double> auto_exposure_if_lit(const std::vector<glm::vec4>& linear);

// A sequence of n frames (a time series, a flyover) is exposed once for all its frames, so it does
// not flicker and frame ranges rendered apart match. Its automatic exposure is the least of the
// automatic exposures of these frames: the first, the last and three evenly between (all of them
// when n <= 5), so the brightest of them sets it and a sequence that begins at dawn is not washed
// out by midday. Frames with no lit pixel are left out; none lit: kDefaultExposure.
std::vector<int> exposure_probe_frames(int n);
double sequence_exposure(const std::vector<std::optional<double>>& probe_exposures);

// Throws std::runtime_error "WHAT: N of M pixels came out not finite (the first at x X, y Y),
// expected finite radiance; nothing written" when any channel of a pixel is NaN or infinite, so
// that a wrong image is never written (rows top to bottom, `width` pixels each).
void check_finite_pixels(const std::vector<glm::vec4>& pixels, int width, const std::string& what);

// rgb = radiance, a = transmittance, rows top to bottom; composited over the background.
std::vector<unsigned char> tonemap_srgb8(const std::vector<glm::vec4>& pixels, const ToneSettings& tone);
void write_png(const std::string& path, int width, int height, const std::vector<unsigned char>& rgb8);
// The same files' contents into an open stream (an OutputFile or a member of an OutputGroup);
// core::WriteError when the stream fails.
void encode_png(std::FILE* f, int width, int height, const std::vector<unsigned char>& rgb8);
// Whether `path` is a PNG that decodes whole at width x height (a frame a stopped run finished:
// frames are written atomically, so this catches files damaged or written by something else).
bool png_decodes_at_size(const std::string& path, int width, int height);
void encode_pfm(std::FILE* f, int width, int height, const std::vector<glm::vec4>& pixels);
void encode_pfm_transmittance(std::FILE* f, int width, int height, const std::vector<glm::vec4>& pixels);
// Portable float map ("PF", 3 channels): the linear radiance alone, nothing composited behind it
// (rgb of `pixels`; no background, no exposure).
void write_pfm(const std::string& path, int width, int height, const std::vector<glm::vec4>& pixels);
// One-channel portable float map ("Pf"): the transmittance, what shows through to whatever stands
// behind the image (a of `pixels`: the clouds' and the air's; 0 where the globe or opaque geometry
// shows).
void write_pfm_transmittance(const std::string& path, int width, int height, const std::vector<glm::vec4>& pixels);
// Where write_pfm_transmittance goes beside a radiance PFM: "out.pfm" -> "out.transmittance.pfm".
std::string transmittance_pfm_path(const std::string& radiance_pfm);

}  // namespace cv::render
