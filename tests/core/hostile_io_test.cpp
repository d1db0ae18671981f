// Hostile files and unsafe writes (issue 13): FIFOs, devices, deep and huge JSON, corrupt .cvvol
// headers, planted symbolic links, failures and signals in the middle of a write. Every file is
// written by the test itself.
#include <algorithm>
#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>

#include "io/input_file.hpp"
#include "io/output_file.hpp"
#include "scene/scene_json.hpp"
#include "volume/volume_io.hpp"

namespace {
using namespace cv::core;
namespace fs = std::filesystem;

class HostileInput : public ::testing::Test {
 protected:
  void SetUp() override {
    // A parameterised test's name holds a '/' ("Name/0"): one folder, not a folder left behind
    // around the one removed.
    std::string name = ::testing::UnitTest::GetInstance()->current_test_info()->name();
    std::replace(name.begin(), name.end(), '/', '_');
    dir_ = fs::temp_directory_path() / ("cv_hostile_" + std::to_string(::getpid()) + "_" + name);
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    OutputFile::set_unnamed_temporaries(true);
    fs::remove_all(dir_);
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  void write(const std::string& name, const std::string& bytes) const {
    std::ofstream(path(name), std::ios::binary) << bytes;
  }
  std::string read(const std::string& name) const {
    std::ifstream in(path(name), std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
  }
  std::set<std::string> listing() const {
    std::set<std::string> out;
    for (const auto& e : fs::directory_iterator(dir_)) out.insert(e.path().filename().string());
    return out;
  }
  fs::path dir_;
};

template <class F>
std::string error_of(F f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "(no error)";
}

// A .cvvol of one step of a 2 x 2 x 2 grid with one field, whose header is `header`.
std::string cvvol_bytes(const std::string& header, std::size_t payload_bytes) {
  std::string out = "CVVOL01\n";
  const std::uint64_t len = header.size();
  out.append(reinterpret_cast<const char*>(&len), sizeof len);
  out += header;
  out.append(payload_bytes, '\0');
  return out;
}
std::string header_with(const std::string& lon_step, const std::string& radius = "6371000", const std::string& fields = "[\"cloud_fraction\"]",
                        const std::string& counts = "2") {
  return "{\"format\": \"cvvol\", \"version\": 1, \"grid\": {\"lon_deg\": {\"start\": 0, \"step\": " + lon_step + ", \"count\": " + counts +
         "}, \"lat_deg\": {\"start\": 0, \"step\": 1, \"count\": " + counts + "}, \"alt_m\": {\"start\": 0, \"step\": 100, \"count\": " +
         counts + "}, \"earth_radius_m\": " + radius + "}, \"liquid_r_eff_um\": 10, \"times\": [{\"iso_utc\": \"2024-01-01T00:00:00Z\", "
         "\"unix_s\": 1704067200}], \"fields\": " + fields + ", \"maps\": []}\n";
}
std::string with_unix_s(const std::string& unix_s) {
  std::string h = header_with("1");
  return h.replace(h.find("1704067200"), 10, unix_s);
}
// 8 points of one field and 7 maps of 4 columns, as float32.
constexpr std::size_t kPayload = (8 + 7 * 4) * 4;

TEST_F(HostileInput, CvvolHeaderValuesAreCheckedAndNamed) {
  write("ok.cvvol", cvvol_bytes(header_with("1"), kPayload));
  EXPECT_EQ(read_cvvol(path("ok.cvvol")).grid.lon_deg.count, 2);  // the reference: a valid one reads
  const std::pair<std::string, std::string> cases[] = {
      {header_with("NaN"), "header key 'step': found 'NaN"},
      {header_with("0"), "axis lon_deg: found start 0, step 0, count 2; expected a finite start, a step > 0"},
      {header_with("-1"), "axis lon_deg: found start 0, step -1"},
      {header_with("1", "0"), "earth_radius_m: found 0, expected 1e6..1e8 m"},
      {header_with("1", "-6371000"), "earth_radius_m: found -6.371e+06"},
      {header_with("1", "NaN"), "header key 'earth_radius_m': found 'NaN"},
      {header_with("abc"), "header key 'step': found 'abc"},  // was std::stod's "stod", exit 1
      // A time beyond int64's range was converted to an integer: undefined behaviour (fuzzer).
      {with_unix_s("1e300"), "header key 'unix_s': found 1.0000000000000001e+300, expected whole seconds within +-1e12 of 1970"},
      {with_unix_s("-1e19"), "header key 'unix_s': found -1e+19"},
      {with_unix_s("0.5"), "header key 'unix_s': found 0.5"},
  };
  for (const auto& [header, expected] : cases) {
    write("bad.cvvol", cvvol_bytes(header, kPayload));
    const std::string msg = error_of([&] { read_cvvol(path("bad.cvvol")); });
    EXPECT_NE(msg.find(path("bad.cvvol") + ": "), std::string::npos) << msg;
    EXPECT_NE(msg.find(expected), std::string::npos) << msg << "\n expected: " << expected;
  }
}

TEST_F(HostileInput, CvvolUnterminatedFieldNameIsRefusedNotLoopedOn) {
  // The name's closing quote is missing: the reader pushed strings until memory ran out.
  write("open.cvvol", cvvol_bytes(header_with("1", "6371000", "[\"cloud_fraction]"), kPayload));
  const std::string msg = error_of([&] { read_cvvol(path("open.cvvol")); });
  EXPECT_NE(msg.find("header key 'fields'"), std::string::npos) << msg;
}

TEST_F(HostileInput, CvvolDeclaringAHugeGridIsRefusedBeforeAllocating) {
  // 524288 x 524288 x 419429 points: step_bytes * steps wrapped to a small number, and a
  // header-only file passed the size check. Axis counts above 1e6 are refused; just below, the
  // product is checked against the memory limit.
  const std::string huge = "{\"format\": \"cvvol\", \"grid\": {\"lon_deg\": {\"start\": 0, \"step\": 0.0001, \"count\": 1000000}, "
                           "\"lat_deg\": {\"start\": 0, \"step\": 0.00005, \"count\": 1000000}, \"alt_m\": {\"start\": 0, \"step\": "
                           "0.0001, \"count\": 1000000}, \"earth_radius_m\": 6371000}, \"times\": [{\"iso_utc\": \"x\", \"unix_s\": 0}], "
                           "\"fields\": [\"cloud_fraction\"]}";
  write("huge.cvvol", cvvol_bytes(huge, 0));
  const std::string msg = error_of([&] { read_cvvol(path("huge.cvvol")); });
  EXPECT_NE(msg.find("one time step of 1000000 x 1000000 x 1000000 points would take"), std::string::npos) << msg;
  EXPECT_NE(msg.find("expected at most the memory limit"), std::string::npos) << msg;
  write("count.cvvol", cvvol_bytes(header_with("1", "6371000", "[\"cloud_fraction\"]", "524288000"), 0));
  EXPECT_NE(error_of([&] { read_cvvol(path("count.cvvol")); }).find("count: found 524288000, expected an integer 1..1000000"),
            std::string::npos);
}

TEST_F(HostileInput, FifosAndDevicesAreRefusedUpFrontNotReadForever) {
  ASSERT_EQ(::mkfifo(path("pipe.json").c_str(), 0600), 0);
  ASSERT_EQ(::mkfifo(path("pipe.cvvol").c_str(), 0600), 0);
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_EQ(error_of([&] { load_scene(path("pipe.json")); }), path("pipe.json") + ": the scene file is a FIFO (named pipe), expected a regular file");
  EXPECT_EQ(error_of([&] { read_cvvol(path("pipe.cvvol")); }),
            path("pipe.cvvol") + ": the cloud volume is a FIFO (named pipe), expected a regular file");
  EXPECT_EQ(error_of([&] { load_scene("/dev/zero"); }), "/dev/zero: the scene file is a character device, expected a regular file");
  EXPECT_EQ(error_of([&] { read_regular_file(dir_.string(), "the input", 10); }), dir_.string() + ": the input is a directory, expected a regular file");
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 5.0);
  // A symbolic link to a regular file is followed; one to a FIFO is refused as the FIFO is.
  write("real.json", "{\"version\": 1}");
  fs::create_symlink(path("real.json"), path("link.json"));
  fs::create_symlink(path("pipe.json"), path("link_pipe.json"));
  EXPECT_NO_THROW(load_scene(path("link.json")));
  EXPECT_NE(error_of([&] { load_scene(path("link_pipe.json")); }).find("is a FIFO"), std::string::npos);
}

TEST_F(HostileInput, DeeplyNestedSceneIsRefusedWithoutOverflowingTheStack) {
  const std::string deep = "{\"version\": 1, \"data\": " + std::string(100000, '[') + std::string(100000, ']') + "}";
  EXPECT_EQ(error_of([&] { scene_from_json(deep, "deep.json"); }),
            "deep.json: found values nested more than 32 levels deep, expected a scene object (docs/scene.md)");
  const std::string top = std::string(100000, '[') + std::string(100000, ']');
  EXPECT_NE(error_of([&] { scene_from_json(top, "top.json"); }).find("nested more than 32"), std::string::npos);
  // A wide value in an error is shown in 40 characters, not dumped whole.
  std::string wide = "{\"version\": 1, \"camera\": [";
  for (int i = 0; i < 200000; ++i) wide += "1,";
  wide += "1]}";
  const std::string msg = error_of([&] { scene_from_json(wide, "wide.json"); });
  EXPECT_EQ(msg, "wide.json: camera: found [1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,..., expected an object { ... }");
}

TEST_F(HostileInput, NumberBeyondADoubleIsNamed) {
  EXPECT_EQ(error_of([] { scene_from_json(R"({"version": 1, "width": 1e400})", "big.json"); }),
            "big.json: found the number '1e400', expected a finite number (at most 1.8e308 in size)");
}

TEST_F(HostileInput, GroundTextureIsTakenFromTheScenesFolder) {
  fs::create_directories(dir_ / "scenes");
  write("scenes/s.json", R"({"version": 1, "data": {"path": "d.nc"}, "render": {"march": {"ground_texture": "relief.png"}}})");
  const Scene s = load_scene(path("scenes/s.json"));
  EXPECT_EQ(s.render.march.medium.ground_texture, path("scenes/relief.png"));
  EXPECT_EQ(s.data.path, path("scenes/d.nc"));
  write("scenes/none.json", R"({"version": 1, "render": {"march": {"ground_texture": "none"}}})");
  EXPECT_EQ(load_scene(path("scenes/none.json")).render.march.medium.ground_texture, "none");
}

TEST_F(HostileInput, ASceneFileWritesNothingAndRunsNothing) {
  // Paths and strings an attacker would try: the reader only reads, and resolves paths as text.
  write("evil.json", R"J({"version": 1, "data": {"path": "../../../tmp/$(touch pwned_data)"},
    "render": {"march": {"ground_texture": "`touch pwned_texture`; rm -rf ."}},
    "sun": {"mode": "datetime", "datetime_utc": "2024-01-01T00:00:00Z"}, "overlays": ["$(touch pwned_overlay)"]})J");
  const auto before = listing();
  const fs::path cwd = fs::current_path();
  fs::current_path(dir_);
  // An overlay is a name from the overlay table: anything else is refused, and nothing is run.
  std::string error;
  try {
    load_scene("evil.json");
  } catch (const SceneError& e) {
    error = e.what();
  }
  fs::current_path(cwd);
  EXPECT_EQ(error, "evil.json: overlays[0]: found \"$(touch pwned_overlay)\", expected one of coastlines, borders, rivers, graticule, isosurface, wind, arrows, section");
  EXPECT_EQ(listing(), before);
  EXPECT_FALSE(fs::exists("pwned_data") || fs::exists("pwned_texture") || fs::exists("pwned_overlay"));
  // Without the overlay the same file loads, its strings kept as text.
  write("evil2.json", R"J({"version": 1, "data": {"path": "../../../tmp/$(touch pwned_data)"},
    "render": {"march": {"ground_texture": "`touch pwned_texture`; rm -rf ."}}})J");
  fs::current_path(dir_);
  Scene s;
  EXPECT_NO_THROW(s = load_scene("evil2.json"));
  fs::current_path(cwd);
  EXPECT_FALSE(fs::exists("pwned_data") || fs::exists("pwned_texture"));
}

