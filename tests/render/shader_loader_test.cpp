// The shader loader: includes (once each), #line remapping so errors name the right file and line,
// the feature prelude, and every shader under shaders/ compiling on llvmpipe.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <unistd.h>
#include <string>

#include "render/context.hpp"
#include "render/shader_loader.hpp"

namespace {
using namespace cv::render;
namespace fs = std::filesystem;

class ShaderLoaderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("cv_shader_test_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_ / "lib");
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path write(const std::string& name, const std::string& text) {
    const fs::path p = dir_ / name;
    std::ofstream(p) << text;
    return p;
  }
  std::string compile_error(const fs::path& file, const ShaderFeatures& f = {}) {
    ShaderLoader loader({dir_});
    try {
      load_compute(loader, file, f);
    } catch (const ShaderError& e) {
      return e.what();
    }
    return "";
  }
  fs::path dir_;
};

const char* kMain = "layout(local_size_x = 1) in;\nvoid main() {}\n";

TEST_F(ShaderLoaderTest, IncludesResolveOnceEachWithLineDirectives) {
  write("lib/a.glsl", "float a() { return 1.0; }\n");
  write("lib/b.glsl", "#include \"a.glsl\"\nfloat b() { return a(); }\n");
  const auto top = write("top.comp", "#include \"lib/a.glsl\"\n#include \"lib/b.glsl\"\n" + std::string(kMain));
  ShaderLoader loader({dir_});
  const ShaderSource src = loader.load(top);
  ASSERT_EQ(src.files.size(), 4u);  // prelude, top, a, b
  EXPECT_EQ(src.text.find("#version 450 core"), 0u);
  const size_t first = src.text.find("float a()");
  EXPECT_NE(first, std::string::npos);
  EXPECT_EQ(src.text.find("float a()", first + 1), std::string::npos);  // a.glsl only once
  EXPECT_NE(src.text.find("#line 200001 2"), std::string::npos);  // a.glsl (file 2) from its line 1
  EXPECT_NE(src.text.find("#line 100002 1"), std::string::npos);  // back in top.comp at its line 2
}

// An X-macro table (first line "// X-macro table") expands at each include under the includer's
// macros, keeping one file index; an ordinary file still comes once. The program compiles and
// reads the copies the second expansion made of the block's members.
TEST_F(ShaderLoaderTest, XMacroTablesExpandAtEachInclude) {
  auto ctx = make_headless_context();
  write("lib/table.glsl", "// X-macro table: two rows\nROW(float, v_a)\nROW(float, v_b)\n");
  write("lib/a.glsl", "float a() { return 1.0; }\n");
  const auto top = write("top.comp",
                         "#include \"lib/a.glsl\"\n"
                         "#define ROW(T, n) T n;\n"
                         "layout(std140, binding = 0) uniform Block {\n#include \"lib/table.glsl\"\n} blk;\n"
                         "#include \"lib/table.glsl\"\n"
                         "#undef ROW\n#define ROW(T, n) n = blk.n;\n"
                         "void load() {\n#include \"lib/table.glsl\"\n}\n"
                         "#include \"lib/a.glsl\"\n"
                         "layout(std430, binding = 1) buffer Out { float o[]; };\n"
                         "layout(local_size_x = 1) in;\nvoid main() { load(); o[0] = v_a + v_b + a(); }\n");
  ShaderLoader loader({dir_});
  const ShaderSource src = loader.load(top);
  ASSERT_EQ(src.files.size(), 4u);  // prelude, top, a, table: the table keeps one index
  std::size_t rows = 0;
  for (std::size_t at = src.text.find("ROW(float, v_a)"); at != std::string::npos; at = src.text.find("ROW(float, v_a)", at + 1)) ++rows;
  EXPECT_EQ(rows, 3u);
  const size_t first = src.text.find("float a()");
  EXPECT_EQ(src.text.find("float a()", first + 1), std::string::npos);  // a.glsl only once
  EXPECT_EQ(compile_error(top), "");
}

TEST_F(ShaderLoaderTest, MissingIncludeNamesFileLineAndWhatWasSought) {
  const auto top = write("top.comp", std::string(kMain) + "#include \"nowhere.glsl\"\n");
  ShaderLoader loader({dir_});
  try {
    loader.load(top);
    FAIL();
  } catch (const ShaderError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("top.comp:3"), std::string::npos) << m;
    EXPECT_NE(m.find("nowhere.glsl"), std::string::npos) << m;
  }
}

