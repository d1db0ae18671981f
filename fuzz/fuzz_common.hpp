// What the fuzz targets share: an input as a regular file the readers can open by path (a memfd,
// reached through /proc/self/fd, so no disk is written per input), and a memory limit well under
// libFuzzer's RSS limit, so a declared size is refused by our check, not by the fuzzer.
#pragma once

#include <sys/mman.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <string>

#include "io/input_file.hpp"

namespace cv::fuzz {

class MemFile {
 public:
  MemFile(const std::uint8_t* data, std::size_t size, const char* suffix) {
    fd_ = ::memfd_create("cv-fuzz", MFD_CLOEXEC);
    std::size_t done = 0;
    while (fd_ >= 0 && done < size) {
      const ssize_t n = ::write(fd_, data + done, size - done);
      if (n <= 0) break;
      done += static_cast<std::size_t>(n);
    }
    // The readers pick the format by the name's ending (.cvvol, .json): a link named so.
    link_ = "/tmp/cv-fuzz-" + std::to_string(::getpid()) + suffix;
    ::unlink(link_.c_str());
    if (::symlink(("/proc/self/fd/" + std::to_string(fd_)).c_str(), link_.c_str()) != 0) link_.clear();
  }
  ~MemFile() {
    if (!link_.empty()) ::unlink(link_.c_str());
    if (fd_ >= 0) ::close(fd_);
  }
  const std::string& path() const { return link_; }

 private:
  int fd_ = -1;
  std::string link_;
};

inline void limit_memory() {
  static const bool once = [] {
    core::set_memory_limit_bytes(std::uint64_t(512) << 20);
    return true;
  }();
  (void)once;
}

}  // namespace cv::fuzz