TEST_F(HostileInput, SizesAreMultipliedWithOverflowChecks) {
  EXPECT_EQ(checked_product({524288, 524288, 419429}), std::optional<std::uint64_t>(524288ull * 524288ull * 419429ull));
  EXPECT_EQ(checked_product({1ull << 32, 1ull << 32}), std::nullopt);
  EXPECT_EQ(checked_product({524288, 524288, 419429, 1024}), std::nullopt);
  EXPECT_EQ(parse_byte_size("4G"), std::optional<std::uint64_t>(4ull << 30));
  EXPECT_EQ(parse_byte_size("512M"), std::optional<std::uint64_t>(512ull << 20));
  EXPECT_EQ(parse_byte_size("-1"), std::nullopt);
  EXPECT_EQ(parse_byte_size("lots"), std::nullopt);
  EXPECT_GE(memory_limit_bytes(), 256u << 20);  // from the machine's memory
  set_memory_limit_bytes(1000);
  EXPECT_EQ(memory_limit_bytes(), 1000u);
  EXPECT_NE(error_of([] { require_within_memory_limit("f.nc", "variable 'x'", 2000); }),
            "(no error)");
  EXPECT_EQ(error_of([] { require_within_memory_limit("f.nc", "variable 'x'", std::nullopt); }),
            "f.nc: variable 'x' would take more than 2^64 bytes, expected at most the memory limit 1000 bytes (set "
            "CLOUDVIEWER_MEMORY_LIMIT to change it)");
  set_memory_limit_bytes(0);
}

