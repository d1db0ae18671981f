// The GPU raymarcher (shaders/render/raymarch.comp): uploads a volume's grid-mean extinction as 3-D
// textures and renders a camera's view into linear radiance and transmittance, the same quantities
// as the CPU reference (core/reference/raymarcher).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <memory>
#include <vector>

#include <glm/vec4.hpp>

#include "kernel/march_params.hpp"
#include "kernel/march_limits.hpp"
#include "kernel/ms_source.hpp"
#include "kernel/prepared_volume.hpp"
#include "noise/noise.hpp"
#include "reference/monte_carlo.hpp"
#include "frame/camera.hpp"
#include "frame/march_stats.hpp"
#include "frame/sun.hpp"
#include "settings/march_settings.hpp"
#include "render/shader_loader.hpp"

namespace cv::render {

// How a render is dispatched: in tiles of rows, so that a long frame reports progress (and no
// single dispatch runs long enough to trip a driver's watchdog), and how long the march took on
// the GPU. The default is one dispatch for the whole image.
struct DispatchOptions {
  int rows_per_tile = 0;  // 0: the whole image at once; otherwise rounded up to the 8-row workgroup
  std::function<void(int rows_done, int rows_total)> on_tile;  // after each tile has finished
  double* gpu_seconds = nullptr;  // if set, the dispatches' GPU time (GL_TIME_ELAPSED queries) is added
};

// Opaque geometry drawn by another pass, for the march to stop at (shaders/kernel/march.glsl): an
// R32F texture of the image's size holding the distance (m) from the camera along each pixel's ray
// (0: none there), and optionally an RGBA32F texture of the geometry's radiance, which the march then
// composites behind the clouds and the air (alpha 0); without it alpha is the transmittance in front
// of the geometry, for the caller to composite. 0: no such texture.
struct OpaqueInput {
  GLuint depth = 0;
  GLuint color = 0;
  // Translucent fragments (core::OpaqueLayer's layers): `layers` per pixel side by side in
  // R32F (distance) and RGBA32F (radiance, alpha) textures layers x width wide; 0: none.
  GLuint layer_distance = 0;
  GLuint layer_color = 0;
  int layers = 0;
};

// Mesa's llvmpipe lets the loops of one shader invocation run 65 535 iterations in all
// (LP_MAX_TGSI_LOOP_ITERATIONS, shared by every loop and never reset); past it, each loop runs its
// body once and stops, without an error. Other drivers have no such limit.
inline constexpr int kLlvmpipeLoopBudget = 65535;

// An upper bound on the loop iterations one view step of raymarch.comp costs on llvmpipe: the step
// itself, the sun march (sun_march_steps over its two shell segments: core::max_sun_march_steps,
// at least 2 sun_steps), the atmosphere's transmittance
// toward the sun (two loops, atmo_sun_steps in all) and the two octave sums, times the substeps a
// step may take with adaptive steps. Every loop counts one iteration more than its trip count (the
// test that ends it), and a loop that no lane needs still runs once (llvmpipe executes masked code).
int loop_iterations_per_view_step(const core::MarchSettings& settings, int sun_march_steps);

// Whether a driver (its GL_RENDERER string) has that loop budget: only then is the march split
// into dispatches of view_steps_per_dispatch steps.
bool driver_has_loop_budget(const std::string& renderer);

// How many view steps one dispatch of the march takes: the budget, less kLoopReserve for the loops
// outside the steps (the two shell segments, the counters), over the bound above.
inline constexpr int kLoopReserve = 1024;
int view_steps_per_dispatch(const core::MarchSettings& settings, int sun_march_steps);

// At most how many view steps any ray takes through a cloud shell whose top is top_m above the
// sphere of radius r0_m: a ray that stays above the ground spends at most the chord of the top
// sphere tangent to the ground inside it, one that meets the ground less; two per segment for
// rounding up.
int max_view_steps(double r0_m, double top_m, double view_step_m);

// The GPU path tracer's settings (shaders/render/pathtrace.comp), as the CPU Monte Carlo's
// (core::MonteCarloSettings): the same path, in float.
struct PathTraceSettings {
  int max_bounces = 1000;
  int roulette_after = 4;
  bool peak_mis = true;
  // The pyramid's brick bounds as majorants instead of the volume's largest extinction: far fewer
  // tentative collisions in a large domain (on the sample at 32x18, 4 spp: 0.43 million null
  // collisions against 5.8), so a vertex fits in llvmpipe's loop budget (on the towering cell a
  // vertex against the global majorant took more than 45 000 iterations 11 times at 16x9, 48 spp).
  bool brick_majorants = true;
  std::uint32_t seed = 1;
  int samples_per_readback = 16;  // samples summed in float on the GPU before the host adds them in double
  // Branches of the droplets' peak a pixel's stack holds (the CPU's is unbounded; docs/physics.md,
  // "Splitting on the GPU"): ten floats each per pixel. Fewer where the driver's largest storage
  // buffer cannot hold them for the whole image; 0: no splitting.
  int branch_slots = 16;
};

// What the path tracer did beyond core::MonteCarloStats: samples left out as not finite, and, on a
// driver with a loop budget (llvmpipe), the dispatches that resumed paths stopped before it, and
// walks that still came near it within one dispatch (one vertex of ~45 000 iterations; such a
// path may have been cut short).
struct PathTraceStats {
  std::uint64_t non_finite = 0;
  std::uint64_t near_loop_budget = 0;
  std::uint64_t resumed_dispatches = 0;
  std::uint64_t splits_without_room = 0;  // vertices that found the pixel's branch stack full
  int branch_slots = 0;                    // the stack's size the paths were traced with
};

class GpuRaymarcher {
 public:
  // Needs a current OpenGL 4.5 context; compiles the raymarcher. Keeps a reference to the loader
  // (for the noise variant, compiled later), which must outlive it.
  explicit GpuRaymarcher(const ShaderLoader& loader);
  ~GpuRaymarcher();
  GpuRaymarcher(const GpuRaymarcher&) = delete;
  GpuRaymarcher& operator=(const GpuRaymarcher&) = delete;

