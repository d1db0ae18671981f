// The background writer: every byte arrives, in order, whatever the chunking, with direct I/O and
// without; a failure of the disk is one WriteError; written volumes read back unchanged.
#include <gtest/gtest.h>

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstring>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include "io/background_writer.hpp"
#include "io/input_file.hpp"
#include "io/output_file.hpp"

namespace {
using namespace cv::core;
namespace fs = std::filesystem;

class BackgroundWriterTest : public ::testing::Test {
 protected:
  void SetUp() override {
    // Beside the build, not in /tmp: a tmpfs there takes no direct I/O and would test one path only.
    dir_ = fs::current_path() / ("cv_bgwriter_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  static std::string read(const std::string& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  }
  fs::path dir_;
};

// Pieces of random lengths, through room()/commit() and write(), against the same bytes kept here.
std::string write_pieces(std::FILE* f, BackgroundWriter::Options o, std::uint32_t seed, bool* direct) {
  std::mt19937 rng(seed);
  std::string expected;
  BackgroundWriter w(f, o);
  for (int piece = 0; piece < 300; ++piece) {
    const std::size_t n = std::uniform_int_distribution<std::size_t>(0, 3 * o.chunk_bytes)(rng);
    std::string bytes(n, '\0');
    for (char& c : bytes) c = static_cast<char>(rng());
    expected += bytes;
    if (piece % 2) {
      w.write(bytes.data(), bytes.size());
    } else {
      std::size_t at = 0;
      while (at < n) {
        const std::span<std::byte> r = w.room();
        EXPECT_FALSE(r.empty());
        if (r.empty()) break;
        const std::size_t k = std::min(n - at, r.size());
        std::memcpy(r.data(), bytes.data() + at, k);
        w.commit(k);
        at += k;
      }
    }
  }
  w.finish();
  *direct = w.direct();
  EXPECT_EQ(w.bytes_committed(), expected.size());
  return expected;
}

TEST_F(BackgroundWriterTest, EveryByteArrivesInOrderWithAndWithoutDirectIo) {
  for (bool direct : {true, false}) {
    for (std::size_t chunk : {std::size_t(4096), std::size_t(3 * 4096)}) {
      SCOPED_TRACE(std::string(direct ? "direct" : "buffered") + ", chunk " + std::to_string(chunk));
      const std::string p = path("pieces.bin");
      std::string expected;
      bool went_direct = false;
      write_file_atomically(p, [&](std::FILE* f) {
        expected = write_pieces(f, {chunk, 3, direct}, static_cast<std::uint32_t>(chunk + direct), &went_direct);
        // The FILE goes on after the writer: it is positioned at the end.
        std::fputs("tail", f);
        expected += "tail";
      });
      EXPECT_EQ(read(p), expected);
      if (!direct) {
        EXPECT_FALSE(went_direct);
      }
      std::printf("chunk %zu: direct I/O %s\n", chunk, went_direct ? "used" : direct ? "refused by the file system" : "off");
    }
  }
}

TEST_F(BackgroundWriterTest, StartsAfterWhatTheFileAlreadyHolds) {
  // An unaligned start: no direct I/O, and the bytes follow what the FILE had buffered.
  const std::string p = path("after.bin");
  write_file_atomically(p, [&](std::FILE* f) {
    std::fputs("head", f);
    BackgroundWriter w(f, {4096, 2, true});
    EXPECT_FALSE(w.direct());
    w.write("body", 4);
    w.finish();
  });
  EXPECT_EQ(read(p), "headbody");
}

TEST_F(BackgroundWriterTest, AFullDiskIsOneWriteError) {
  // The file size limit stands in for a full disk: the writer thread's write fails with EFBIG,
  // and the caller gets it as a WriteError from room(), write() or finish(), not a crash or a hang.
  const pid_t pid = ::fork();
  if (pid == 0) {
    std::signal(SIGXFSZ, SIG_IGN);
    const rlimit lim{1 << 16, 1 << 16};
    ::setrlimit(RLIMIT_FSIZE, &lim);
    std::string msg;
    try {
      write_file_atomically(path("big.bin"), [](std::FILE* f) {
        BackgroundWriter w(f, {4096, 2, true});
        const std::string block(1 << 20, 'x');
        for (int i = 0; i < 8; ++i) w.write(block.data(), block.size());
        w.finish();
      });
    } catch (const std::exception& e) {
      msg = e.what();
    }
    ::_exit(msg.find("big.bin: write failed (File too large)") != std::string::npos ? 0 : 1);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  EXPECT_FALSE(fs::exists(path("big.bin")));
}

}  // namespace

namespace cv::core {
namespace {
// populate_pages is advice: the pages it faults in keep what they hold, from an unaligned start
// and length, on a buffer large enough to be split between threads; null and small buffers are
// left alone.
TEST(PopulatePages, KeepsWhatTheBufferHolds) {
  std::vector<float> v;
  v.reserve((std::size_t(48) << 20) / sizeof(float) + 7);  // 48 MB: split between threads
  v.resize(v.capacity());
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = static_cast<float>(i % 1000003) * 0.5f;
  populate_pages(reinterpret_cast<char*>(v.data()) + 3, v.size() * sizeof(float) - 5);
  std::size_t wrong = 0;
  for (std::size_t i = 0; i < v.size(); ++i) wrong += v[i] != static_cast<float>(i % 1000003) * 0.5f;
  EXPECT_EQ(wrong, 0u);
  populate_pages(nullptr, std::size_t(1) << 30);
  float small[16] = {1.0f};
  populate_pages(small, sizeof small);
  EXPECT_EQ(small[0], 1.0f);
}
}  // namespace
}  // namespace cv::core