class OutputFiles : public HostileInput, public ::testing::WithParamInterface<bool> {
 protected:
  void SetUp() override {
    HostileInput::SetUp();
    OutputFile::set_unnamed_temporaries(GetParam());
  }
};

TEST_P(OutputFiles, APlantedSymlinkIsNeverFollowed) {
  // The old temporary name was predictable (OUT.tmp-PID) and opened without O_EXCL: a link planted
  // there sent the write to its target.
  write("victim.txt", "precious");
  fs::create_symlink(path("victim.txt"), path("out.png.tmp-" + std::to_string(::getpid())));
  write_file_atomically(path("out.png"), [](std::FILE* f) { std::fputs("image", f); });
  EXPECT_EQ(read("victim.txt"), "precious");
  EXPECT_EQ(read("out.png"), "image");
  EXPECT_EQ(listing(), (std::set<std::string>{"out.png", "out.png.tmp-" + std::to_string(::getpid()), "victim.txt"}));
  // An output that is itself a link is replaced, its target left alone.
  fs::create_symlink(path("victim.txt"), path("link.png"));
  write_file_atomically(path("link.png"), [](std::FILE* f) { std::fputs("new", f); });
  EXPECT_EQ(read("victim.txt"), "precious");
  EXPECT_FALSE(fs::is_symlink(path("link.png")));
  EXPECT_EQ(fs::status(path("out.png")).permissions() & fs::perms::owner_read, fs::perms::owner_read);
}

