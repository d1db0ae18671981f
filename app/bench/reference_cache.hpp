// The benchmark's Monte Carlo references on disk: the running sums, not just the mean, so a
// reference can be extended by more samples later (or resumed after an interruption) and gives the
// same image, bit for bit, as if it had been rendered in one go.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>

#include "bench/standard_scenes.hpp"
#include "reference/monte_carlo.hpp"

namespace cv::core {}

namespace cv::bench {
// The bench works on core's types throughout (it was core::bench before it moved up to app/).
using namespace cv::core;

// File layout (native byte order, doubles): "CVREF2\n", uint64 key, int32 width, int32 height,
// uint64 spp, 7 uint64 MonteCarloStats counters, then per pixel sum (rgb), sum_sq (rgb), lum_sum,
// lum_sq, each as one array over all pixels.
//
// Reads `path` into `img` when it holds a reference of this key and size. Returns false, with the
// reason in *why, when the file is missing, of another key or size, or cut short (a bad cache file
// is never fatal: the caller renders afresh).
bool read_reference_cache(const std::string& path, std::uint64_t key, int width, int height, MonteCarloImage& img,
                          std::string* why = nullptr);
// Writes atomically (a temporary file renamed over the old one): an interrupted run keeps the last
// complete state. Throws std::runtime_error naming the file when it cannot be written.
void write_reference_cache(const std::string& path, std::uint64_t key, const MonteCarloImage& img);

// FNV-1a, 64 bit, of a text: the key of everything that decides a reference.
std::uint64_t reference_key_hash(const std::string& text);

// Everything that decides a standard scene's reference image under march settings `m` and Monte
// Carlo settings `mc`, as text (the medium enters through a checksum).
std::string reference_key(const StandardScene& sc, const GridMeanExtinction& medium, const MarchSettings& m,
                          const MonteCarloSettings& mc);

struct ExtendedReference {
  MonteCarloImage img;
  std::string path;              // the cache file
  std::uint64_t cached_spp = 0;  // samples per pixel read from it
  double seconds = 0.0;          // to render the samples added in this call
};

// The reference of scene `name` (sc, or a variant of it such as "<scene>+modelled") at the
// camera's size: read from `dir` when a file there holds it (ref_<name>_<W>x<H>_<key>.cvref), then
// extended to `spp` samples per pixel, or until its mean relative standard error is at most
// `ref_error` when that is above 0, in chunks of about 10 s, each saved atomically as it is done
// (so `bench` and the benchmark programs share references and an interrupted one resumes).
// Progress goes to `log`. A cache file of other settings or size is rendered afresh and replaced.
ExtendedReference extend_reference(const std::string& dir, const std::string& name, const StandardScene& sc,
                                   const GridMeanExtinction& medium, const MarchSettings& m,
                                   const MonteCarloSettings& mc, int spp, double ref_error,
                                   const ErosionNoise* noise, std::FILE* log);

}  // namespace cv::bench
