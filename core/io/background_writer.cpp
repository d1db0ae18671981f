// A writer thread draining a queue of aligned chunks into a file, with direct I/O where allowed.
#include "io/background_writer.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>

#include "io/output_file.hpp"

namespace cv::core {

BackgroundWriter::BackgroundWriter(std::FILE* f, Options options) : f_(f), options_(options) {
  if (options_.chunk_bytes < kAlign || options_.chunk_bytes % kAlign) options_.chunk_bytes = Options{}.chunk_bytes;
  options_.max_chunks = std::max<std::size_t>(2, options_.max_chunks);
  if (std::fflush(f_) != 0) throw WriteError(std::string("write failed (") + std::strerror(errno) + ")");
  fd_ = ::fileno(f_);
  offset_ = ::lseek(fd_, 0, SEEK_CUR);
  if (offset_ < 0) throw WriteError(std::string("write failed (") + std::strerror(errno) + ")");
  original_flags_ = ::fcntl(fd_, F_GETFL);
  buffers_.reserve(options_.max_chunks);  // never reallocated: the writer thread reads it unlocked
#ifdef O_DIRECT
  // Only from an aligned offset: the chunks' offsets follow from it.
  if (options_.direct && original_flags_ >= 0 && offset_ % static_cast<long long>(kAlign) == 0) {
    direct_ = ::fcntl(fd_, F_SETFL, original_flags_ | O_DIRECT) == 0;
  }
#endif
  thread_ = std::thread([this] { run(); });
}

BackgroundWriter::~BackgroundWriter() {
  {
    std::lock_guard<std::mutex> lock(m_);
    stop_ = true;
  }
  cv_.notify_all();
  if (thread_.joinable()) thread_.join();
  if (direct_ && !finished_) ::fcntl(fd_, F_SETFL, original_flags_);
}

void BackgroundWriter::check_failed() {
  if (!failure_.empty()) throw WriteError(failure_);
}

std::span<std::byte> BackgroundWriter::room() {
  if (current_ >= 0 && fill_ < options_.chunk_bytes) {
    return {buffers_[static_cast<std::size_t>(current_)].get() + fill_, options_.chunk_bytes - fill_};
  }
  std::unique_lock<std::mutex> lock(m_);
  check_failed();
  if (current_ >= 0) {  // full: queue it
    full_.push_back({static_cast<std::size_t>(current_), fill_});
    current_ = -1;
    cv_.notify_all();
  }
  if (free_.empty() && buffers_.size() < options_.max_chunks) {
    void* p = std::aligned_alloc(kAlign, options_.chunk_bytes);
    if (!p) throw WriteError("write failed (out of memory for the write queue)");
    buffers_.emplace_back(static_cast<std::byte*>(p), std::free);
    free_.push_back(buffers_.size() - 1);
  }
  cv_.wait(lock, [&] { return !free_.empty() || !failure_.empty(); });
  check_failed();
  current_ = static_cast<long long>(free_.back());
  free_.pop_back();
  fill_ = 0;
  return {buffers_[static_cast<std::size_t>(current_)].get(), options_.chunk_bytes};
}

void BackgroundWriter::commit(std::size_t n) {
  fill_ += n;
  committed_ += n;
}

void BackgroundWriter::write(const void* data, std::size_t n) {
  const auto* p = static_cast<const std::byte*>(data);
  while (n) {
    const std::span<std::byte> r = room();
    const std::size_t k = std::min(n, r.size());
    std::memcpy(r.data(), p, k);
    commit(k);
    p += k, n -= k;
  }
}

void BackgroundWriter::write_out(const Chunk& c) {
  const std::byte* p = buffers_[c.index].get();
  std::size_t left = c.used;
#ifdef O_DIRECT
  // Direct I/O takes whole blocks: the last, partial chunk goes through the page cache.
  if (direct_ && left % kAlign) ::fcntl(fd_, F_SETFL, original_flags_);
#endif
  while (left) {
    const ssize_t w = ::pwrite(fd_, p, left, static_cast<off_t>(offset_));
    if (w < 0 && errno == EINTR) continue;
#ifdef O_DIRECT
    if (w < 0 && errno == EINVAL && direct_) {  // the file system took the flag but not the write
      ::fcntl(fd_, F_SETFL, original_flags_);
      direct_ = false;
      continue;
    }
#endif
    if (w <= 0) throw WriteError(std::string("write failed (") + std::strerror(w < 0 ? errno : ENOSPC) + ")");
    p += w, left -= static_cast<std::size_t>(w), offset_ += w;
  }
}

void BackgroundWriter::run() {
  std::unique_lock<std::mutex> lock(m_);
  for (;;) {
    cv_.wait(lock, [&] { return stop_ || !full_.empty(); });
    if (full_.empty()) return;  // stopping with nothing queued
    if (stop_ && !finished_) return;  // abandoned: the caller is failing
    const Chunk c = full_.front();
    full_.pop_front();
    writing_ = true;
    const bool skip = !failure_.empty();  // after a failure the rest is dropped
    lock.unlock();
    std::string failed;
    if (!skip) {
      try {
        write_out(c);
      } catch (const WriteError& e) {
        failed = e.what();
      }
    }
    lock.lock();
    if (!failed.empty() && failure_.empty()) failure_ = failed;
    free_.push_back(c.index);
    writing_ = false;
    cv_.notify_all();
  }
}

void BackgroundWriter::finish() {
  std::unique_lock<std::mutex> lock(m_);
  if (current_ >= 0 && fill_ > 0) full_.push_back({static_cast<std::size_t>(current_), fill_});
  else if (current_ >= 0) free_.push_back(static_cast<std::size_t>(current_));
  current_ = -1;
  fill_ = 0;
  finished_ = true;
  cv_.notify_all();
  cv_.wait(lock, [&] { return (full_.empty() && !writing_) || !failure_.empty(); });
  stop_ = true;
  cv_.notify_all();
  lock.unlock();
  thread_.join();
  if (direct_) ::fcntl(fd_, F_SETFL, original_flags_);
  check_failed();
  if (std::fseek(f_, 0, SEEK_END) != 0) throw WriteError(std::string("write failed (") + std::strerror(errno) + ")");
}

}  // namespace cv::core