TEST_P(OutputFiles, AFailedWriteLeavesTheOldFileAndNoTemporary) {
  write("out.cvvol", "old");
  EXPECT_THROW(write_file_atomically(path("out.cvvol"), [](std::FILE* f) {
                 std::fputs("half", f);
                 throw std::runtime_error("bad data at step 2");
               }),
               std::runtime_error);
  EXPECT_EQ(read("out.cvvol"), "old");
  EXPECT_EQ(listing(), std::set<std::string>{"out.cvvol"});
}

TEST_P(OutputFiles, AGroupIsCommittedTogetherOrNotAtAll) {
  write("a.png", "old a");
  {  // the second member fails while it is written: neither appears, the old one stays
    OutputGroup g;
    g.write(path("a.png"), [](std::FILE* f) { std::fputs("new a", f); });
    EXPECT_THROW(g.write(path("a.pfm"), [](std::FILE*) { throw WriteError("write failed (No space left on device)"); }),
                 std::runtime_error);
  }
  EXPECT_EQ(read("a.png"), "old a");
  EXPECT_EQ(listing(), std::set<std::string>{"a.png"});
  {  // the second member cannot take its place (a folder is there): the first is put back
    fs::create_directories(dir_ / "b.pfm" / "inside");
    OutputGroup g;
    g.write(path("a.png"), [](std::FILE* f) { std::fputs("new a", f); });
    g.write(path("b.pfm"), [](std::FILE* f) { std::fputs("new b", f); });
    const std::string msg = error_of([&] { g.commit(); });
    EXPECT_NE(msg.find(path("b.pfm") + ": cannot rename into place"), std::string::npos) << msg;
  }
  EXPECT_EQ(read("a.png"), "old a");
  EXPECT_EQ(listing(), (std::set<std::string>{"a.png", "b.pfm"}));
  {  // and both, when both can
    fs::remove_all(dir_ / "b.pfm");
    OutputGroup g;
    g.write(path("a.png"), [](std::FILE* f) { std::fputs("new a", f); });
    g.write(path("b.pfm"), [](std::FILE* f) { std::fputs("new b", f); });
    g.commit();
  }
  EXPECT_EQ(read("a.png"), "new a");
  EXPECT_EQ(read("b.pfm"), "new b");
  EXPECT_EQ(listing(), (std::set<std::string>{"a.png", "b.pfm"}));
}

