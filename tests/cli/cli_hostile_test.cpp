// The command line against hostile and mistaken input (issue 13): the cloudviewer executable run
// on files the tests write; exit 2 and one line, nothing written at the output, existing outputs
// left as they were, and the behaviour users expect from --help, output paths and piped progress.
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImathBox.h>

#include "support/nc_builder.hpp"

namespace {
namespace fs = std::filesystem;

struct Result {
  int rc = -1;
  std::string out;  // stdout and stderr together
  double seconds = 0;
};

// Runs `cloudviewer ARGS` under sh (with a 60 s guard so a hang fails instead of blocking).
Result cloudviewer(const std::string& args, const std::string& prefix = "") {
  const std::string cmd = prefix + "timeout 60 " + std::string(CV_CLOUDVIEWER) + " " + args + " 2>&1";
  const auto t0 = std::chrono::steady_clock::now();
  Result r;
  FILE* p = ::popen(cmd.c_str(), "r");
  std::array<char, 4096> buf;
  std::size_t n;
  while ((n = std::fread(buf.data(), 1, buf.size(), p)) > 0) r.out.append(buf.data(), n);
  const int status = ::pclose(p);
  r.rc = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

class CliHostile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("cv_cli_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    sample_ = (dir_ / "in.nc").string();
    fs::copy_file(CV_SAMPLE_FILE, sample_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& n) const { return (dir_ / n).string(); }
  void write(const std::string& n, const std::string& text) const { std::ofstream(path(n), std::ios::binary) << text; }
  std::string read(const std::string& n) const {
    std::ifstream in(path(n), std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
  }
  std::size_t files() const { return static_cast<std::size_t>(std::distance(fs::directory_iterator(dir_), fs::directory_iterator())); }
  // Exit 2, one line, and it contains `what`.
  static void expect_refused(const Result& r, const std::string& what) {
    EXPECT_EQ(r.rc, 2) << r.out;
    EXPECT_NE(r.out.find(what), std::string::npos) << r.out;
    EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1) << r.out;
  }
  fs::path dir_;
  std::string sample_;
};

TEST_F(CliHostile, HelpOnEveryCommandAndHelpCommand) {
  for (const char* c : {"info", "import", "gpu-info", "phase", "render", "bench", "time-error", "probe", "section", "series", "compare", "view"}) {
    const Result a = cloudviewer(std::string(c) + " --help", "env -u DISPLAY ");
    EXPECT_EQ(a.rc, 0) << c << ": " << a.out;
    EXPECT_NE(a.out.find(std::string("usage: cloudviewer ") + c), std::string::npos) << a.out;
    const Result b = cloudviewer(std::string("help ") + c);
    EXPECT_EQ(b.rc, 0) << c;
    EXPECT_EQ(a.out, b.out) << c;
  }
  const Result usage = cloudviewer("help");
  EXPECT_EQ(usage.rc, 0);
  const Result help_on_help = cloudviewer("help --help");  // every command answers --help, help too
  EXPECT_EQ(help_on_help.rc, 0) << help_on_help.out;
  EXPECT_EQ(help_on_help.out, usage.out);
  expect_refused(cloudviewer("help frobnicate"), "cloudviewer help: found 'frobnicate', expected one command");
}

TEST_F(CliHostile, OutputsAreCheckedBeforeTheRenderStarts) {
  Result r = cloudviewer("render " + sample_ + " -o " + path("no/such/x.png"));
  expect_refused(r, "-o: found '" + path("no/such/x.png") + "': its folder '" + path("no/such") + "' does not exist");
  EXPECT_LT(r.seconds, 5.0);  // before any import or GPU work
  expect_refused(cloudviewer("render " + sample_ + " -o " + path("x.mp4")), "expected a file name ending in .png");
  expect_refused(cloudviewer("render " + sample_ + " -o " + path("x.png") + " --pfm " + path("x.exr")),
                 "--pfm: found '" + path("x.exr") + "', expected a file name ending in .pfm");
  expect_refused(cloudviewer("render " + sample_ + " -o " + dir_.string() + "/"), "expected a file name");
  EXPECT_EQ(files(), 1u);  // the input alone
}

// The viewer's screenshot and the bench's folder too: refused before a window opens or a
// reference is rendered (no display is needed to be told).
TEST_F(CliHostile, ScreenshotAndBenchOutputsAreCheckedFirst) {
  const std::string env = "env -u DISPLAY ";
  expect_refused(cloudviewer("view " + sample_ + " --frames 2 --screenshot " + path("no/such/x.png"), env),
                 "--screenshot: found '" + path("no/such/x.png") + "': its folder '" + path("no/such") + "' does not exist");
  expect_refused(cloudviewer("view " + sample_ + " --frames 2 --screenshot " + path("x.jpg"), env),
                 "--screenshot: found '" + path("x.jpg") + "', expected a file name ending in .png");
  fs::create_symlink(sample_, path("alias.png"));
  expect_refused(cloudviewer("view " + sample_ + " --frames 2 --screenshot " + path("alias.png"), env), "which is the input");
  write("plain", "a file, not a folder");
  expect_refused(cloudviewer("bench --out " + path("plain")), "cloudviewer bench: --out: cannot create the folder '" + path("plain") + "'");
  ::chmod(dir_.c_str(), 0555);
  const bool root = ::access(dir_.c_str(), W_OK) == 0;  // root writes anywhere: the check cannot be seen
  ::chmod(dir_.c_str(), 0755);
  if (!root) {
    fs::create_directories(path("ro"));
    ::chmod(path("ro").c_str(), 0555);
    expect_refused(cloudviewer("bench --out " + path("ro")), "--out");
    ::chmod(path("ro").c_str(), 0755);
  }
  EXPECT_EQ(fs::file_size(path("plain")), std::string("a file, not a folder").size());
}

TEST_F(CliHostile, AnOutputThatIsAnInputIsRefusedAndTheInputKept) {
  const auto size = fs::file_size(sample_);
  // The data through a link named like an image, and a scene saved over the scene it renders.
  fs::create_symlink(sample_, path("alias.png"));
  expect_refused(cloudviewer("render " + sample_ + " -o " + path("alias.png")), "which is the input");
  write("s.json", "{\"version\": 1, \"data\": {\"path\": \"in.nc\"}}");
  expect_refused(cloudviewer("render " + path("s.json") + " -o " + path("x.png") + " --save-scene " + path("s.json")), "which is the input");
  expect_refused(cloudviewer("render " + sample_ + " -o " + path("x.png") + " --save-scene " + path("x.png.json") + " --pfm " + path("x.pfm") +
                             " --save-scene " + path("x.transmittance.pfm")),
                 "expected a file name ending in .json");
  fs::create_symlink(sample_, path("alias.cvvol"));
  expect_refused(cloudviewer("import " + sample_ + " -o " + path("alias")), "which is the input");
  EXPECT_EQ(fs::file_size(sample_), size);
  EXPECT_TRUE(fs::is_symlink(path("alias.png")));
}

TEST_F(CliHostile, BadNumbersAndDatesAreRefused) {
  expect_refused(cloudviewer("render " + sample_ + " --size 4294967328x18 -o " + path("x.png")),
                 "--size: found '4294967328x18', expected WxH with 1..16384 each");
  expect_refused(cloudviewer("import " + sample_ + " --times 2020-02-30T00:00:00Z.. -o " + path("v")),
                 "--times: found '2020-02-30T00:00:00Z..'");
  expect_refused(cloudviewer("import " + sample_ + " --dz 1e300 -o " + path("v")), "--dz: found '1e300', expected a spacing in metres 1..100000");
  expect_refused(cloudviewer("render " + sample_ + " --steps 1e-9 -o " + path("x.png")), "--steps: found '1e-9'");
  write("step.json", "{\"version\": 1, \"data\": {\"path\": \"in.nc\"}, \"render\": {\"march\": {\"view_step_m\": 1e-9}}}");
  expect_refused(cloudviewer("render " + path("step.json") + " -o " + path("x.png")), "render.march.view_step_m: found 1e-09");
  expect_refused(cloudviewer("info " + sample_, "CLOUDVIEWER_MEMORY_LIMIT=lots "), "CLOUDVIEWER_MEMORY_LIMIT: found 'lots'");
  EXPECT_EQ(files(), 2u);
}

TEST_F(CliHostile, AStepCountBeyondTheBoundIsRefusedWithTheSettingsName) {
  // 1 m steps are within the setting's range, but take ~1e6 steps per ray across the sample's layer.
  const Result r = cloudviewer("render " + sample_ + " --time 1 --size 16x9 --steps 1 -o " + path("x.png"));
  expect_refused(r, "view_step_m (--steps): found 1 m, which takes up to");
  EXPECT_NE(r.out.find("expected at most 250000 steps"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(path("x.png")));
}

TEST_F(CliHostile, FifosAndDevicesAsInputsAreRefusedWithoutHanging) {
  ASSERT_EQ(::mkfifo(path("pipe").c_str(), 0600), 0);
  ASSERT_EQ(::mkfifo(path("pipe.json").c_str(), 0600), 0);
  ASSERT_EQ(::mkfifo(path("pipe.cvvol").c_str(), 0600), 0);
  expect_refused(cloudviewer("render " + path("pipe.json") + " -o " + path("x.png")), "the scene file is a FIFO (named pipe), expected a regular file");
  expect_refused(cloudviewer("render " + path("pipe.cvvol") + " -o " + path("x.png")), "the cloud volume is a FIFO (named pipe)");
  expect_refused(cloudviewer("info " + path("pipe.cvvol")), "the cloud volume is a FIFO");
  expect_refused(cloudviewer("render " + sample_ + " --time 1 --size 16x9 --budget-ms 100 --front " + path("pipe") + " -o " + path("x.png")),
                 "the quality front is a FIFO");
  expect_refused(cloudviewer("render " + sample_ + " --time 1 --size 16x9 --budget-ms 100 --front /dev/zero -o " + path("x.png")),
                 "/dev/zero: the quality front is a character device, expected a regular file");
  write("g.json", "{\"version\": 1, \"data\": {\"path\": \"in.nc\"}, \"render\": {\"march\": {\"ground_texture\": \"pipe\"}}}");
  expect_refused(cloudviewer("render " + path("g.json") + " -o " + path("x.png")), path("pipe") + ": render.march.ground_texture, the ground image is a FIFO");
  EXPECT_FALSE(fs::exists(path("x.png")));
}

TEST_F(CliHostile, PipedProgressEndsEachLine) {
  const Result r = cloudviewer("render " + sample_ + " --time 1 --size 32x18 --accumulate 3 -o " + path("x.png") + " | cat");
  EXPECT_EQ(r.out.find('\r'), std::string::npos);
  for (int i = 1; i <= 3; ++i) {
    const std::string line = "accumulated " + std::to_string(i) + "/3 frames";
    const std::size_t at = r.out.find(line);
    ASSERT_NE(at, std::string::npos) << r.out;
    EXPECT_TRUE(at == 0 || r.out[at - 1] == '\n') << line << " does not start a line: " << r.out;
  }
}

TEST_F(CliHostile, AFailedImportLeavesNoPartOfItsSet) {
  // The second time step holds an impossible mixing ratio: the import fails there, after the first
  // step's VTI file was written. None of the set may appear, and an existing volume stays as it was.
  const std::string bad = path("bad.nc");
  {
    cv::test::NcBuilder b(bad);
    const int dt = b.dim("time", 2), dz = b.dim("level", 3), dy = b.dim("latitude", 3), dx = b.dim("longitude", 4);
    const int time = b.var("time", NC_DOUBLE, {dt}), lev = b.var("level", NC_DOUBLE, {dz});
    const int lat = b.var("latitude", NC_DOUBLE, {dy}), lon = b.var("longitude", NC_DOUBLE, {dx});
    b.text(time, "units", "hours since 2000-01-01 00:00:00");
    b.text(lev, "units", "hPa");
    b.text(lat, "units", "degrees_north");
    b.text(lon, "units", "degrees_east");
    const int clwc = b.var("clwc", NC_FLOAT, {dt, dz, dy, dx});
    b.text(clwc, "units", "kg kg-1");
    b.put(time, {0, 3});
    b.put(lev, {500, 700, 850});
    b.put(lat, {10, 11, 12});
    b.put(lon, {0, 1, 2, 3});
    std::vector<double> q(72, 1e-4);
    for (std::size_t i = 36; i < 72; ++i) q[i] = 1.0;  // 1 kg/kg at the second step
    b.put(clwc, q);
    b.close();
  }
  write("v.cvvol", "old volume");
  const Result r = cloudviewer("import " + bad + " -o " + path("v") + " --vti");
  EXPECT_EQ(r.rc, 2) << r.out;
  EXPECT_NE(r.out.find("importing time step 2/2"), std::string::npos) << r.out;  // it got as far as the second step
  EXPECT_NE(r.out.find("variable 'clwc' has value 1 at time step 1, expected a mixing ratio between 0 and 0.05 kg/kg"),
            std::string::npos)
      << r.out;  // it got as far as the second step
  EXPECT_EQ(read("v.cvvol"), "old volume");
  EXPECT_FALSE(fs::exists(path("v_t000.vti")));
  EXPECT_FALSE(fs::exists(path("v.report.json")));
  EXPECT_EQ(files(), 3u);  // in.nc, bad.nc, v.cvvol
}

// render --exr: the --pfm pair (radiance, transmittance) in one OpenEXR file, R, G, B and A = 1 - T,
// read here through OpenEXR itself; the path tracer's has R, G, B alone; its arguments are checked
// before the render like every output's.
TEST_F(CliHostile, ExrIsThePfmPairInOneFileAndItsArgumentsAreChecked) {
  const int w = 24, h = 14;
  const std::string size = " --size " + std::to_string(w) + "x" + std::to_string(h);
  Result r = cloudviewer("render " + sample_ + " --time 1" + size + " -o " + path("x.png") + " --pfm " + path("x.pfm") + " --exr " + path("x.exr"));
  ASSERT_EQ(r.rc, 0) << r.out;
  EXPECT_NE(r.out.find(path("x.exr") + " (radiance and coverage)"), std::string::npos) << r.out;
  // The PFM pair, rows bottom to top.
  auto pfm = [&](const std::string& name, int channels) {
    const std::string bytes = read(name);
    const std::string head = std::string(channels == 3 ? "PF" : "Pf") + "\n" + std::to_string(w) + " " + std::to_string(h) + "\n-1.0\n";
    EXPECT_EQ(bytes.substr(0, head.size()), head);
    std::vector<float> v(static_cast<std::size_t>(w) * h * channels);
    EXPECT_EQ(bytes.size(), head.size() + v.size() * sizeof(float));
    if (bytes.size() == head.size() + v.size() * sizeof(float)) std::memcpy(v.data(), bytes.data() + head.size(), v.size() * sizeof(float));
    return v;
  };
  const std::vector<float> rgb = pfm("x.pfm", 3), t = pfm("x.transmittance.pfm", 1);
  auto exr = [&](const std::string& name, int ew, int eh, std::vector<std::string>& channels) {
    Imf::InputFile file(path(name).c_str());
    const Imath::Box2i dw = file.header().dataWindow();
    EXPECT_EQ(dw.min.x, 0);
    EXPECT_EQ(dw.min.y, 0);
    EXPECT_EQ(dw.max.x, ew - 1);
    EXPECT_EQ(dw.max.y, eh - 1);
    for (auto it = file.header().channels().begin(); it != file.header().channels().end(); ++it) {
      channels.push_back(it.name());
      EXPECT_EQ(it.channel().type, Imf::FLOAT) << it.name();
    }
    std::vector<std::vector<float>> v(channels.size(), std::vector<float>(static_cast<std::size_t>(ew) * eh));
    Imf::FrameBuffer fb;
    for (std::size_t c = 0; c < channels.size(); ++c) {
      fb.insert(channels[c], Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(v[c].data()), sizeof(float), sizeof(float) * ew));
    }
    file.setFrameBuffer(fb);
    file.readPixels(0, eh - 1);
    return v;
  };
  std::vector<std::string> names;
  const auto e = exr("x.exr", w, h, names);  // A, B, G, R
  ASSERT_EQ(names, (std::vector<std::string>{"A", "B", "G", "R"}));
  std::size_t lit = 0, see_through = 0;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * w + x, j = static_cast<std::size_t>(h - 1 - y) * w + x;
      EXPECT_EQ(e[3][i], rgb[j * 3 + 0]) << x << "," << y;
      EXPECT_EQ(e[2][i], rgb[j * 3 + 1]) << x << "," << y;
      EXPECT_EQ(e[1][i], rgb[j * 3 + 2]) << x << "," << y;
      EXPECT_EQ(e[0][i], 1.0f - t[j]) << x << "," << y;
      lit += e[3][i] > 0.0f ? 1 : 0;
      see_through += e[0][i] < 1.0f ? 1 : 0;
    }
  }
  EXPECT_GT(lit, 0u);          // not an empty image
  EXPECT_GT(see_through, 0u);  // and not all opaque: the coverage is the transmittance's
  // The path tracer: radiance alone.
  r = cloudviewer("render " + sample_ + " --time 1 --size 8x5 --quality reference --spp 2 -o " + path("p.png") + " --exr " + path("p.exr"));
  ASSERT_EQ(r.rc, 0) << r.out;
  EXPECT_NE(r.out.find(path("p.exr") + " (radiance)"), std::string::npos) << r.out;
  names.clear();
  exr("p.exr", 8, 5, names);
  EXPECT_EQ(names, (std::vector<std::string>{"B", "G", "R"}));
  // Arguments.
  expect_refused(cloudviewer("render " + sample_ + " -o " + path("y.png") + " --exr " + path("y.pfm")),
                 "--exr: found '" + path("y.pfm") + "', expected a file name ending in .exr");
  expect_refused(cloudviewer("render " + sample_ + " -o " + path("y.png") + " --exr " + path("no/such/y.exr")),
                 "--exr: found '" + path("no/such/y.exr") + "': its folder '" + path("no/such") + "' does not exist");
  expect_refused(cloudviewer("render " + sample_ + " -o " + path("frames") + " --times 2000-01-01T00:00Z..2000-01-01T01:00Z --every 30m --exr " +
                             path("y.exr")),
                 "--times: found it with --pfm, --exr");
  EXPECT_FALSE(fs::exists(path("y.png")));
  EXPECT_FALSE(fs::exists(path("y.exr")));
}

