// Appending a large output from a background thread, in aligned chunks written with direct I/O
// where the file system takes it.
//
// Why: a global import writes gigabytes. Through the page cache every byte is copied by the kernel
// (on the team's VM 400 MB/s of system time, more than the whole conversion) and then written back
// by fsync; with O_DIRECT the disk reads the chunk from our memory (1.3 GB/s there, almost no
// system time), and with the write on its own thread the caller goes on converting while the disk
// writes.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <cstdio>
#include <deque>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <thread>
#include <vector>

namespace cv::core {

class BackgroundWriter {
 public:
  struct Options {
    // The queue's memory is chunk_bytes x max_chunks at most: 64 MB. A bigger queue overlaps more of
    // a step's write with the next step's conversion, but its fresh pages cost more than that
    // saves (a 512 MB queue made the global import about 3 s slower on the team's VM).
    std::size_t chunk_bytes = std::size_t(16) << 20;  // a multiple of kAlign
    std::size_t max_chunks = 4;
    bool direct = true;                               // try O_DIRECT (falls back to buffered writes)
  };
  // Direct I/O needs buffers, lengths and file offsets that are multiples of the device's block
  // size (512 or 4096 bytes): 4096 suits both.
  static constexpr std::size_t kAlign = 4096;

  // Appends to `f` from its current position (what it buffered is flushed first). The FILE must
  // not be written through while the writer lives; after finish() it may be again.
  BackgroundWriter(std::FILE* f, Options options);
  BackgroundWriter(std::FILE* f) : BackgroundWriter(f, Options{}) {}
  // Stops the thread; bytes not yet finish()ed may be lost (the caller is failing anyway).
  ~BackgroundWriter();
  BackgroundWriter(const BackgroundWriter&) = delete;
  BackgroundWriter& operator=(const BackgroundWriter&) = delete;

  // Free bytes at the end of the current chunk (never empty), waiting for a chunk to come free.
  // Throws WriteError when an earlier write failed.
  std::span<std::byte> room();
  // The first n bytes of room() were filled.
  void commit(std::size_t n);
  // Copies n bytes in.
  void write(const void* data, std::size_t n);
  // Writes everything and waits; throws WriteError on failure. Leaves the FILE positioned after
  // the last byte, with the file's flags as they were.
  void finish();
  // Whether chunks went out with direct I/O.
  bool direct() const { return direct_; }
  std::size_t bytes_committed() const { return committed_; }

 private:
  struct Chunk {
    std::size_t index = 0;  // into buffers_
    std::size_t used = 0;
  };
  void run();
  void submit_current();
  void check_failed();  // under the lock
  void write_out(const Chunk& c);

  int fd_ = -1;
  std::FILE* f_ = nullptr;
  Options options_;
  int original_flags_ = 0;
  bool direct_ = false;
  long long offset_ = 0;  // the file offset of the next chunk to be written (writer thread)
  std::size_t committed_ = 0;
  std::vector<std::unique_ptr<std::byte, void (*)(void*)>> buffers_;
  std::vector<std::size_t> free_;  // indices of buffers free for filling
  std::deque<Chunk> full_;         // filled, in file order
  long long current_ = -1;         // the buffer being filled (-1: none)
  std::size_t fill_ = 0;
  bool writing_ = false, stop_ = false, finished_ = false;
  std::string failure_;
  std::mutex m_;
  std::condition_variable cv_;
  std::thread thread_;
};

}  // namespace cv::core