  // Uploads one prepared time step (replacing the previous one), keeping it for the frame's parameters.
  void upload(std::shared_ptr<const core::PreparedVolume> volume);
  // Prepares a time step and uploads it.
  void upload(const core::VolumeGrid& grid, const core::GridMeanExtinction& medium);

  // Uploads the erosion noise textures and compiles the noise variant of the raymarcher: needed
  // before a render with settings.noise_amount > 0, not done otherwise.
  void upload_noise(const core::ErosionNoise& noise);

  // Loads and uploads the ground texture the settings name (globe on and a ground_texture), unless
  // it is the one already uploaded; returns whether the frame is textured. A render does this
  // itself; a caller that times its frames calls it first, so that the one-time load (the image,
  // and the GSHHS shorelines rasterised into the water fraction) is not counted as frame time.
  // A file that cannot be read throws GroundImageError.
  bool prepare_ground(const core::MarchSettings& settings);

  // Renders: rgb = radiance, a = view transmittance (0 where the globe shows), rows top to bottom.
  // With noise_amount 0 the program without the noise code runs and the noise textures are not
  // bound. With settings.globe and a ground_texture, the image is loaded (once per path and ground
  // model) with load_albedo_map; a file that cannot be read throws GroundImageError.
  std::vector<glm::vec4> render(const core::Camera& cam, const core::Sun& sun, const core::MarchSettings& settings,
                                const DispatchOptions& dispatch = {}, const OpaqueInput& opaque = {});

