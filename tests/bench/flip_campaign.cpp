// A byte-level fuzzing campaign over whole real files, for the NetCDF-4 (HDF5) files that
// libFuzzer's size limit keeps out of fuzz/ (issue 13): each input is a real file with a few
// flipped bits (anywhere, or in its first 4 KiB where the HDF5 superblock and root headers lie),
// a run of random bytes written into its first 64 KiB, or the file cut short. Each input is imported
// in a child process as `info` and `import` would (describe_file, import_file, every time step
// up to 4 loaded): exit 0 imported, 2 refused with an InputError (counted apart when the refusal
// says the HDF5 library crashed or hung in NcFile's reader process; a few of those inputs kept). Anything else is a finding:
// another exception, a signal (a crash of our code; a crash of HDF5 must come back as an
// ImportError from NcFile's reader process), or no end within 150 s (a hang; the reader's own waits
// are set to 30 s for the header and 60 s for a read unless the environment sets them). Findings
// are kept under OUT_DIR with what happened.
//   bench_flip_campaign OUT_DIR INPUTS SEED FILE.nc...
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include "importer.hpp"

namespace fs = std::filesystem;

namespace {

int import_one(const std::string& path) {
  try {
    (void)cv::importers::describe_file(path);
  } catch (const cv::core::InputError&) {
  }
  try {
    cv::importers::ImportOptions o;
    o.cache_steps = 1;
    cv::core::CloudVolume v = cv::importers::import_file(path, o);
    for (std::size_t t = 0; t < v.times.size() && t < 4; ++t) (void)v.step(t);
  } catch (const cv::core::InputError& e) {
    // Refused; counted apart when the HDF5 library crashed or hung in NcFile's reader process.
    const std::string m = e.what();
    if (m.find("the NetCDF-4/HDF5 library crashed") != std::string::npos) return 4;
    if (m.find("the NetCDF-4/HDF5 library did not answer") != std::string::npos) return 5;
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "not an InputError: %s\n", e.what());
    return 3;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 5 || std::string(argv[1]) == "--help") {
    std::fprintf(stderr, "usage: bench_flip_campaign OUT_DIR INPUTS SEED FILE.nc...\n");
    return argc >= 2 && std::string(argv[1]) == "--help" ? 0 : 2;
  }
  ::setenv("CLOUDVIEWER_OPEN_TIMEOUT_S", "30", 0);
  ::setenv("CLOUDVIEWER_READ_TIMEOUT_S", "60", 0);
  const fs::path out = argv[1];
  const long inputs = std::atol(argv[2]);
  std::mt19937_64 rng(std::strtoull(argv[3], nullptr, 10));
  std::vector<std::string> files(argv + 4, argv + argc);
  std::vector<std::vector<char>> data;
  for (const auto& f : files) {
    std::ifstream in(f, std::ios::binary);
    data.emplace_back(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    if (data.back().empty()) {
      std::fprintf(stderr, "%s: cannot read it or it is empty\n", f.c_str());
      return 2;
    }
  }
  fs::create_directories(out);
  const fs::path work = out / ("input-" + std::to_string(::getpid()) + ".nc");
  long imported = 0, refused = 0, reader_crashed = 0, reader_hung = 0, findings = 0;
  const auto t0 = std::chrono::steady_clock::now();
  for (long i = 0; i < inputs; ++i) {
    const std::size_t which = rng() % files.size();
    std::vector<char> b = data[which];
    std::string kind;
    const unsigned pick = static_cast<unsigned>(rng() % 10);
    if (pick < 7) {  // bit flips
      const bool head = rng() % 2;
      const std::size_t span = head ? std::min<std::size_t>(b.size(), 4096) : b.size();
      const int n = 1 + static_cast<int>(rng() % 8);
      for (int k = 0; k < n; ++k) b[rng() % span] ^= static_cast<char>(1u << (rng() % 8));
      kind = std::to_string(n) + (head ? " flips in the first 4 KiB" : " flips anywhere");
    } else if (pick < 9) {  // random bytes over a header region
      const std::size_t span = std::min<std::size_t>(b.size(), 65536);
      const std::size_t at = rng() % span, len = 1 + rng() % 16;
      for (std::size_t k = at; k < std::min(b.size(), at + len); ++k) b[k] = static_cast<char>(rng());
      kind = std::to_string(len) + " random bytes at " + std::to_string(at);
    } else {  // cut short
      b.resize(rng() % b.size());
      kind = "cut at " + std::to_string(b.size());
    }
    {
      std::ofstream o(work, std::ios::binary | std::ios::trunc);
      o.write(b.data(), static_cast<std::streamsize>(b.size()));
    }
    std::fflush(nullptr);
    const pid_t pid = ::fork();
    if (pid == 0) {
      ::alarm(150);  // a hang: SIGALRM
      ::_exit(import_one(work.string()));
    }
    int status = 0;
    ::waitpid(pid, &status, 0);
    if (WIFEXITED(status) && WEXITSTATUS(status) == 0) {
      ++imported;
    } else if (WIFEXITED(status) && WEXITSTATUS(status) == 2) {
      ++refused;
    } else if (WIFEXITED(status) && (WEXITSTATUS(status) == 4 || WEXITSTATUS(status) == 5)) {
      ++(WEXITSTATUS(status) == 4 ? reader_crashed : reader_hung);
      if (reader_crashed + reader_hung <= 20) {  // a few kept, to see what HDF5 does not survive
        const fs::path keep = out / ("hdf5-" + std::to_string(i) + "-" + fs::path(files[which]).filename().string());
        fs::copy_file(work, keep, fs::copy_options::overwrite_existing);
      }
    } else {
      ++findings;
      const std::string what = WIFSIGNALED(status) ? (WTERMSIG(status) == SIGALRM ? "hang (150 s)" : std::string("signal ") + strsignal(WTERMSIG(status)))
                                                   : "exit " + std::to_string(WEXITSTATUS(status));
      const fs::path keep = out / ("finding-" + std::to_string(i) + "-" + fs::path(files[which]).filename().string());
      fs::copy_file(work, keep, fs::copy_options::overwrite_existing);
      std::printf("finding %ld: %s on %s (%s), kept as %s\n", i, what.c_str(), files[which].c_str(), kind.c_str(), keep.c_str());
    }
    if ((i + 1) % 100 == 0 || i + 1 == inputs) {
      const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      std::printf("%ld inputs in %.0f s: %ld imported, %ld refused (exit 2), of them %ld as HDF5 crashed and %ld as it hung in the reader "
                  "process; %ld findings\n",
                  i + 1, s, imported, refused + reader_crashed + reader_hung, reader_crashed, reader_hung, findings);
      std::fflush(stdout);
    }
  }
  fs::remove(work);
  return findings ? 1 : 0;
}
