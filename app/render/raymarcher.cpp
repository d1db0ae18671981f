// The GPU raymarcher: texture upload, uniforms, dispatch, read-back.
#include "render/raymarcher.hpp"

#include <algorithm>
#include <cmath>

#include <glm/glm.hpp>

#include "geo/geodesy.hpp"
#include "noise/blue_noise.hpp"
#include "render/albedo_map.hpp"
#include "physics/physics.hpp"
#include "reference/earth_shadow.hpp"
#include "volume/column_depth.hpp"
#include "volume/sampler.hpp"

namespace cv::render {
namespace {
GLint loc(GLuint program, const char* name) { return glGetUniformLocation(program, name); }
void set3(GLuint p, const char* n, const glm::dvec3& v) {
  glProgramUniform3f(p, loc(p, n), static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z));
}
}  // namespace

int loop_iterations_per_view_step(const core::MarchSettings& s, int sun_march_steps) {
  // The sun march (cloud_sun_depth): at most sun_march_steps over both segments, never fewer than
  // the 2 sun_steps budgeted before the length limit; 5 for the tests that end its loops.
  const int sun = 3 + 2 + std::max(sun_march_steps, 2 * std::max(s.sun_steps, 0));
  const int air = std::max(s.atmo_sun_steps, 0) + 2;
  const int octaves = 2 * (std::max(s.octaves, 0) + 1);
  const int substeps = s.adaptive_steps ? 64 : 1;  // march_substeps divides a step at most 64 times
  return substeps * (1 + sun + air + octaves);
}

int view_steps_per_dispatch(const core::MarchSettings& s, int sun_march_steps) {
  return std::max(1, (kLlvmpipeLoopBudget - kLoopReserve) / loop_iterations_per_view_step(s, sun_march_steps));
}

int max_view_steps(double r0_m, double top_m, double view_step_m) {
  const double top = std::max(top_m, 0.0);
  const double chord = 2.0 * std::sqrt((r0_m + top) * (r0_m + top) - r0_m * r0_m);
  return static_cast<int>(std::min(std::ceil(chord / view_step_m) + 4.0, 2e9));
}

GpuRaymarcher::GpuRaymarcher(const ShaderLoader& loader) : loader_(loader) {
  program_for(core::MarchSettings{});  // the default program now: shader errors show at construction
  // The jitter's blue-noise mask, the very array the CPU reference reads (made once per process),
  // fetched texel by texel: a sampler's filtering would blend ranks.
  const core::BlueNoiseMask& mask = core::step_jitter_mask();
  glCreateTextures(GL_TEXTURE_2D, 1, &jitter_mask_);
  glTextureStorage2D(jitter_mask_, 1, GL_R32F, mask.n, mask.n);
  glTextureSubImage2D(jitter_mask_, 0, 0, 0, mask.n, mask.n, GL_RED, GL_FLOAT, mask.values.data());
  check_gl("uploading the blue-noise jitter mask");
}

const GlProgram& GpuRaymarcher::program_for(const core::MarchSettings& s) {
  const bool noise = s.noise_amount > 0.0;
  std::unique_ptr<GlProgram>& p = programs_[noise ? 1 : 0][s.skip_empty ? 1 : 0][s.adaptive_steps ? 1 : 0]
                                           [s.atmosphere ? 1 : 0][s.globe ? 1 : 0];
  if (!p) {
    p = std::make_unique<GlProgram>(load_compute(loader_, ShaderLoader::default_shader_dir() / "render" / "raymarch.comp",
                                                 noise ? ShaderFeatures{ShaderFeature::NoiseDetail} : ShaderFeatures{},
                                                 {{"CV_SKIP_EMPTY", s.skip_empty ? "1" : "0"},
                                                  {"CV_ADAPTIVE", s.adaptive_steps ? "1" : "0"},
                                                  {"CV_ATMOSPHERE", s.atmosphere ? "1" : "0"},
                                                  {"CV_GLOBE", s.globe ? "1" : "0"}}));
  }
  return *p;
}