  // Renders into `out`, an RGBA32F 2-D texture of at least cam.width x cam.height that stays on
  // the GPU (the viewer draws and accumulates it there; nothing is read back).
  void render_into(GLuint out, const core::Camera& cam, const core::Sun& sun, const core::MarchSettings& settings,
                   const DispatchOptions& dispatch = {}, const OpaqueInput& opaque = {});

  // Adds `spp` path-traced samples per pixel of cam's view into img (made by core::MonteCarloRenderer's
  // start() for this camera, or empty of the camera's size), continuing its sample indices. The
  // path is the CPU Monte Carlo's (shaders/kernel/path.glsl): clouds and the globe's ground (the
  // ground texture's land albedo and water, else the constant albedo); with the air on, sunlight
  // reddened by it, the sky as an environment light and the haze in front of the first vertex.
  // on_samples(done, spp) after each readback. `opaque` (the overlays, drawn for this camera) ends
  // each view ray at its geometry with the geometry's radiance, and its translucent fragments
  // composite in front of the ray's first vertex, as the march composites them.
  void trace_paths(core::MonteCarloImage& img, const core::Camera& cam, const core::Sun& sun,
                   const core::MarchSettings& settings, int spp, const PathTraceSettings& pt = {},
                   PathTraceStats* extra = nullptr, const std::function<void(int, int)>& on_samples = {},
                   const OpaqueInput& opaque = {});

  // The last frame's cloud depth, for later passes: an R32F texture of its size holding the distance
  // (m) from the camera at which the view transmittance fell to 0.5 (3e38 where it never did).
  GLuint cloud_depth_texture() const { return state_[2]; }
  // The same, read back (rows top to bottom).
  std::vector<float> read_cloud_depth() const;

  // What the last march did (view and sun samples, what was skipped, octave terms); waits for it to
  // finish.
  const core::MarchStats& last_stats();
  // Wall time of the last build of the two-stream source (ms; 0 before any), rebuilt only when the
  // time step, the sun or the medium's phases change.
  double ms_source_build_ms() const { return ms_build_ms_; }
  // The last source's light between columns: its 3-D solve's iterations, -1 where the columns were
  // left on their own.
  int ms_source_lateral_iterations() const { return ms_lateral_iterations_; }
  // With -1 above: why (core::ms_columns_alone_why).
  const std::string& ms_source_columns_alone() const { return ms_columns_alone_; }
  // Whether the source in use was built on this thread (false: the volume's prebuilt one), and how
  // many sources were built here and taken prebuilt so far.
  bool ms_source_built_here() const { return ms_built_here_; }
  std::size_t ms_sources_built_here() const { return ms_count_[0]; }
  std::size_t ms_sources_taken_prebuilt() const { return ms_count_[1]; }

