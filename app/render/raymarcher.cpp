// The GPU raymarcher: texture upload, uniforms, dispatch, read-back.
#include "render/raymarcher.hpp"

#include <algorithm>
#include <cmath>

#include <glm/glm.hpp>

#include "kernel/bindings.glsl"
#include "kernel/march_stats.glsl"
#include "kernel/ms_beam.glsl"
#include "kernel/ms_slab.glsl"
#include "kernel/detail_drift.hpp"
#include "physics/physics.hpp"  // CV_DETAIL_COVERS (shaders/common/detail.glsl)
#include "noise/blue_noise.hpp"
#include "render/albedo_map.hpp"
#include "reference/earth_shadow.hpp"

namespace cv::render {
namespace {
GLint loc(GLuint program, const char* name) { return glGetUniformLocation(program, name); }
}  // namespace

int loop_iterations_per_view_step(const core::MarchSettings& s, int sun_march_steps) {
  // The sun march (cloud_sun_depth): at most sun_march_steps over both segments, never fewer than
  // the 2 sun_steps budgeted before the length limit; 5 for the tests that end its loops.
  const int sun = 3 + 2 + std::max(sun_march_steps, 2 * std::max(s.quality.sun_steps, 0));
  const int air = std::max(s.quality.atmo_sun_steps, 0) + 2;
  const int octaves = 2 * (std::max(s.quality.octaves, 0) + 1);
  const int substeps = s.features.adaptive_steps ? 64 : 1;  // march_substeps divides a step at most 64 times
  // The slab-shaped diffuse light (ms_slab_in_scatter): its harmonics' recurrence (37 iterations)
  // and the table's eight corners (the rest is written out).
  const int slab = s.medium.ms_two_stream && s.medium.ms_slab ? 37 + 8 + 3 : 0;
  return substeps * (1 + sun + air + octaves + slab);
}

int view_steps_per_dispatch(const core::MarchSettings& s, int sun_march_steps) {
  return std::max(1, (kLlvmpipeLoopBudget - kLoopReserve) / loop_iterations_per_view_step(s, sun_march_steps));
}

bool driver_has_loop_budget(const std::string& renderer) {
  // Mesa's gallivm drivers: llvmpipe (and the older softpipe shares the limit through its TGSI path).
  return renderer.find("llvmpipe") != std::string::npos || renderer.find("softpipe") != std::string::npos;
}

int max_view_steps(double r0_m, double top_m, double view_step_m) {
  const double top = std::max(top_m, 0.0);
  const double chord = 2.0 * std::sqrt((r0_m + top) * (r0_m + top) - r0_m * r0_m);
  return static_cast<int>(std::min(std::ceil(chord / view_step_m) + 4.0, 2e9));
}

GpuRaymarcher::GpuRaymarcher(const ShaderLoader& loader) : loader_(loader) {
  const auto* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  loop_budget_ = driver_has_loop_budget(renderer ? renderer : "");
  program_for(kernel::MarchVariant::of(core::MarchSettings{}));  // the default program now: shader errors show at construction
  // The jitter's blue-noise mask, the very array the CPU reference reads (made once per process),
  // fetched texel by texel: a sampler's filtering would blend ranks.
  const core::BlueNoiseMask& mask = core::step_jitter_mask();
  glCreateTextures(GL_TEXTURE_2D, 1, &jitter_mask_);
  glTextureStorage2D(jitter_mask_, 1, GL_R32F, mask.n, mask.n);
  glTextureSubImage2D(jitter_mask_, 0, 0, 0, mask.n, mask.n, GL_RED, GL_FLOAT, mask.values.data());
  check_gl("uploading the blue-noise jitter mask");
}

const GlProgram& GpuRaymarcher::program_for(const kernel::MarchVariant& v) {
  std::unique_ptr<GlProgram>& p = programs_[v.key()];
  if (!p) {
    p = std::make_unique<GlProgram>(
        load_compute(loader_, ShaderLoader::default_shader_dir() / "render" / "raymarch.comp", ShaderFeatures{}, v.defines()));
  }
  return *p;
}

const GlProgram& GpuRaymarcher::path_program_for(const kernel::MarchVariant& v) {
  std::unique_ptr<GlProgram>& p = path_programs_[v.key()];
  if (!p) {
    p = std::make_unique<GlProgram>(
        load_compute(loader_, ShaderLoader::default_shader_dir() / "render" / "pathtrace.comp", ShaderFeatures{}, v.defines()));
  }
  return *p;
}

GpuRaymarcher::~GpuRaymarcher() {
  if (path_sums_) glDeleteBuffers(1, &path_sums_);
  if (path_state_) glDeleteBuffers(1, &path_state_);
  if (path_branches_) glDeleteBuffers(1, &path_branches_);
  if (path_stats_) glDeleteBuffers(1, &path_stats_);
  if (textures_[0]) glDeleteTextures(2, textures_);
  if (state_[0]) glDeleteTextures(4, state_);
  if (ground_) glDeleteTextures(1, &ground_);
  if (jitter_mask_) glDeleteTextures(1, &jitter_mask_);
  if (column_tau_) glDeleteTextures(1, &column_tau_);
  for (GLuint t : ms_) {
    if (t) glDeleteTextures(1, &t);
  }
  if (noise_textures_[0]) glDeleteTextures(2, noise_textures_);
  if (fraction_) glDeleteTextures(1, &fraction_);
  if (detail_table_) glDeleteTextures(1, &detail_table_);
  if (detail_shift_) glDeleteTextures(1, &detail_shift_);
  if (modelled_pyramid_) glDeleteBuffers(1, &modelled_pyramid_);
  if (pyramid_buffer_) glDeleteBuffers(1, &pyramid_buffer_);
  if (stats_buffer_) glDeleteBuffers(1, &stats_buffer_);
  if (ms_beam_buffer_) glDeleteBuffers(1, &ms_beam_buffer_);
  if (ms_slab_buffer_) glDeleteBuffers(1, &ms_slab_buffer_);
  if (params_buffer_) glDeleteBuffers(1, &params_buffer_);
}

void GpuRaymarcher::upload_noise(const core::ErosionNoise& noise) {
  // The noise variant (with the default march switches) is compiled here, not in the first
  // render, so render timings are the march's.
  core::MarchSettings with_noise;
  with_noise.medium.noise_amount = 1.0;
  program_for(kernel::MarchVariant::of(with_noise));
  if (noise_textures_[0]) glDeleteTextures(2, noise_textures_);
  glCreateTextures(GL_TEXTURE_3D, 2, noise_textures_);
  const core::NoiseTexture* tex[2] = {&noise.low, &noise.high};
  for (int i = 0; i < 2; ++i) {
    // Fetched texel by texel (texelFetch) and interpolated with wrap-around in the shader, exactly
    // as the CPU reference does.
    glTextureStorage3D(noise_textures_[i], 1, GL_R32F, tex[i]->n, tex[i]->n, tex[i]->n);
    glTextureSubImage3D(noise_textures_[i], 0, 0, 0, 0, tex[i]->n, tex[i]->n, tex[i]->n, GL_RED, GL_FLOAT,
                        tex[i]->texels.data());
  }
  // The modelled cloud's table over these tiles (threshold, ramp mean per cover and cloud type).
  if (detail_table_) glDeleteTextures(1, &detail_table_);
  detail_table_ = 0;
  detail_values_ = noise.detail;
  if (noise.detail.size() == 2 * (CV_DETAIL_COVERS + 1) * CV_DETAIL_ROWS) {
    glCreateTextures(GL_TEXTURE_2D, 1, &detail_table_);
    glTextureStorage2D(detail_table_, 1, GL_RG32F, CV_DETAIL_COVERS + 1, CV_DETAIL_ROWS);  // rows per cloud type, then its moments
    glTextureSubImage2D(detail_table_, 0, 0, 0, CV_DETAIL_COVERS + 1, CV_DETAIL_ROWS, GL_RG, GL_FLOAT, noise.detail.data());
  }
  check_gl("uploading the erosion noise textures");
}

void GpuRaymarcher::upload(const core::VolumeGrid& grid, const core::GridMeanExtinction& medium) {
  upload(std::make_shared<const core::PreparedVolume>(core::prepare_volume(grid, medium)));
}

void GpuRaymarcher::upload(std::shared_ptr<const core::PreparedVolume> volume) {
  const core::VolumeGrid& grid = volume->grid;
  const core::GridMeanExtinction& medium = volume->extinction;
  GLint max3d = 0;
  glGetIntegerv(GL_MAX_3D_TEXTURE_SIZE, &max3d);
  if (grid.lon_deg.count > max3d || grid.lat_deg.count > max3d || grid.alt_m.count > max3d) {
    throw GlError("the volume is " + std::to_string(grid.lon_deg.count) + " x " + std::to_string(grid.lat_deg.count) + " x " +
                  std::to_string(grid.alt_m.count) + " points; this OpenGL allows " + std::to_string(max3d) +
                  " per side of a 3-D texture: import with --region or --stride");
  }
  if (textures_[0]) glDeleteTextures(2, textures_);
  glCreateTextures(GL_TEXTURE_3D, 2, textures_);
  const std::vector<float>* fields[2] = {&medium.liquid_per_m, &medium.ice_per_m};
  for (int i = 0; i < 2; ++i) {
    // Texels are fetched one by one (texelFetch) and interpolated in the kernel at full precision.
    glTextureStorage3D(textures_[i], 1, GL_R32F, grid.lon_deg.count, grid.lat_deg.count, grid.alt_m.count);
    glTextureSubImage3D(textures_[i], 0, 0, 0, 0, grid.lon_deg.count, grid.lat_deg.count, grid.alt_m.count, GL_RED,
                        GL_FLOAT, fields[i]->data());
  }
  check_gl("uploading the volume's extinction textures");
  // The octave gate's column optical depths (texelFetch: interpolated in the kernel).
  const core::ColumnDepth& columns = volume->columns;
  if (column_tau_) glDeleteTextures(1, &column_tau_);
  glCreateTextures(GL_TEXTURE_2D_ARRAY, 1, &column_tau_);
  // Four channels: the optical depth, the ground's altitude (the layer masks) and the modelled
  // cloud's type memberships (cumuliform, cirriform); a second layer: the ice's optical depth.
  static_assert(core::kColumnMapChannels == 4);
  const int column_layers = static_cast<int>(core::kColumnMapLayers);
  glTextureStorage3D(column_tau_, 1, GL_RGBA32F, columns.nx, columns.ny, column_layers);
  glTextureSubImage3D(column_tau_, 0, 0, 0, 0, columns.nx, columns.ny, column_layers, GL_RGBA, GL_FLOAT, volume->column_maps.data());
  check_gl("uploading the column optical depths");
  column_mask_ = core::MediumMask{};
  // The two-stream source belongs to a time step: built again, at this size, when a march needs it.
  for (GLuint& t : ms_) {
    if (t) glDeleteTextures(1, &t);
    t = 0;
  }
  ms_lateral_ = ms_second_ = false;
  ms_volume_ = nullptr;
  // The modelled cloud's cover: uploaded again when a march needs it, into a texture of this grid's size.
  if (fraction_) glDeleteTextures(1, &fraction_);
  fraction_ = 0;
  fraction_volume_ = nullptr;
  modelled_pyramid_volume_ = nullptr;  // and its brick bounds
  // The pyramid for empty-space skipping and adapted steps, all levels in one buffer.
  std::vector<glm::vec2> packed = volume->pyramid_packed;
  if (packed.empty()) packed.emplace_back(0.0f, 1.0f);  // a buffer must not be empty; u_levels = 0 ignores it
  if (pyramid_buffer_) glDeleteBuffers(1, &pyramid_buffer_);
  glCreateBuffers(1, &pyramid_buffer_);
  glNamedBufferStorage(pyramid_buffer_, static_cast<GLsizeiptr>(packed.size() * sizeof(glm::vec2)), packed.data(), 0);
  check_gl("uploading the extinction pyramid");
  volume_ = std::move(volume);
}

bool GpuRaymarcher::prepare_ground(const core::MarchSettings& s) {
  const bool textured = s.features.globe && !s.medium.ground_texture.empty();
  if (textured && (s.medium.ground_texture != ground_path_ || s.medium.ground_map_colours != ground_map_colours_)) {
    ground_map_ = shared_albedo_map(s.medium.ground_texture, s.medium.ground_map_colours);
    const core::AlbedoMap& map = *ground_map_;
    if (ground_) glDeleteTextures(1, &ground_);
    glCreateTextures(GL_TEXTURE_2D, 1, &ground_);
    glTextureStorage2D(ground_, 1, GL_RGBA32F, map.width, map.height);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    glTextureSubImage2D(ground_, 0, 0, 0, map.width, map.height, GL_RGBA, GL_FLOAT, map.rgba.data());
    check_gl("uploading the ground texture");
    ground_w_ = map.width;
    ground_h_ = map.height;
    ground_path_ = s.medium.ground_texture;
    ground_map_colours_ = s.medium.ground_map_colours;
  }
  return textured;
}

// The march kernel's inputs for a frame, shared by the march and the path tracer: the ground
// texture (loaded once per path and model), the parameters packed into the uniform block, the
// two-stream source when it is used, the noise, the pyramid, the counters and the textures bound.
kernel::MarchParams GpuRaymarcher::bind_inputs(const core::Camera& cam, const core::Sun& sun, const core::MarchSettings& s,
                                               const OpaqueInput& opaque) {
  const core::PreparedVolume& v = *volume_;
  const core::VolumeGrid& grid = v.grid;
  const bool textured = prepare_ground(s);
  // The kernel's parameters, built as the CPU kernel builds them, packed into the uniform block.
  kernel::MarchParams params =
      core::march_params(v, cam, sun, s, textured ? glm::ivec2(ground_w_, ground_h_) : glm::ivec2(0));
  params.u_has_depth = opaque.depth != 0;
  params.u_has_opaque_color = opaque.depth != 0 && opaque.color != 0;
  params.u_tl_count = opaque.layer_distance != 0 && opaque.layer_color != 0 ? opaque.layers : 0;
  // The octave gate's column depths of what the march shows: made again when the mask changes.
  if (const core::MediumMask hidden = core::medium_mask(s); !(hidden == column_mask_)) {
    const std::vector<float> maps = core::column_maps_for(v, hidden);
    glTextureSubImage3D(column_tau_, 0, 0, 0, 0, v.columns.nx, v.columns.ny, static_cast<int>(core::kColumnMapLayers), GL_RGBA, GL_FLOAT,
                        maps.data());
    check_gl("uploading the masked column optical depths");
    column_mask_ = hidden;
  }
  if (s.medium.ms_two_stream) {  // the two-stream source, for this time step and sun
    const core::MsSourceKey key = core::ms_source_key(s, params.u_to_sun, textured ? ground_map_.get() : nullptr);
    if (!ms_[0] || ms_volume_ != &v || !(key == ms_key_)) {
      bool built = true;
      const std::shared_ptr<const core::MsSource> ms = core::ms_source_for(v, key, &built);  // built ahead by the viewer's prefetcher, or now
      const core::MsSource& src = *ms;
      // Two RG32F textures: (I0, I1 up) and, where the columns exchange light, (I1 east, I1 north);
      // both RGBA32F with the higher-order source's fields (core::ms_moments_texels), the second
      // then always made.
      const glm::ivec3 n(grid.lon_deg.count, grid.lat_deg.count, grid.alt_m.count);
      const bool rgba = core::ms_moments_channels(src) == 4;
      if (rgba != ms_rgba_) {
        for (GLuint& tex : ms_) {
          if (tex) glDeleteTextures(1, &tex);
          tex = 0;
        }
      }
      const bool second = rgba || !src.i1e.empty();
      for (int t = 0; t < 2; ++t) {
        if (ms_[t] || (t == 1 && !second)) continue;
        glCreateTextures(GL_TEXTURE_3D, 1, &ms_[t]);
        glTextureStorage3D(ms_[t], 1, rgba ? GL_RGBA32F : GL_RG32F, n.x, n.y, n.z);
      }
      ms_rgba_ = rgba;
      glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
      const std::vector<float> moments = core::ms_moments_texels(src);
      glTextureSubImage3D(ms_[0], 0, 0, 0, 0, n.x, n.y, n.z, rgba ? GL_RGBA : GL_RG, GL_FLOAT, moments.data());
      ms_lateral_ = !src.i1e.empty();
      ms_second_ = second;
      if (second) {
        const std::vector<float> horizontal = core::ms_horizontal_texels(src);
        glTextureSubImage3D(ms_[1], 0, 0, 0, 0, n.x, n.y, n.z, rgba ? GL_RGBA : GL_RG, GL_FLOAT, horizontal.data());
      }
      check_gl("uploading the two-stream source");
      ms_volume_ = &v, ms_key_ = key, ms_build_ms_ = src.build_ms, ms_built_here_ = built;
      ms_lateral_iterations_ = src.lateral_iterations;
      ms_columns_alone_ = src.columns_alone;
      ++ms_count_[built ? 0 : 1];
    }
    params.u_ms_lateral = ms_lateral_;
  }
  // The droplets' beam table (core::ms_peaks, remembered there per droplet size): always bound, since
  // llvmpipe may read it under a mask where the kernel does not use it.
  {
    const core::MsPeaks peaks = s.medium.ms_two_stream ? core::ms_peaks(s) : core::MsPeaks{};
    if (!ms_beam_buffer_) {
      glCreateBuffers(1, &ms_beam_buffer_);
      glNamedBufferStorage(ms_beam_buffer_, static_cast<GLsizeiptr>(sizeof(float) * CV_MS_BEAM_ROWS * CV_MS_BEAM_ANGLES), nullptr,
                           GL_DYNAMIC_STORAGE_BIT);
    }
    if (peaks.beam && peaks.beam != ms_beam_uploaded_) {
      glNamedBufferSubData(ms_beam_buffer_, 0, static_cast<GLsizeiptr>(sizeof(float) * peaks.beam->values.size()),
                           peaks.beam->values.data());
      check_gl("uploading the droplets' beam table");
      ms_beam_uploaded_ = peaks.beam;
    }
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CV_SSBO_MS_BEAM, ms_beam_buffer_);
  }
  // The higher-order source's slab tables (core::ms_slab_tables): always bound too, for the same reason.
  {
    const std::shared_ptr<const std::vector<float>> tables = core::ms_slab_on(s) ? core::ms_slab_tables(s) : nullptr;
    if (!ms_slab_buffer_) {
      glCreateBuffers(1, &ms_slab_buffer_);
      glNamedBufferStorage(ms_slab_buffer_, static_cast<GLsizeiptr>(sizeof(float) * CV_MS_SLAB_TOTAL), nullptr, GL_DYNAMIC_STORAGE_BIT);
    }
    if (tables && tables != ms_slab_uploaded_) {
      glNamedBufferSubData(ms_slab_buffer_, 0, static_cast<GLsizeiptr>(sizeof(float) * tables->size()), tables->data());
      check_gl("uploading the slab tables");
      ms_slab_uploaded_ = tables;
    }
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CV_SSBO_MS_SLAB, ms_slab_buffer_);
  }
  if (s.medium.modelled && params.u_has_fraction && fraction_volume_ != &v) {  // the cover, only when the modelled cloud reads it
    if (!fraction_) {
      glCreateTextures(GL_TEXTURE_3D, 1, &fraction_);
      glTextureStorage3D(fraction_, 1, GL_R32F, grid.lon_deg.count, grid.lat_deg.count, grid.alt_m.count);
    }
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    glTextureSubImage3D(fraction_, 0, 0, 0, 0, grid.lon_deg.count, grid.lat_deg.count, grid.alt_m.count, GL_RED, GL_FLOAT,
                        v.extinction.fraction.data());
    check_gl("uploading the cloud fraction");
    fraction_volume_ = &v;
  }
  if (s.medium.modelled) {  // the detail's wind displacement per level (a few hundred bytes: every frame)
    const std::vector<float> shift = core::detail_shift_texels(v, params);
    if (detail_shift_levels_ != grid.alt_m.count) {
      if (detail_shift_) glDeleteTextures(1, &detail_shift_);
      glCreateTextures(GL_TEXTURE_2D, 1, &detail_shift_);
      glTextureStorage2D(detail_shift_, 1, GL_RG32F, grid.alt_m.count, 1);
      detail_shift_levels_ = grid.alt_m.count;
    }
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    glTextureSubImage2D(detail_shift_, 0, 0, 0, grid.alt_m.count, 1, GL_RG, GL_FLOAT, shift.data());
    check_gl("uploading the detail's wind displacement");
  }
  const kernel::MarchParamsStd140 block = kernel::pack_std140(params);
  if (!params_buffer_) {
    glCreateBuffers(1, &params_buffer_);
    glNamedBufferStorage(params_buffer_, sizeof(block), nullptr, GL_DYNAMIC_STORAGE_BIT);
  }
  glNamedBufferSubData(params_buffer_, 0, sizeof(block), &block);
  glBindBufferBase(GL_UNIFORM_BUFFER, CV_UBO_MARCH, params_buffer_);
  sun_down_ = params.u_sun_down;
  if (s.medium.noise_amount > 0.0 || s.medium.modelled) {
    glBindTextureUnit(CV_TEX_NOISE_LOW, noise_textures_[0]);
    glBindTextureUnit(CV_TEX_NOISE_HIGH, noise_textures_[1]);
  }
  if (!stats_buffer_) {
    glCreateBuffers(1, &stats_buffer_);
    glNamedBufferStorage(stats_buffer_, 2 * kStatCounters * sizeof(GLuint), nullptr, GL_DYNAMIC_STORAGE_BIT);
  }
  const GLuint zeros[2 * kStatCounters] = {};
  glNamedBufferSubData(stats_buffer_, 0, sizeof(zeros), zeros);
  if (s.medium.modelled) {  // the modelled cloud's own brick bounds (core::medium_pyramid), made once per volume and amount
    if (modelled_pyramid_volume_ != &v || modelled_pyramid_amount_ != s.medium.detail_amount) {
      const std::vector<glm::vec2> packed = core::medium_pyramid(v, s, detail_values_);
      if (modelled_pyramid_) glDeleteBuffers(1, &modelled_pyramid_);
      glCreateBuffers(1, &modelled_pyramid_);
      glNamedBufferStorage(modelled_pyramid_, static_cast<GLsizeiptr>(std::max<std::size_t>(packed.size(), 1) * sizeof(glm::vec2)),
                           packed.empty() ? nullptr : packed.data(), 0);
      check_gl("uploading the modelled cloud's brick bounds");
      modelled_pyramid_volume_ = &v, modelled_pyramid_amount_ = s.medium.detail_amount;
    }
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CV_SSBO_PYRAMID, modelled_pyramid_);
  } else {
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CV_SSBO_PYRAMID, pyramid_buffer_);
  }
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CV_SSBO_STATS, stats_buffer_);
  glBindTextureUnit(CV_TEX_DEPTH, opaque.depth);
  glBindTextureUnit(CV_TEX_OPAQUE, opaque.color);
  glBindTextureUnit(CV_TEX_TL_DISTANCE, opaque.layer_distance);
  glBindTextureUnit(CV_TEX_TL_COLOR, opaque.layer_color);
  glBindTextureUnit(CV_TEX_LIQUID, textures_[0]);
  glBindTextureUnit(CV_TEX_ICE, textures_[1]);
  glBindTextureUnit(CV_TEX_GROUND, ground_);
  glBindTextureUnit(CV_TEX_JITTER_MASK, jitter_mask_);
  glBindTextureUnit(CV_TEX_COLUMN_TAU, column_tau_);
  glBindTextureUnit(CV_TEX_MS_MOMENTS, ms_[0]);
  glBindTextureUnit(CV_TEX_MS_HORIZONTAL, ms_second_ ? ms_[1] : ms_[0]);  // unread without the light between columns or the slab
  glBindTextureUnit(CV_TEX_FRACTION, fraction_);
  glBindTextureUnit(CV_TEX_DETAIL_TABLE, detail_table_);
  glBindTextureUnit(CV_TEX_DETAIL_SHIFT, detail_shift_);
  return params;
}