GpuRaymarcher::~GpuRaymarcher() {
  if (textures_[0]) glDeleteTextures(2, textures_);
  if (ground_) glDeleteTextures(1, &ground_);
  if (jitter_mask_) glDeleteTextures(1, &jitter_mask_);
  if (column_tau_) glDeleteTextures(1, &column_tau_);
  if (noise_textures_[0]) glDeleteTextures(2, noise_textures_);
  if (pyramid_buffer_) glDeleteBuffers(1, &pyramid_buffer_);
  if (stats_buffer_) glDeleteBuffers(1, &stats_buffer_);
}

void GpuRaymarcher::upload_noise(const core::ErosionNoise& noise) {
  // The noise variant (with the default march switches) is compiled here, not in the first
  // render, so render timings are the march's.
  core::MarchSettings with_noise;
  with_noise.noise_amount = 1.0;
  program_for(with_noise);
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
  check_gl("uploading the erosion noise textures");
}

void GpuRaymarcher::upload(const core::VolumeGrid& grid, const core::GridMeanExtinction& medium) {
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
    // Texels are fetched one by one (texelFetch) and interpolated in the shader at full precision.
    glTextureStorage3D(textures_[i], 1, GL_R32F, grid.lon_deg.count, grid.lat_deg.count, grid.alt_m.count);
    glTextureSubImage3D(textures_[i], 0, 0, 0, 0, grid.lon_deg.count, grid.lat_deg.count, grid.alt_m.count, GL_RED,
                        GL_FLOAT, fields[i]->data());
  }
  check_gl("uploading the volume's extinction textures");
  // The octave gate's column optical depths, once per volume (texelFetch: interpolated in the shader).
  const core::ColumnDepth columns = core::column_depth(grid, medium.liquid_per_m, medium.ice_per_m);
  if (column_tau_) glDeleteTextures(1, &column_tau_);
  glCreateTextures(GL_TEXTURE_2D, 1, &column_tau_);
  glTextureStorage2D(column_tau_, 1, GL_R32F, columns.nx, columns.ny);
  glTextureSubImage2D(column_tau_, 0, 0, 0, columns.nx, columns.ny, GL_RED, GL_FLOAT, columns.tau.data());
  check_gl("uploading the column optical depths");
  grid_ = grid;
  layer_ = core::cloud_layer(grid, medium);
  sigma_max_ = core::largest_extinction(medium);
  // The pyramid for empty-space skipping and adapted steps, all levels in one buffer.
  pyramid_ = core::ExtinctionPyramid(grid, medium.liquid_per_m, medium.ice_per_m);
  std::vector<glm::vec2> packed;
  for (const auto& l : pyramid_.levels()) packed.insert(packed.end(), l.min_max.begin(), l.min_max.end());
  if (packed.empty()) packed.emplace_back(0.0f, 1.0f);  // a buffer must not be empty; u_levels = 0 ignores it
  if (pyramid_buffer_) glDeleteBuffers(1, &pyramid_buffer_);
  glCreateBuffers(1, &pyramid_buffer_);
  glNamedBufferStorage(pyramid_buffer_, static_cast<GLsizeiptr>(packed.size() * sizeof(glm::vec2)), packed.data(), 0);
  check_gl("uploading the extinction pyramid");
}