TEST_F(ShaderLoaderTest, VersionLinesAndCyclesAreRejected) {
  ShaderLoader loader({dir_});
  EXPECT_THROW(loader.load(write("v.comp", "#version 430\n" + std::string(kMain))), ShaderError);
  write("lib/x.glsl", "#include \"y.glsl\"\n");
  write("lib/y.glsl", "#include \"x.glsl\"\n");
  try {
    loader.load(write("c.comp", "#include \"lib/x.glsl\"\n" + std::string(kMain)));
    FAIL();
  } catch (const ShaderError& e) {
    EXPECT_NE(std::string(e.what()).find("include cycle"), std::string::npos) << e.what();
  }
}

TEST_F(ShaderLoaderTest, CompileErrorsPointAtTheRightFileAndLine) {
  auto ctx = make_headless_context();
  write("lib/bad.glsl", "float ok() { return 1.0; }\n\nfloat bad() { return undefined_name; }\n");
  const auto top = write("top.comp", "#include \"lib/bad.glsl\"\n" + std::string(kMain));
  std::string err = compile_error(top);
  EXPECT_NE(err.find("bad.glsl:3"), std::string::npos) << err;
  EXPECT_NE(err.find("top.comp"), std::string::npos) << err;  // the program's own path
  EXPECT_NE(err.find("GLSL"), std::string::npos) << err;      // and the driver's GLSL version

  // An error in the top file after an include keeps the top file's numbering.
  write("lib/good.glsl", "float g() { return 1.0; }\n");
  const auto top2 = write("top2.comp", "#include \"lib/good.glsl\"\nlayout(local_size_x = 1) in;\n"
                                        "void main() { float x = missing_fn(); }\n");
  err = compile_error(top2);
  EXPECT_NE(err.find("top2.comp:3"), std::string::npos) << err;
}

TEST_F(ShaderLoaderTest, FeaturesBecomeDefinesAndSelectCode) {
  auto ctx = make_headless_context();
  const auto top = write("f.comp", "#ifndef CV_FEATURE_MIE_PHASE\n#error needs the Mie feature\n#endif\n" +
                                       std::string(kMain));
  EXPECT_FALSE(compile_error(top).empty());
  EXPECT_TRUE(compile_error(top, ShaderFeatures{ShaderFeature::MiePhase}).empty());
  const std::string defs = ShaderFeatures{ShaderFeature::MultipleScattering, ShaderFeature::SunShadow}.defines();
  EXPECT_NE(defs.find("#define CV_FEATURE_MULTIPLE_SCATTERING 1"), std::string::npos);
  EXPECT_NE(defs.find("#define CV_FEATURE_SUN_SHADOW 1"), std::string::npos);
  EXPECT_EQ(defs.find("MIE"), std::string::npos);
}

TEST(ShaderLog, NvidiaAndMesaFormatsAreRemapped) {
  ShaderSource src;
  src.files = {"<prelude>", "shaders/top.comp", "shaders/common/phase.glsl"};
  // Mesa reports source 0 whatever #line said; the file index rides in the line number.
  EXPECT_EQ(src.remap_log("0:12(5): error: boom"), "<prelude>:12(5): error: boom\n");
  EXPECT_EQ(src.remap_log("0:200007(3): error: x"), "shaders/common/phase.glsl:7(3): error: x\n");
  // NVIDIA honours the source number and prints "source(line)".
  EXPECT_EQ(src.remap_log("1(100040) : error C1008: undefined variable"),
            "shaders/top.comp:40: error C1008: undefined variable\n");
  EXPECT_EQ(src.remap_log("2(7) : error C0000: y"), "shaders/common/phase.glsl:7: error C0000: y\n");
}

TEST(Shaders, EveryShaderUnderShadersCompilesOnThisDriver) {
  auto ctx = make_headless_context();
  const fs::path dir = CV_SHADER_DIR;
  ShaderLoader loader({dir});
  int n = 0;
  std::set<std::string> covered;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (!e.is_regular_file() || e.path().extension() != ".comp") continue;
    for (const auto& f : loader.load(e.path()).files) covered.insert(f);
    EXPECT_NO_THROW({
      try {
        load_compute(loader, e.path());
      } catch (const std::exception& ex) {
        ADD_FAILURE() << ex.what();
        throw;
      }
    }) << e.path();
    ++n;
  }
  EXPECT_GT(n, 0);
  // Every GLSL file is part of some compiled program, so none escapes the compiler.
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (e.is_regular_file() && e.path().extension() == ".glsl") {
      EXPECT_TRUE(covered.count(fs::weakly_canonical(e.path()).string())) << e.path() << " is in no program";
    }
  }
  std::printf("%d compute shader(s) compiled on %s\n", n, ctx->info().renderer.c_str());
}

}  // namespace