 private:
  static constexpr int kStatCounters = 8;  // 64-bit counters in the Stats buffer (CV_STAT_COUNT, kernel/march_stats.glsl)
  void read_stats();  // the Stats buffer into stats_
  // The program of a march variant, compiled on first use (the noise variants need upload_noise first).
  const GlProgram& program_for(const kernel::MarchVariant& v);
  // The path tracer's program of a variant (only globe and noise matter to it), compiled on first use.
  const GlProgram& path_program_for(const kernel::MarchVariant& v);
  kernel::MarchParams bind_inputs(const core::Camera& cam, const core::Sun& sun, const core::MarchSettings& s,
                                  const OpaqueInput& opaque);
  const ShaderLoader& loader_;
  std::unique_ptr<GlProgram> programs_[kernel::MarchVariant::kCount];  // by MarchVariant::key
  std::unique_ptr<GlProgram> path_programs_[kernel::MarchVariant::kCount];
  GLuint path_sums_ = 0, path_stats_ = 0, path_state_ = 0;  // the path tracer's per-pixel sums, counters, paths in flight
  GLuint path_branches_ = 0;                                 // and their branch stacks
  std::size_t path_branch_floats_ = 0;
  std::size_t path_pixels_ = 0;
  GLuint textures_[2] = {0, 0};
  GLuint noise_textures_[2] = {0, 0};
  GLuint ms_[2] = {0, 0};           // the two-stream source (RG32F x2; RGBA32F x2 with the slab's fields), built for ms_key_ on ms_volume_
  bool ms_rgba_ = false;            // both hold four channels (the higher-order source's fields)
  bool ms_lateral_ = false;         // ms_[1] holds the source's horizontal moment
  bool ms_second_ = false;          // ms_[1] is made (the horizontal moment, or the slab's fields)
  GLuint fraction_ = 0;             // the modelled cloud's cover (R32F 3-D), uploaded for fraction_volume_ when used
  const core::PreparedVolume* fraction_volume_ = nullptr;
  GLuint detail_shift_ = 0;         // the modelled cloud's displacement per level (RG32F, detail_shift_levels_ x 1)
  int detail_shift_levels_ = 0;
  GLuint modelled_pyramid_ = 0;     // the modelled cloud's brick bounds (core::medium_pyramid) for modelled_pyramid_volume_
  const core::PreparedVolume* modelled_pyramid_volume_ = nullptr;
  double modelled_pyramid_amount_ = -1.0;
  GLuint detail_table_ = 0;         // the modelled cloud's table (RG32F, CV_DETAIL_COVERS + 1 by CV_DETAIL_ROWS), with the noise
  std::vector<float> detail_values_;  // the same table on the CPU (the path tracer's majorant)
  core::MsSourceKey ms_key_;
  const core::PreparedVolume* ms_volume_ = nullptr;
  double ms_build_ms_ = 0.0;
  int ms_lateral_iterations_ = -1;
  std::string ms_columns_alone_;
  bool ms_built_here_ = true;
  std::size_t ms_count_[2] = {0, 0};  // sources built here, taken prebuilt
  GLuint ms_beam_buffer_ = 0;         // the droplets' beam table (CV_SSBO_MS_BEAM)
  std::shared_ptr<const core::MsBeamTable> ms_beam_uploaded_;  // the table it holds
  GLuint ms_slab_buffer_ = 0;         // the higher-order source's slab tables (CV_SSBO_MS_SLAB)
  std::shared_ptr<const std::vector<float>> ms_slab_uploaded_;  // the tables it holds
  GLuint column_tau_ = 0;           // the column maps (RGBA32F): optical depth (the octave gate), ground, cloud type
  core::MediumMask column_mask_;    // the mask column_tau_'s depths were made for (none: the prepared map)
  GLuint jitter_mask_ = 0;          // the blue-noise mask (R32F), uploaded at construction
  GLuint ground_ = 0;               // land albedo and water fraction (RGBA32F), loaded from ground_path_
  // The march's state between dispatches (image-sized, two RGBA32F) and the cloud depth it writes (R32F).
  GLuint state_[4] = {0, 0, 0, 0};  // march state (radiance, depths), cloud depth, two-stream transmittance
  int state_w_ = 0, state_h_ = 0;
  int ground_w_ = 0, ground_h_ = 0;
  std::shared_ptr<const core::AlbedoMap> ground_map_;  // the map ground_ holds, for the two-stream columns' ground
  std::string ground_path_;
  bool ground_map_colours_ = false;  // the ground model ground_ was loaded with
  GLuint pyramid_buffer_ = 0, stats_buffer_ = 0;
  GLuint params_buffer_ = 0;  // the kernel's uniform block (kernel::MarchParamsStd140)
  std::shared_ptr<const core::PreparedVolume> volume_;  // the time step uploaded
  bool stats_read_ = true;
  bool loop_budget_ = true;  // the driver ends loops past kLlvmpipeLoopBudget (driver_has_loop_budget)
  bool sun_down_ = false;  // the last render left out the sun (core::layer_in_earth_shadow)
  core::MarchStats stats_;
};

}  // namespace cv::render
