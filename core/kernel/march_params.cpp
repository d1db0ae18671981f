// Packing the march parameters for the GPU, and the program variant of a march's settings.
#include "kernel/march_params.hpp"

#include "settings/march_settings.hpp"

namespace cv::kernel {

namespace params {
MarchParamsStd140 pack_std140(const MarchParams& p) {
  MarchParamsStd140 o{};
#define CV_PARAM(T, name) o.name = std140::Map<T>::convert(p.name);
#define CV_PARAM_ARRAY(T, name, N) \
  for (int i = 0; i < (N); ++i) o.name[i] = std140::Map<T>::convert(p.name[i]);
#include "kernel/march_params.glsl"
#undef CV_PARAM
#undef CV_PARAM_ARRAY
  return o;
}
}  // namespace params

MarchVariant MarchVariant::of(const core::MarchSettings& s) {
  MarchVariant v;
  v.noise = s.medium.noise_amount > 0.0;
  v.skip_empty = s.features.skip_empty;
  v.adaptive = s.features.adaptive_steps;
  v.atmosphere = s.features.atmosphere;
  v.globe = s.features.globe;
  v.two_stream = s.medium.ms_two_stream;
  v.layer_mask = core::layer_band_set(s);
  v.tint = core::tint_set(s);
  v.modelled = s.medium.modelled;
  v.slab = s.medium.ms_two_stream && s.medium.ms_slab;
  return v;
}

unsigned MarchVariant::key() const {
  return (noise ? 1u : 0u) | (skip_empty ? 2u : 0u) | (adaptive ? 4u : 0u) | (atmosphere ? 8u : 0u) | (globe ? 16u : 0u) |
         (two_stream ? 32u : 0u) | (translucent ? 64u : 0u) | (layer_mask ? 128u : 0u) | (tint ? 256u : 0u) |
         (modelled ? 512u : 0u) | (slab ? 1024u : 0u);
}

std::vector<std::pair<std::string, std::string>> MarchVariant::defines() const {
  auto b = [](bool on) { return std::string(on ? "1" : "0"); };
  return {{"CV_NOISE", b(noise)}, {"CV_SKIP_EMPTY", b(skip_empty)}, {"CV_ADAPTIVE", b(adaptive)},
          {"CV_ATMOSPHERE", b(atmosphere)}, {"CV_GLOBE", b(globe)}, {"CV_TWO_STREAM", b(two_stream)},
          {"CV_TRANSLUCENT", b(translucent)}, {"CV_LAYER_MASK", b(layer_mask)}, {"CV_TINT", b(tint)},
          {"CV_MODELLED", b(modelled)}, {"CV_MS_SLAB_SHAPE", b(slab)}};
}

}  // namespace cv::kernel