void GpuRaymarcher::render_into(GLuint out, const core::Camera& cam, const core::Sun& sun, const core::MarchSettings& s,
                                const DispatchOptions& dispatch, const OpaqueInput& opaque) {
  if (!volume_) throw GlError("render needs upload() first");
  const bool noise = s.medium.noise_amount > 0.0;
  if (noise && !noise_textures_[0]) throw GlError("noise_amount > 0 needs upload_noise() first");
  if (noise && !(s.medium.noise_scale_m > 0.0)) throw GlError("noise_scale_m must be > 0");
  if (s.medium.modelled && !detail_table_) throw GlError("cloud_model modelled needs upload_noise() first");
  if (!(s.quality.view_step_m > 0.0)) throw GlError("view_step_m must be > 0");
  kernel::MarchVariant variant = kernel::MarchVariant::of(s);
  variant.translucent = opaque.layers > 0 && opaque.layer_distance != 0 && opaque.layer_color != 0;
  const GLuint p = program_for(variant).id();
  const kernel::MarchParams params = bind_inputs(cam, sun, s, opaque);
  const core::PreparedVolume& v = *volume_;
  const core::VolumeGrid& grid = v.grid;
  const double r0 = grid.earth_radius_m;
  const glm::dvec3 to_sun = params.u_to_sun;
  if (!state_[0] || state_w_ != cam.width || state_h_ != cam.height) {
    if (state_[0]) glDeleteTextures(4, state_);
    glCreateTextures(GL_TEXTURE_2D, 4, state_);
    glTextureStorage2D(state_[0], 1, GL_RGBA32F, cam.width, cam.height);
    glTextureStorage2D(state_[1], 1, GL_RGBA32F, cam.width, cam.height);
    glTextureStorage2D(state_[2], 1, GL_R32F, cam.width, cam.height);  // the cloud depth, kept after the frame
    glTextureStorage2D(state_[3], 1, GL_R32F, cam.width, cam.height);  // the two-stream's scaled view transmittance
    state_w_ = cam.width;
    state_h_ = cam.height;
  }
  glBindImageTexture(CV_IMAGE_OUT, out, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
  glBindImageTexture(CV_IMAGE_STATE_L, state_[0], 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
  glBindImageTexture(CV_IMAGE_STATE_DEPTH, state_[1], 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
  glBindImageTexture(CV_IMAGE_CLOUD_DEPTH, state_[2], 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32F);
  glBindImageTexture(CV_IMAGE_STATE_MS, state_[3], 0, GL_FALSE, 0, GL_READ_WRITE, GL_R32F);
  glUseProgram(p);
  const int tile = dispatch.rows_per_tile > 0 ? (dispatch.rows_per_tile + 7) / 8 * 8 : cam.height;
  GLuint query = 0;
  if (dispatch.gpu_seconds) glCreateQueries(GL_TIME_ELAPSED, 1, &query);
  // On llvmpipe the march goes in ranges of view steps, one dispatch each, then the air and the
  // ground: no dispatch exceeds its loop budget (see loop_iterations_per_view_step). Other drivers
  // have no such budget and march every step in one dispatch.
  const double top_m = v.layer.empty ? grid.alt_m.last() : v.layer.top_m;
  const int total_steps = max_view_steps(r0, top_m, s.quality.view_step_m);
  const int chunk = loop_budget_ ? view_steps_per_dispatch(s, core::max_sun_march_steps(s.quality.sun_steps, params.u_sun_step_max, r0,
                                                                                        v.layer.bottom_m, top_m,
                                                                                        core::smallest_sun_cosine(grid, to_sun)))
                                 : total_steps;
  glProgramUniform1i(p, loc(p, "u_step_count"), chunk);
  for (int row = 0; row < cam.height; row += tile) {
    const int rows = std::min(tile, cam.height - row);
    glProgramUniform1i(p, loc(p, "u_row_offset"), row);
    if (query) glBeginQuery(GL_TIME_ELAPSED, query);
    const auto groups_x = static_cast<GLuint>((cam.width + 7) / 8), groups_y = static_cast<GLuint>((rows + 7) / 8);
    glProgramUniform1i(p, loc(p, "u_pass"), 0);
    for (int begin = 0; begin < total_steps; begin += chunk) {
      glProgramUniform1i(p, loc(p, "u_step_begin"), begin);
      glDispatchCompute(groups_x, groups_y, 1);
      glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
    }
    glProgramUniform1i(p, loc(p, "u_pass"), 1);
    glDispatchCompute(groups_x, groups_y, 1);
    if (query) {
      glEndQuery(GL_TIME_ELAPSED);
      GLuint64 ns = 0;
      glGetQueryObjectui64v(query, GL_QUERY_RESULT, &ns);  // waits for this tile
      *dispatch.gpu_seconds += static_cast<double>(ns) * 1e-9;
    }
    if (dispatch.on_tile) {
      glFinish();  // progress means finished rows, not queued ones
      dispatch.on_tile(row + rows, cam.height);
    }
  }
  if (query) glDeleteQueries(1, &query);
  // Readers either fetch texels (the viewer's accumulation) or read the image back.
  glMemoryBarrier(GL_TEXTURE_UPDATE_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT |
                  GL_BUFFER_UPDATE_BARRIER_BIT);
  stats_read_ = false;
  check_gl("running the raymarcher");
}

void GpuRaymarcher::read_stats() {
  static_assert(kStatCounters == CV_STAT_COUNT, "the Stats buffer holds every counter of march_stats.glsl");
  GLuint counts[2 * kStatCounters] = {};
  glGetNamedBufferSubData(stats_buffer_, 0, sizeof(counts), counts);
  auto count = [&](int k) { return (std::uint64_t(counts[2 * k + 1]) << 32) | counts[2 * k]; };
  stats_ = core::MarchStats{};
  stats_.view_samples = count(0), stats_.view_skipped = count(1), stats_.bricks_jumped = count(2);
  stats_.sun_samples = count(3), stats_.sun_skipped = count(4), stats_.rays_missed = count(5);
  stats_.sun_down = sun_down_;
  stats_.octave_terms = count(6), stats_.octave_terms_full = count(7);
}

void GpuRaymarcher::trace_paths(core::MonteCarloImage& img, const core::Camera& cam, const core::Sun& sun,
                                const core::MarchSettings& s, int spp, const PathTraceSettings& pt, PathTraceStats* extra,
                                const std::function<void(int, int)>& on_samples, const OpaqueInput& opaque) {
  if (!volume_) throw GlError("trace_paths needs upload() first");
  if (pt.max_bounces < 1) throw GlError("the path tracer needs max_bounces >= 1");
  if (s.medium.modelled && !detail_table_) throw GlError("cloud_model modelled needs upload_noise() first");
  const bool noise = s.medium.noise_amount > 0.0;
  if (noise && !noise_textures_[0]) throw GlError("noise_amount > 0 needs upload_noise() first");
  const std::size_t n = static_cast<std::size_t>(cam.width) * static_cast<std::size_t>(cam.height);
  if (img.sum.empty() && img.spp == 0) {
    img.width = cam.width, img.height = cam.height;
    img.sum.assign(n, glm::dvec3(0.0)), img.sum_sq.assign(n, glm::dvec3(0.0));
    img.lum_sum.assign(n, 0.0), img.lum_sq.assign(n, 0.0);
  }
  if (img.width != cam.width || img.height != cam.height || img.sum.size() != n) {
    throw GlError("trace_paths: the accumulator was not made for this camera");
  }
  if (spp <= 0) return;
  // The globe, the air (sunlight through it and the sky as an environment light) and the noise
  // change the path; the rest is the march's.
  kernel::MarchVariant variant;
  variant.globe = s.features.globe;
  variant.atmosphere = s.features.atmosphere;
  variant.noise = noise;
  variant.layer_mask = kernel::MarchVariant::of(s).layer_mask;  // a height band shown alone
  variant.modelled = s.medium.modelled;
  const GLuint p = path_program_for(variant).id();
  core::MarchSettings paths = s;  // the paths scatter for themselves: no two-stream source is built for them
  paths.medium.ms_two_stream = false;
  // The overlays' geometry only with its radiance: the paths have no alpha to hand a caller.
  OpaqueInput shown = opaque;
  if (shown.color == 0) shown.depth = 0;
  bind_inputs(cam, sun, paths, shown);
  if (!path_sums_ || path_pixels_ != n) {
    if (path_sums_) glDeleteBuffers(1, &path_sums_);
    if (path_state_) glDeleteBuffers(1, &path_state_);
    glCreateBuffers(1, &path_sums_);
    glNamedBufferStorage(path_sums_, static_cast<GLsizeiptr>(n * 2 * sizeof(glm::vec4)), nullptr, GL_DYNAMIC_STORAGE_BIT);
    glCreateBuffers(1, &path_state_);  // PathState between dispatches (pathtrace.comp), five vec4 per pixel
    glNamedBufferStorage(path_state_, static_cast<GLsizeiptr>(n * 5 * sizeof(glm::vec4)), nullptr, 0);
    path_pixels_ = n;
  }
  // The branch stacks: as many slots as asked for that a storage buffer of the driver holds for
  // the whole image, and at most 4 GB (the shader indexes floats with 32 bits); at least one float,
  // so the binding is never empty.
  GLint64 max_block = 0;
  glGetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &max_block);
  max_block = std::min<GLint64>(max_block, GLint64(1) << 32);
  constexpr std::size_t kBranchFloats = 10;
  const std::size_t per_slot = n * kBranchFloats * sizeof(float);
  const int slots = static_cast<int>(std::min<std::size_t>(static_cast<std::size_t>(std::max(0, pt.branch_slots)),
                                                           static_cast<std::size_t>(std::max<GLint64>(max_block, 0)) / per_slot));
  const std::size_t branch_floats = std::max<std::size_t>(1, n * kBranchFloats * static_cast<std::size_t>(slots));
  if (!path_branches_ || path_branch_floats_ != branch_floats) {
    if (path_branches_) glDeleteBuffers(1, &path_branches_);
    glCreateBuffers(1, &path_branches_);
    glNamedBufferStorage(path_branches_, static_cast<GLsizeiptr>(branch_floats * sizeof(float)), nullptr, 0);
    path_branch_floats_ = branch_floats;
  }
  if (extra) extra->branch_slots = slots;
  constexpr int kPathStats = 12;
  if (!path_stats_) {
    glCreateBuffers(1, &path_stats_);
    glNamedBufferStorage(path_stats_, 2 * kPathStats * sizeof(GLuint), nullptr, GL_DYNAMIC_STORAGE_BIT);
  }
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CV_SSBO_PATH_SUMS, path_sums_);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CV_SSBO_PATH_STATS, path_stats_);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CV_SSBO_PATH_STATE, path_state_);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CV_SSBO_PATH_BRANCHES, path_branches_);
  glUseProgram(p);
  glProgramUniform1ui(p, loc(p, "u_seed"), pt.seed);
  glProgramUniform1i(p, loc(p, "u_row_offset"), 0);
  // The modelled cloud exceeds the data inside its shapes: its own bound, and not the pyramid's
  // brick bounds (the data's). Float rounding of the fetch stays within the counted 1e-5.
  const double majorant = core::medium_majorant(*volume_, s, detail_values_);
  if (!std::isfinite(majorant)) throw GlError("the modelled cloud has extinction where the cloud fraction is 0: no majorant bounds it");
  glProgramUniform1f(p, loc(p, "u_track_majorant"), static_cast<float>(majorant));
  glProgramUniform1i(p, loc(p, "u_track_bricks"), pt.brick_majorants ? 1 : 0);
  glProgramUniform1i(p, loc(p, "u_path_max_bounces"), pt.max_bounces);
  glProgramUniform1i(p, loc(p, "u_path_roulette_after"), pt.roulette_after);
  glProgramUniform1i(p, loc(p, "u_path_peak_mis"), pt.peak_mis ? 1 : 0);
  glProgramUniform1i(p, loc(p, "u_loop_budget"), loop_budget_ ? 1 : 0);
  glProgramUniform1i(p, loc(p, "u_path_branch_slots"), slots);
  const auto groups_x = static_cast<GLuint>((cam.width + 7) / 8), groups_y = static_cast<GLuint>((cam.height + 7) / 8);
  const int batch = std::max(1, pt.samples_per_readback);
  std::vector<glm::vec4> sums(2 * n);
  const GLuint zero_stats[2 * kPathStats] = {};
  int done = 0;
  while (done < spp) {
    const int k = std::min(batch, spp - done);
    glClearNamedBufferData(path_sums_, GL_RGBA32F, GL_RGBA, GL_FLOAT, nullptr);
    glNamedBufferSubData(path_stats_, 0, sizeof(zero_stats), zero_stats);
    for (int i = 0; i < k; ++i) {
      // Pass 0 starts sample img.spp + i in every pixel; pass 1 resumes the paths still in flight
      // (on llvmpipe a path stops between vertices before the loop budget) until none is.
      glProgramUniform1ui(p, loc(p, "u_sample"), static_cast<GLuint>(img.spp + static_cast<std::uint64_t>(i)));
      for (int pass = 0;; ++pass) {
        const GLuint zero2[2] = {0, 0};
        glNamedBufferSubData(path_stats_, 2 * 10 * sizeof(GLuint), sizeof(zero2), zero2);
        glProgramUniform1i(p, loc(p, "u_pass"), pass == 0 ? 0 : 1);
        glDispatchCompute(groups_x, groups_y, 1);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
        GLuint in_flight = 0;
        glGetNamedBufferSubData(path_stats_, 2 * 10 * sizeof(GLuint), sizeof(GLuint), &in_flight);
        if (in_flight == 0) break;
        if (extra) ++extra->resumed_dispatches;
      }
    }
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    glGetNamedBufferSubData(path_sums_, 0, static_cast<GLsizeiptr>(sums.size() * sizeof(glm::vec4)), sums.data());
    GLuint st[2 * kPathStats] = {};
    glGetNamedBufferSubData(path_stats_, 0, sizeof(st), st);
    check_gl("running the path tracer");
    for (std::size_t i = 0; i < n; ++i) {
      const glm::vec4 a = sums[2 * i], b = sums[2 * i + 1];
      img.sum[i] += glm::dvec3(a), img.lum_sum[i] += a.w;
      img.sum_sq[i] += glm::dvec3(b), img.lum_sq[i] += b.w;
    }
    auto counter = [&](int c) { return static_cast<std::uint64_t>(st[2 * c]) | static_cast<std::uint64_t>(st[2 * c + 1]) << 32; };
    img.stats.paths += counter(0);
    img.stats.scatterings += counter(1);
    img.stats.null_collisions += counter(2);
    img.stats.shadow_lookups += counter(3);
    img.stats.truncated += counter(4);
    img.stats.roulette_killed += counter(5);
    img.stats.peak_samples += counter(6);
    img.stats.majorant_exceeded += counter(7);
    if (extra) extra->near_loop_budget += counter(8), extra->non_finite += counter(9), extra->splits_without_room += counter(11);
    img.spp += static_cast<std::uint64_t>(k);
    done += k;
    if (on_samples) on_samples(done, spp);
  }
}