// The environment is input too: a value the program would not use is refused, not ignored.
TEST_F(CliHostile, UnknownEnvironmentValuesAreRefused) {
  expect_refused(cloudviewer("info " + sample_, "CLOUDVIEWER_CPU=Baseline "), "CLOUDVIEWER_CPU: found 'Baseline', expected baseline (or unset)");
  expect_refused(cloudviewer("info " + sample_, "CLOUDVIEWER_THREADS=lots "),
                 "CLOUDVIEWER_THREADS: found 'lots', expected a whole number of threads 1..4096");
  expect_refused(cloudviewer("info " + sample_, "CLOUDVIEWER_THREADS=0 "), "CLOUDVIEWER_THREADS: found '0'");
  const Result ok = cloudviewer("info " + sample_, "CLOUDVIEWER_CPU=baseline CLOUDVIEWER_THREADS=1 ");
  EXPECT_EQ(ok.rc, 0) << ok.out;
}

TEST_F(CliHostile, AFullDiskNamesTheOutput) {
  const Result r = cloudviewer("import " + sample_ + " --times 0:0 -o " + path("v"), "ulimit -f 64; trap '' XFSZ; ");
  EXPECT_EQ(r.rc, 1) << r.out;
  EXPECT_NE(r.out.find(path("v.cvvol") + ": write failed (File too large)"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(path("v.cvvol")));
}

}  // namespace