// In a child: starts writing `out`, says so on `ready`, and waits to be killed.
[[noreturn]] void write_and_wait(const std::string& out, int ready, bool unnamed) {
  OutputFile::set_unnamed_temporaries(unnamed);
  install_output_cleanup();
  OutputFile f(out);
  std::fputs("partial", f.stream());
  std::fflush(f.stream());
  const char c = 'x';
  if (::write(ready, &c, 1) != 1) ::_exit(3);
  for (;;) ::pause();
}

TEST_P(OutputFiles, SignalsLeaveNoTemporaryBehind) {
  for (int sig : {SIGTERM, SIGINT, SIGKILL}) {
    if (sig == SIGKILL && !GetParam()) continue;  // no handler runs on SIGKILL: only an unnamed temporary leaves nothing
    int fds[2];
    ASSERT_EQ(::pipe(fds), 0);
    const pid_t pid = ::fork();
    if (pid == 0) write_and_wait(path("out.png"), fds[1], GetParam());
    char c = 0;
    ASSERT_EQ(::read(fds[0], &c, 1), 1);
    if (!GetParam()) {  // the named temporary is there while the write runs
      bool temp = false;
      for (const auto& n : listing()) temp = temp || n.find(".out.png.cvtmp-") == 0;
      EXPECT_TRUE(temp);
    }
    ::kill(pid, sig);
    int status = 0;
    ::waitpid(pid, &status, 0);
    ::close(fds[0]), ::close(fds[1]);
    EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == sig) << "signal " << sig;
    EXPECT_EQ(listing(), std::set<std::string>{}) << "after signal " << sig;
  }
}

TEST_P(OutputFiles, AFullDiskNamesThePath) {
  // The file size limit stands in for a full disk: writes fail with EFBIG (SIGXFSZ ignored).
  const pid_t pid = ::fork();
  if (pid == 0) {
    OutputFile::set_unnamed_temporaries(GetParam());
    std::signal(SIGXFSZ, SIG_IGN);
    const rlimit lim{4096, 4096};
    ::setrlimit(RLIMIT_FSIZE, &lim);
    const std::string msg = error_of([&] {
      write_file_atomically(path("big.cvvol"), [](std::FILE* f) {
        const std::string block(65536, 'x');
        if (std::fwrite(block.data(), 1, block.size(), f) != block.size()) throw WriteError("write failed (File too large)");
      });
    });
    ::_exit(msg.rfind(path("big.cvvol") + ": write failed (File too large)", 0) == 0 ? 0 : 1);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  EXPECT_EQ(listing(), std::set<std::string>{});
}

INSTANTIATE_TEST_SUITE_P(UnnamedAndNamedTemporaries, OutputFiles, ::testing::Bool(),
                         [](const ::testing::TestParamInfo<bool>& i) { return i.param ? std::string("O_TMPFILE") : std::string("Named"); });

TEST_F(HostileInput, OutputPathsAreCheckedBeforeAnyWork) {
  EXPECT_EQ(error_of([&] { check_output_path(path("no/such/out.png"), "-o"); }),
            "cloudviewer: -o: found '" + path("no/such/out.png") + "': its folder '" + path("no/such") +
                "' does not exist, expected an existing folder");
  EXPECT_EQ(error_of([&] { check_output_path(dir_.string(), "-o"); }), "cloudviewer: -o: found '" + dir_.string() + "': it is a folder, expected a file name");
  write("file", "x");
  EXPECT_NE(error_of([&] { check_output_path(path("file/out.png"), "-o"); }).find("is not a folder"), std::string::npos);
  EXPECT_EQ(error_of([&] { check_output_extension("x.mp4", "-o", {".png"}); }),
            "cloudviewer: -o: found 'x.mp4', expected a file name ending in .png (the only format it writes)");
  EXPECT_NO_THROW(check_output_extension("X.PNG", "-o", {".png"}));
  // The same file under another name: a link and a path through "..".
  fs::create_directories(dir_ / "sub");
  fs::create_symlink(path("file"), path("alias"));
  EXPECT_TRUE(same_file(path("alias"), path("file")));
  EXPECT_TRUE(same_file(path("sub/../file"), path("file")));
  EXPECT_FALSE(same_file(path("sub/../other"), path("file")));
  EXPECT_NE(error_of([&] { check_output_not_input(path("alias"), "--pfm", path("file"), "the input"); }).find("which is the input"),
            std::string::npos);
}

}  // namespace