const core::MarchStats& GpuRaymarcher::last_stats() {
  // Read on demand: reading waits for the march, which the viewer should not do every frame.
  if (!stats_read_ && stats_buffer_) {
    read_stats();
    stats_read_ = true;
  }
  return stats_;
}

std::vector<float> GpuRaymarcher::read_cloud_depth() const {
  std::vector<float> depth(static_cast<std::size_t>(state_w_) * state_h_);
  if (state_[2]) {
    glGetTextureImage(state_[2], 0, GL_RED, GL_FLOAT, static_cast<GLsizei>(depth.size() * sizeof(float)), depth.data());
  }
  return depth;
}

std::vector<glm::vec4> GpuRaymarcher::render(const core::Camera& cam, const core::Sun& sun, const core::MarchSettings& s,
                                             const DispatchOptions& dispatch, const OpaqueInput& opaque) {
  // The read-back takes its byte count as a GLsizei.
  if (static_cast<double>(cam.width) * cam.height * sizeof(glm::vec4) >= 2147483647.0) {
    throw GlError("an image of " + std::to_string(cam.width) + " x " + std::to_string(cam.height) +
                  " pixels is too large to read back at once (at most 134 million pixels)");
  }
  GLuint out = 0;
  glCreateTextures(GL_TEXTURE_2D, 1, &out);
  glTextureStorage2D(out, 1, GL_RGBA32F, cam.width, cam.height);
  render_into(out, cam, sun, s, dispatch, opaque);
  std::vector<glm::vec4> pixels(static_cast<std::size_t>(cam.width) * cam.height);
  glGetTextureImage(out, 0, GL_RGBA, GL_FLOAT, static_cast<GLsizei>(pixels.size() * sizeof(glm::vec4)), pixels.data());
  glDeleteTextures(1, &out);
  read_stats();
  check_gl("running the raymarcher");
  return pixels;
}

}  // namespace cv::render
