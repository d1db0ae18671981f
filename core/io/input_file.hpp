// Reading files a user hands us without trusting them: only regular files are opened (a FIFO,
// a device such as /dev/zero, a directory or a socket is refused up front, so no read blocks or
// runs forever), sizes come with a bound, and products of declared sizes are checked for overflow
// and against the memory limit (a setting, by default from the machine's memory) before anything
// is allocated.
#pragma once

#include <cstdint>
#include <cstdio>
#include <initializer_list>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace cv::core {

// Bad input: a file, key or argument that is wrong. One line naming the file, the variable or key,
// what was found and what was expected. The command line exits with 2 for it (and its subclasses:
// SceneError, VolumeFileError, importers::ImportError, ...).
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// What kind of thing is at `path` ("a FIFO", "a directory", "a character device", ...), or "" for
// a regular file (symbolic links followed). "no such file" when nothing is there.
std::string file_kind(const std::string& path);

// Throws InputError "<path>: <what> is <kind>, expected a regular file" unless `path` is a regular
// file (after following symbolic links).
void require_regular_file(const std::string& path, const std::string& what);

// Opens a regular file for reading without ever blocking on it: opened with O_NONBLOCK (a FIFO
// opens at once instead of waiting for a writer) and refused unless the opened descriptor is a
// regular file, so nothing can be swapped in between the check and the open. Throws InputError
// naming the file and `what` ("the scene file", "the ground image", ...).
std::FILE* open_regular_file(const std::string& path, const std::string& what);

// The whole of a regular file of at most max_bytes (InputError naming the size and the bound).
std::string read_regular_file(const std::string& path, const std::string& what, std::uint64_t max_bytes);

// a * b * ... or nothing when the product does not fit in 64 bits.
std::optional<std::uint64_t> checked_product(std::initializer_list<std::uint64_t> factors);

// The memory one input may ask for, in bytes: CLOUDVIEWER_MEMORY_LIMIT (bytes, or with a suffix
// K, M, G, T: powers of 1024) when set, else set_memory_limit_bytes, else half the machine's
// physical memory (at least 256 MiB).
std::uint64_t memory_limit_bytes();
void set_memory_limit_bytes(std::uint64_t bytes);  // 0: back to the default
// "4G", "512M", "1000000" -> bytes; nothing for anything else (zero, negative, unknown suffix).
std::optional<std::uint64_t> parse_byte_size(const std::string& text);
// "1.5 GiB": a size for messages.
std::string byte_size_text(double bytes);

// Throws InputError "<source>: <what> would take <size>, more than the memory limit <limit>
// (CLOUDVIEWER_MEMORY_LIMIT)" when `bytes` (nothing: an overflowing product) exceeds the limit.
void require_within_memory_limit(const std::string& source, const std::string& what, std::optional<std::uint64_t> bytes);

// Makes room for exactly n values in v before any is written; v's old contents are dropped when it
// has to grow (for buffers whose every value the caller writes next, reused step to step).
//
// No transparent huge pages are asked for here any more. They were (madvise MADV_HUGEPAGE): fewer
// page faults, but with the kernel's usual defrag setting ("madvise") each fault in an advised
// region compacts memory synchronously, and once the page cache had fragmented memory the global
// import took 14 s instead of 10 (docs/BENCHMARKS.md, "Import: direct writes").
template <typename T, typename A>
void reserve_exact(std::vector<T, A>& v, std::size_t n) {
  if (v.capacity() >= n) return;
  std::vector<T, A>().swap(v);
  v.reserve(n);
}

// Faults in the pages of [p, p + bytes) on every core (madvise MADV_POPULATE_WRITE in slices),
// before a vector's resize writes them from one thread: a fresh global field is 190 MB of pages
// the kernel clears as they are first touched. Nothing happens where the kernel lacks it.
void populate_pages(void* p, std::size_t bytes);

}  // namespace cv::core