void GpuRaymarcher::render_into(GLuint out, const core::Camera& cam, const core::Sun& sun, const core::MarchSettings& s,
                                const DispatchOptions& dispatch) {
  const bool noise = s.noise_amount > 0.0;
  if (noise && !noise_textures_[0]) throw GlError("noise_amount > 0 needs upload_noise() first");
  if (noise && !(s.noise_scale_m > 0.0)) throw GlError("noise_scale_m must be > 0");
  if (!(s.view_step_m > 0.0)) throw GlError("view_step_m must be > 0");
  const GLuint p = program_for(s).id();
  const core::CameraFrame c = core::camera_frame(cam);
  const double r0 = grid_.earth_radius_m;
  glProgramUniform2i(p, loc(p, "u_size"), cam.width, cam.height);
  set3(p, "u_cam_ecef", geo::sphere_to_ecef({cam.lat_deg, cam.lon_deg, cam.alt_m}, r0));
  glProgramUniform1f(p, loc(p, "u_cam_alt"), static_cast<float>(cam.alt_m));
  set3(p, "u_cam_up", geo::sphere_enu(cam.lat_deg, cam.lon_deg).up);
  set3(p, "u_forward", c.forward);
  set3(p, "u_right", c.right);
  set3(p, "u_upv", c.up);
  glProgramUniform1f(p, loc(p, "u_tan_half"), static_cast<float>(c.tan_half));
  const glm::dvec3 to_sun = glm::normalize(geo::sphere_to_ecef({sun.subsolar_lat_deg, sun.subsolar_lon_deg, 0.0}, r0));
  set3(p, "u_to_sun", to_sun);
  // Night over the whole cloud layer: decided here once, in double, with a margin (earth_shadow.hpp).
  sun_down_ = s.leave_out_night && core::layer_in_earth_shadow(grid_, layer_, to_sun);
  glProgramUniform1i(p, loc(p, "u_sun_down"), sun_down_ ? 1 : 0);
  set3(p, "u_irradiance", sun.irradiance);
  glProgramUniform1f(p, loc(p, "u_r0"), static_cast<float>(r0));
  set3(p, "u_grid_start", {grid_.lon_deg.start, grid_.lat_deg.start, grid_.alt_m.start});
  set3(p, "u_grid_step", {grid_.lon_deg.step, grid_.lat_deg.step, grid_.alt_m.step});
  set3(p, "u_grid_count", {double(grid_.lon_deg.count), double(grid_.lat_deg.count), double(grid_.alt_m.count)});
  std::vector<float> unused;
  glProgramUniform1i(p, loc(p, "u_wraps"), grid_.wraps_lon() ? 1 : 0);
  glProgramUniform1i(p, loc(p, "u_global_lat"), core::VolumeSampler(grid_, unused).global_lat() ? 1 : 0);
  glProgramUniform1f(p, loc(p, "u_view_step"), static_cast<float>(s.view_step_m));
  glProgramUniform2f(p, loc(p, "u_layer"), static_cast<float>(layer_.bottom_m), static_cast<float>(layer_.top_m));
  glProgramUniform1i(p, loc(p, "u_cloudless"), layer_.empty ? 1 : 0);
  glProgramUniform1i(p, loc(p, "u_sun_steps"), s.sun_steps);
  glProgramUniform1f(p, loc(p, "u_sigma_max"), static_cast<float>(sigma_max_));
  glProgramUniform1f(p, loc(p, "u_sun_step_tau"), static_cast<float>(s.max_sun_step_optical_depth));
  const double sun_step_max_m = core::sun_step_limit_m(grid_, layer_, s);
  glProgramUniform1f(p, loc(p, "u_sun_step_max"), static_cast<float>(sun_step_max_m));
  glProgramUniform1i(p, loc(p, "u_octaves"), s.octaves);
  set3(p, "u_octave_abc", {s.octave_a, s.octave_b, s.octave_c});
  glProgramUniform1i(p, loc(p, "u_octave_gate"), s.octave_gate ? 1 : 0);
  glProgramUniform1f(p, loc(p, "u_droplet_um"), static_cast<float>(s.droplet_diameter_um));
  glProgramUniform1i(p, loc(p, "u_liquid_phase_hg"), s.liquid_phase_hg ? 1 : 0);
  glProgramUniform1f(p, loc(p, "u_ice_g"), static_cast<float>(s.ice_g));
  glProgramUniform1i(p, loc(p, "u_frame"), s.frame);
  glProgramUniform1i(p, loc(p, "u_blue_noise"), s.blue_noise ? 1 : 0);
  if (noise) {
    const core::NoiseAnchor a = core::noise_anchor(core::grid_centre_ecef(grid_), s.noise_scale_m);
    set3(p, "u_noise_anchor", a.ecef_m);  // float-exact by construction
    set3(p, "u_noise_anchor_frac", a.frac);
    glProgramUniform1f(p, loc(p, "u_noise_period"), static_cast<float>(s.noise_scale_m));
    glProgramUniform1f(p, loc(p, "u_noise_amount"), static_cast<float>(s.noise_amount));
    glBindTextureUnit(3, noise_textures_[0]);
    glBindTextureUnit(4, noise_textures_[1]);
  }
  glProgramUniform1f(p, loc(p, "u_ambient"), static_cast<float>(s.ambient));
  glProgramUniform1i(p, loc(p, "u_sky_steps"), s.sky_steps);
  glProgramUniform1i(p, loc(p, "u_atmo_sun_steps"), s.atmo_sun_steps);
  set3(p, "u_ground_albedo", s.ground_albedo);
  const bool textured = s.globe && !s.ground_texture.empty();
  if (textured && s.ground_texture != ground_path_) {
    const core::AlbedoMap map = load_albedo_map(s.ground_texture);
    if (ground_) glDeleteTextures(1, &ground_);
    glCreateTextures(GL_TEXTURE_2D, 1, &ground_);
    glTextureStorage2D(ground_, 1, GL_RGB32F, map.width, map.height);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    glTextureSubImage2D(ground_, 0, 0, 0, map.width, map.height, GL_RGB, GL_FLOAT, map.rgb.data());
    check_gl("uploading the ground albedo texture");
    ground_w_ = map.width;
    ground_h_ = map.height;
    ground_path_ = s.ground_texture;
  }
  glProgramUniform2i(p, loc(p, "u_ground_size"), textured ? ground_w_ : 0, textured ? ground_h_ : 0);
  glProgramUniform1f(p, loc(p, "u_max_step_tau"), static_cast<float>(s.max_step_optical_depth));
  glProgramUniform1f(p, loc(p, "u_min_t"), static_cast<float>(s.min_transmittance));
  glProgramUniform1f(p, loc(p, "u_sun_tau_limit"),
                     static_cast<float>(std::min(3.0e38, physics::f64::sun_march_tau_limit(s.octaves, s.octave_a, s.min_transmittance))));
  const auto& levels = pyramid_.levels();
  GLint bricks[3 * core::ExtinctionPyramid::kMaxLevels] = {}, nodes[core::ExtinctionPyramid::kMaxLevels] = {},
        offsets[core::ExtinctionPyramid::kMaxLevels] = {};
  GLint offset = 0;
  for (std::size_t l = 0; l < levels.size(); ++l) {
    bricks[3 * l] = levels[l].nx, bricks[3 * l + 1] = levels[l].ny, bricks[3 * l + 2] = levels[l].nz;
    nodes[l] = levels[l].nodes;
    offsets[l] = offset;
    offset += static_cast<GLint>(levels[l].min_max.size());
  }
  glProgramUniform1i(p, loc(p, "u_levels"), static_cast<GLint>(levels.size()));
  glProgramUniform3iv(p, loc(p, "u_bricks"), core::ExtinctionPyramid::kMaxLevels, bricks);
  glProgramUniform1iv(p, loc(p, "u_level_nodes"), core::ExtinctionPyramid::kMaxLevels, nodes);
  glProgramUniform1iv(p, loc(p, "u_level_offset"), core::ExtinctionPyramid::kMaxLevels, offsets);
  if (!stats_buffer_) {
    glCreateBuffers(1, &stats_buffer_);
    glNamedBufferStorage(stats_buffer_, 2 * kStatCounters * sizeof(GLuint), nullptr, GL_DYNAMIC_STORAGE_BIT);
  }
  const GLuint zeros[2 * kStatCounters] = {};
  glNamedBufferSubData(stats_buffer_, 0, sizeof(zeros), zeros);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, pyramid_buffer_);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 4, stats_buffer_);
  if (!state_[0] || state_w_ != cam.width || state_h_ != cam.height) {
    if (state_[0]) glDeleteTextures(2, state_);
    glCreateTextures(GL_TEXTURE_2D, 2, state_);
    for (GLuint t : state_) glTextureStorage2D(t, 1, GL_RGBA32F, cam.width, cam.height);
    state_w_ = cam.width;
    state_h_ = cam.height;
  }
  glBindImageTexture(0, out, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
  glBindImageTexture(6, state_[0], 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
  glBindImageTexture(7, state_[1], 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
  glBindTextureUnit(1, textures_[0]);
  glBindTextureUnit(2, textures_[1]);
  glBindTextureUnit(5, ground_);  // 3 and 4 are the noise textures
  glBindTextureUnit(6, jitter_mask_);
  glBindTextureUnit(7, column_tau_);
  glUseProgram(p);
  const int tile = dispatch.rows_per_tile > 0 ? (dispatch.rows_per_tile + 7) / 8 * 8 : cam.height;
  GLuint query = 0;
  if (dispatch.gpu_seconds) glCreateQueries(GL_TIME_ELAPSED, 1, &query);
  // The march goes in ranges of view steps, one dispatch each, then the air and the ground: no
  // dispatch exceeds llvmpipe's loop budget (see loop_iterations_per_view_step).
  const double top_m = layer_.empty ? grid_.alt_m.last() : layer_.top_m;
  const int total_steps = max_view_steps(r0, top_m, s.view_step_m);
  const int chunk = view_steps_per_dispatch(
      s, core::max_sun_march_steps(s.sun_steps, core::sun_step_limit_m(grid_, layer_, s), r0, layer_.bottom_m, top_m,
                                   core::smallest_sun_cosine(grid_, to_sun)));
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
  GLuint counts[2 * kStatCounters] = {};
  glGetNamedBufferSubData(stats_buffer_, 0, sizeof(counts), counts);
  auto count = [&](int k) { return (std::uint64_t(counts[2 * k + 1]) << 32) | counts[2 * k]; };
  stats_ = core::MarchStats{};
  stats_.view_samples = count(0), stats_.view_skipped = count(1), stats_.bricks_jumped = count(2);
  stats_.sun_samples = count(3), stats_.sun_skipped = count(4), stats_.rays_missed = count(5);
  stats_.sun_down = sun_down_;
  stats_.octave_terms = count(6), stats_.octave_terms_full = count(7);
}

const core::MarchStats& GpuRaymarcher::last_stats() {
  // Read on demand: reading waits for the march, which the viewer should not do every frame.
  if (!stats_read_ && stats_buffer_) {
    read_stats();
    stats_read_ = true;
  }
  return stats_;
}

std::vector<glm::vec4> GpuRaymarcher::render(const core::Camera& cam, const core::Sun& sun, const core::MarchSettings& s,
                                             const DispatchOptions& dispatch) {
  // The read-back takes its byte count as a GLsizei.
  if (static_cast<double>(cam.width) * cam.height * sizeof(glm::vec4) >= 2147483647.0) {
    throw GlError("an image of " + std::to_string(cam.width) + " x " + std::to_string(cam.height) +
                  " pixels is too large to read back at once (at most 134 million pixels)");
  }
  GLuint out = 0;
  glCreateTextures(GL_TEXTURE_2D, 1, &out);
  glTextureStorage2D(out, 1, GL_RGBA32F, cam.width, cam.height);
  render_into(out, cam, sun, s, dispatch);
  std::vector<glm::vec4> pixels(static_cast<std::size_t>(cam.width) * cam.height);
  glGetTextureImage(out, 0, GL_RGBA, GL_FLOAT, static_cast<GLsizei>(pixels.size() * sizeof(glm::vec4)), pixels.data());
  glDeleteTextures(1, &out);
  read_stats();
  check_gl("running the raymarcher");
  return pixels;
}

}  // namespace cv::render
