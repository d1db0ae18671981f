// The `cloudviewer` command: batch subcommands (more arrive with the importers and the renderer).
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <string>
#include <vector>

#include "physics/physics.hpp"
#include "render/context.hpp"
#include "render/shader_loader.hpp"

namespace {

namespace fs = std::filesystem;
constexpr int kExitBadInput = 2;

// Bad command-line input: one line naming the argument, what was found and what was expected.
struct UsageError {
  std::string message;
};

void print_usage() {
  std::printf(
      "usage: cloudviewer <command> [options]\n"
      "commands:\n"
      "  gpu-info                 open a headless OpenGL 4.5 context and compile every shader\n"
      "  phase --diameter D_UM    approximate Mie phase parameters for a droplet diameter\n"
      "  render --dry-run [-o OUT.png] [--size WxH]\n"
      "                           say what a render will do (the raymarcher is not built yet)\n"
      "  --version                print the version\n");
}

double parse_number(const std::string& option, const std::string& text) {
  try {
    size_t used = 0;
    const double v = std::stod(text, &used);
    if (used == text.size()) return v;
  } catch (const std::exception&) {
  }
  throw UsageError{"cloudviewer: " + option + ": found '" + text + "', expected a number"};
}

std::vector<fs::path> all_shaders(const fs::path& dir) {
  std::vector<fs::path> out;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (e.is_regular_file() && e.path().extension() == ".comp") out.push_back(e.path());
  }
  std::sort(out.begin(), out.end());
  return out;
}

// Opens the headless context and compiles every compute shader; returns how many compiled.
int check_gpu(bool verbose) {
  auto ctx = cv::render::make_headless_context();
  std::printf("context: %s\n", ctx->info().summary().c_str());
  const fs::path dir = cv::render::ShaderLoader::default_shader_dir();
  cv::render::ShaderLoader loader({dir});
  int n = 0;
  for (const auto& file : all_shaders(dir)) {
    cv::render::load_compute(loader, file);
    if (verbose) std::printf("compiled %s\n", fs::relative(file, dir).c_str());
    ++n;
  }
  std::printf("%d compute shader(s) compiled from %s\n", n, dir.c_str());
  return n;
}

int cmd_phase(const std::vector<std::string>& args) {
  double d_um = -1.0;
  for (size_t i = 0; i < args.size(); ++i) {
    if (args[i] == "--diameter" && i + 1 < args.size()) {
      d_um = parse_number("--diameter", args[++i]);
    } else {
      throw UsageError{"cloudviewer phase: unexpected argument '" + args[i] + "', expected --diameter D_UM"};
    }
  }
  if (!(d_um >= 0.01 && d_um <= 50.0)) {
    throw UsageError{"cloudviewer phase: --diameter: expected a droplet diameter in [0.01, 50] um"};
  }
  const auto p = cv::physics::f64::mie_params(d_um);
  std::printf("droplet diameter %.4g um: g_HG %.4f  g_D %.4f  alpha %.4f  w_D %.4f  mean cosine %.4f\n", d_um,
              p.g_hg, p.g_d, p.alpha, p.w_d, cv::physics::f64::mie_mean_cosine(p));
  return 0;
}

int cmd_render(const std::vector<std::string>& args) {
  bool dry_run = false;
  std::string out = "cloudviewer.png";
  int w = 1280, h = 720;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "--dry-run") {
      dry_run = true;
    } else if (a == "-o" && i + 1 < args.size()) {
      out = args[++i];
    } else if (a == "--size" && i + 1 < args.size()) {
      const std::string s = args[++i];
      if (std::sscanf(s.c_str(), "%dx%d", &w, &h) != 2 || w < 1 || h < 1 || w > 16384 || h > 16384) {
        throw UsageError{"cloudviewer render: --size: found '" + s + "', expected WxH with 1..16384 each"};
      }
    } else {
      throw UsageError{"cloudviewer render: unexpected argument '" + a + "'"};
    }
  }
  std::printf(
      "cloudviewer render: plan for a %dx%d image to %s\n"
      "  1. import the bundled sample forecast into a CloudVolume      (importers: not built yet)\n"
      "  2. upload weather textures and the extinction min/max pyramid (renderer: not built yet)\n"
      "  3. march the cloud shell in a compute shader, tonemap, write the PNG atomically\n",
      w, h, out.c_str());
  std::printf("checking what this build can already do:\n");
  check_gpu(false);
  if (!dry_run) {
    std::fprintf(stderr, "cloudviewer render: the raymarcher is not in this build yet; no image was written\n");
    return 3;
  }
  std::printf("dry run: no image was written (the raymarcher is not in this build yet)\n");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  if (args.empty() || args[0] == "-h" || args[0] == "--help") {
    print_usage();
    return args.empty() ? kExitBadInput : 0;
  }
  const std::string cmd = args[0];
  args.erase(args.begin());
  try {
    if (cmd == "--version") {
      std::printf("cloudviewer %s\n", CV_VERSION);
      return 0;
    }
    if (cmd == "gpu-info") return check_gpu(true) > 0 ? 0 : 1;
    if (cmd == "phase") return cmd_phase(args);
    if (cmd == "render") return cmd_render(args);
    throw UsageError{"cloudviewer: unknown command '" + cmd + "', expected gpu-info, phase or render"};
  } catch (const UsageError& e) {
    std::fprintf(stderr, "%s\n", e.message.c_str());
    return kExitBadInput;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cloudviewer %s: %s\n", cmd.c_str(), e.what());
    return 1;
  }
}
