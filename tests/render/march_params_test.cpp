// The march's uniform block as the driver lays it out: every member of kernel::MarchParamsStd140 at
// the offset the compiled raymarch.comp reports, and the block no larger than the struct; and the
// packing keeps every parameter (float of the double).
#include <gtest/gtest.h>

#include <cstddef>
#include <string>

#include "kernel/march_params.hpp"
#include "render/context.hpp"
#include "render/gl.hpp"
#include "render/shader_loader.hpp"

namespace {
using namespace cv;

GLint member_offset(GLuint program, const char* name) {
  const GLuint index = glGetProgramResourceIndex(program, GL_UNIFORM, name);
  if (index == GL_INVALID_INDEX) return -1;
  const GLenum prop = GL_OFFSET;
  GLint offset = -1;
  glGetProgramResourceiv(program, GL_UNIFORM, index, 1, &prop, 1, nullptr, &offset);
  return offset;
}

TEST(MarchParams, Std140StructMatchesTheCompiledBlock) {
  auto ctx = render::make_headless_context();
  render::ShaderLoader loader({render::ShaderLoader::default_shader_dir()});
  for (const kernel::MarchVariant v : {kernel::MarchVariant{}, kernel::MarchVariant{true, false, true, true, true}}) {
    const render::GlProgram p =
        render::load_compute(loader, render::ShaderLoader::default_shader_dir() / "render" / "raymarch.comp", {}, v.defines());
    int members = 0;
#define CV_PARAM(T, name)                                                                                  \
  EXPECT_EQ(member_offset(p.id(), "MarchParams." #name), static_cast<GLint>(offsetof(kernel::MarchParamsStd140, name))) << #name; \
  ++members;
#define CV_PARAM_ARRAY(T, name, N)                                                                            \
  EXPECT_EQ(member_offset(p.id(), "MarchParams." #name "[0]"), static_cast<GLint>(offsetof(kernel::MarchParamsStd140, name))) << #name; \
  ++members;
#include "kernel/march_params.glsl"
#undef CV_PARAM
#undef CV_PARAM_ARRAY
    EXPECT_GT(members, 40);
    const GLuint block = glGetProgramResourceIndex(p.id(), GL_UNIFORM_BLOCK, "MarchParams");
    ASSERT_NE(block, GL_INVALID_INDEX);
    const GLenum prop = GL_BUFFER_DATA_SIZE;
    GLint size = 0;
    glGetProgramResourceiv(p.id(), GL_UNIFORM_BLOCK, block, 1, &prop, 1, nullptr, &size);
    EXPECT_LE(size, static_cast<GLint>(sizeof(kernel::MarchParamsStd140)));
    EXPECT_GE(size + 16, static_cast<GLint>(sizeof(kernel::MarchParamsStd140)));
  }
}

TEST(MarchParams, PackingKeepsEveryParameter) {
  kernel::MarchParams p;
  double x = 1.0;
  // A distinct value in every member: a dropped or swapped one would show.
  auto next = [&] { return x += 1.0; };
  auto set = [&](auto& m) {
    using M = std::decay_t<decltype(m)>;
    if constexpr (std::is_same_v<M, bool>) m = static_cast<int>(next()) % 2 == 0;
    else if constexpr (std::is_arithmetic_v<M>) m = static_cast<M>(next());
    else for (int i = 0; i < M::length(); ++i) m[i] = static_cast<typename M::value_type>(next());
  };
#define CV_PARAM(T, name) set(p.name);
#define CV_PARAM_ARRAY(T, name, N) for (int i = 0; i < (N); ++i) set(p.name[i]);
#include "kernel/march_params.glsl"
#undef CV_PARAM
#undef CV_PARAM_ARRAY
  const kernel::MarchParamsStd140 o = kernel::pack_std140(p);
  auto same = [](const auto& packed, const auto& orig) {
    using M = std::decay_t<decltype(orig)>;
    if constexpr (std::is_same_v<M, bool>) return packed == (orig ? 1u : 0u);
    else if constexpr (std::is_arithmetic_v<M>) return static_cast<double>(packed) == static_cast<double>(orig);
    else {
      for (int i = 0; i < M::length(); ++i) if (static_cast<double>(packed[i]) != static_cast<double>(orig[i])) return false;
      return true;
    }
  };
#define CV_PARAM(T, name) EXPECT_TRUE(same(o.name, p.name)) << #name;
#define CV_PARAM_ARRAY(T, name, N) for (int i = 0; i < (N); ++i) EXPECT_TRUE(same(o.name[i], p.name[i])) << #name << i;
#include "kernel/march_params.glsl"
#undef CV_PARAM
#undef CV_PARAM_ARRAY
}

}  // namespace
