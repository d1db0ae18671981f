// The GPU raymarcher: texture upload, uniforms, dispatch, read-back.
#include "render/raymarcher.hpp"

#include <cmath>

#include <glm/glm.hpp>

#include "geo/geodesy.hpp"
#include "render/albedo_map.hpp"
#include "volume/sampler.hpp"

namespace cv::render {
namespace {
GLint loc(GLuint program, const char* name) { return glGetUniformLocation(program, name); }
void set3(GLuint p, const char* n, const glm::dvec3& v) {
  glProgramUniform3f(p, loc(p, n), static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z));
}
}  // namespace

GpuRaymarcher::GpuRaymarcher(const ShaderLoader& loader)
    : program_(load_compute(loader, ShaderLoader::default_shader_dir() / "render" / "raymarch.comp")) {}

GpuRaymarcher::~GpuRaymarcher() {
  if (textures_[0]) glDeleteTextures(2, textures_);
  if (ground_) glDeleteTextures(1, &ground_);
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
  grid_ = grid;
}

std::vector<glm::vec4> GpuRaymarcher::render(const core::Camera& cam, const core::Sun& sun, const core::MarchSettings& s) {
  // The read-back takes its byte count as a GLsizei.
  if (static_cast<double>(cam.width) * cam.height * sizeof(glm::vec4) >= 2147483647.0) {
    throw GlError("an image of " + std::to_string(cam.width) + " x " + std::to_string(cam.height) +
                  " pixels is too large to read back at once (at most 134 million pixels)");
  }
  const GLuint p = program_.id();
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
  set3(p, "u_to_sun", glm::normalize(geo::sphere_to_ecef({sun.subsolar_lat_deg, sun.subsolar_lon_deg, 0.0}, r0)));
  set3(p, "u_irradiance", sun.irradiance);
  glProgramUniform1f(p, loc(p, "u_r0"), static_cast<float>(r0));
  set3(p, "u_grid_start", {grid_.lon_deg.start, grid_.lat_deg.start, grid_.alt_m.start});
  set3(p, "u_grid_step", {grid_.lon_deg.step, grid_.lat_deg.step, grid_.alt_m.step});
  set3(p, "u_grid_count", {double(grid_.lon_deg.count), double(grid_.lat_deg.count), double(grid_.alt_m.count)});
  std::vector<float> unused;
  glProgramUniform1i(p, loc(p, "u_wraps"), grid_.wraps_lon() ? 1 : 0);
  glProgramUniform1i(p, loc(p, "u_global_lat"), core::VolumeSampler(grid_, unused).global_lat() ? 1 : 0);
  glProgramUniform1f(p, loc(p, "u_view_step"), static_cast<float>(s.view_step_m));
  glProgramUniform1i(p, loc(p, "u_sun_steps"), s.sun_steps);
  glProgramUniform1i(p, loc(p, "u_octaves"), s.octaves);
  set3(p, "u_octave_abc", {s.octave_a, s.octave_b, s.octave_c});
  glProgramUniform1f(p, loc(p, "u_droplet_um"), static_cast<float>(s.droplet_diameter_um));
  glProgramUniform1f(p, loc(p, "u_ice_g"), static_cast<float>(s.ice_g));
  glProgramUniform1i(p, loc(p, "u_frame"), s.frame);
  glProgramUniform1i(p, loc(p, "u_atmosphere"), s.atmosphere ? 1 : 0);
  glProgramUniform1i(p, loc(p, "u_globe"), s.globe ? 1 : 0);
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
  GLuint out = 0;
  glCreateTextures(GL_TEXTURE_2D, 1, &out);
  glTextureStorage2D(out, 1, GL_RGBA32F, cam.width, cam.height);
  glBindImageTexture(0, out, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
  glBindTextureUnit(1, textures_[0]);
  glBindTextureUnit(2, textures_[1]);
  glBindTextureUnit(3, ground_);
  glUseProgram(p);
  glDispatchCompute(static_cast<GLuint>((cam.width + 7) / 8), static_cast<GLuint>((cam.height + 7) / 8), 1);
  glMemoryBarrier(GL_TEXTURE_UPDATE_BARRIER_BIT);
  std::vector<glm::vec4> pixels(static_cast<std::size_t>(cam.width) * cam.height);
  glGetTextureImage(out, 0, GL_RGBA, GL_FLOAT, static_cast<GLsizei>(pixels.size() * sizeof(glm::vec4)), pixels.data());
  glDeleteTextures(1, &out);
  check_gl("running the raymarcher");
  return pixels;
}

}  // namespace cv::render
