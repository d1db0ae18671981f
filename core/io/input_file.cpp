// Untrusted input files: regular files only, bounded reads, checked sizes.
#include "io/input_file.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>

#include "io/parallel.hpp"

namespace cv::core {
namespace {

std::string kind_of(mode_t m) {
  if (S_ISREG(m)) return "";
  if (S_ISDIR(m)) return "a directory";
  if (S_ISFIFO(m)) return "a FIFO (named pipe)";
  if (S_ISCHR(m)) return "a character device";
  if (S_ISBLK(m)) return "a block device";
  if (S_ISSOCK(m)) return "a socket";
  return "not a regular file";
}

std::atomic<std::uint64_t> g_memory_limit{0};

}  // namespace

std::string file_kind(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return errno == ENOENT ? "no such file" : std::string("unreadable (") + std::strerror(errno) + ")";
  return kind_of(st.st_mode);
}

void require_regular_file(const std::string& path, const std::string& what) {
  const std::string kind = file_kind(path);
  if (kind == "no such file") throw InputError(path + ": " + what + ": no such file");
  if (!kind.empty()) throw InputError(path + ": " + what + " is " + kind + ", expected a regular file");
}

std::FILE* open_regular_file(const std::string& path, const std::string& what) {
  require_regular_file(path, what);
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
  if (fd < 0) throw InputError(path + ": cannot open " + what + " (" + std::strerror(errno) + ")");
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    throw InputError(path + ": " + what + " is " + kind_of(st.st_mode) + ", expected a regular file");
  }
  // Regular files never block; clear the flag so reads behave as usual.
  ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) & ~O_NONBLOCK);
  std::FILE* f = ::fdopen(fd, "rb");
  if (!f) {
    ::close(fd);
    throw InputError(path + ": cannot open " + what + " (" + std::strerror(errno) + ")");
  }
  return f;
}

std::string read_regular_file(const std::string& path, const std::string& what, std::uint64_t max_bytes) {
  std::FILE* f = open_regular_file(path, what);
  struct stat st {};
  ::fstat(::fileno(f), &st);
  if (static_cast<std::uint64_t>(st.st_size) > max_bytes) {
    std::fclose(f);
    throw InputError(path + ": " + what + " holds " + byte_size_text(static_cast<double>(st.st_size)) + ", expected at most " +
                     byte_size_text(static_cast<double>(max_bytes)));
  }
  std::string text(static_cast<std::size_t>(st.st_size), '\0');
  const std::size_t got = text.empty() ? 0 : std::fread(text.data(), 1, text.size(), f);
  const bool err = std::ferror(f) != 0;
  std::fclose(f);
  if (err) throw InputError(path + ": cannot read " + what);
  text.resize(got);  // a file that shrank meanwhile: what is there
  return text;
}

std::optional<std::uint64_t> checked_product(std::initializer_list<std::uint64_t> factors) {
  std::uint64_t p = 1;
  for (std::uint64_t f : factors) {
    if (f != 0 && p > std::numeric_limits<std::uint64_t>::max() / f) return std::nullopt;
    p *= f;
  }
  return p;
}

std::optional<std::uint64_t> parse_byte_size(const std::string& text) {
  if (text.empty() || !(text[0] >= '0' && text[0] <= '9')) return std::nullopt;
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(text.c_str(), &end);
  if (errno || !std::isfinite(v) || v <= 0.0) return std::nullopt;
  const std::string suffix(end);
  double scale = 1.0;
  if (suffix.empty() || suffix == "B") scale = 1.0;
  else if (suffix == "K" || suffix == "KiB") scale = 1024.0;
  else if (suffix == "M" || suffix == "MiB") scale = 1024.0 * 1024.0;
  else if (suffix == "G" || suffix == "GiB") scale = 1024.0 * 1024.0 * 1024.0;
  else if (suffix == "T" || suffix == "TiB") scale = 1024.0 * 1024.0 * 1024.0 * 1024.0;
  else return std::nullopt;
  const double bytes = v * scale;
  if (!(bytes >= 1.0 && bytes < 1.8e19)) return std::nullopt;
  return static_cast<std::uint64_t>(bytes);
}

std::string byte_size_text(double bytes) {
  static const char* units[] = {"bytes", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
  int u = 0;
  while (bytes >= 1024.0 && u < 6) bytes /= 1024.0, ++u;
  char buf[48];
  std::snprintf(buf, sizeof buf, u == 0 ? "%.0f %s" : "%.3g %s", bytes, units[u]);
  return buf;
}

void set_memory_limit_bytes(std::uint64_t bytes) { g_memory_limit = bytes; }

std::uint64_t memory_limit_bytes() {
  if (const char* env = std::getenv("CLOUDVIEWER_MEMORY_LIMIT"); env && *env) {
    if (const auto v = parse_byte_size(env)) return *v;
  }
  if (const std::uint64_t set = g_memory_limit.load()) return set;
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGESIZE);
  const std::uint64_t physical = pages > 0 && page > 0 ? static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(page) : 0;
  return std::max<std::uint64_t>(physical / 2, std::uint64_t(256) << 20);
}

void require_within_memory_limit(const std::string& source, const std::string& what, std::optional<std::uint64_t> bytes) {
  const std::uint64_t limit = memory_limit_bytes();
  if (bytes && *bytes <= limit) return;
  throw InputError(source + ": " + what + " would take " +
                   (bytes ? byte_size_text(static_cast<double>(*bytes)) : std::string("more than 2^64 bytes")) +
                   ", expected at most the memory limit " + byte_size_text(static_cast<double>(limit)) +
                   " (set CLOUDVIEWER_MEMORY_LIMIT to change it)");
}

void populate_pages(void* p, std::size_t bytes) {
#ifdef MADV_POPULATE_WRITE
  const long page_size = ::sysconf(_SC_PAGESIZE);
  if (!p || page_size <= 0 || bytes < (std::size_t(1) << 24)) return;  // small buffers: not worth a thread
  const std::size_t page = static_cast<std::size_t>(page_size);
  // The whole pages inside the buffer (madvise wants a page-aligned start).
  const std::uintptr_t lo = (reinterpret_cast<std::uintptr_t>(p) + page - 1) / page * page;
  const std::uintptr_t hi = (reinterpret_cast<std::uintptr_t>(p) + bytes) / page * page;
  if (hi <= lo) return;
  const std::size_t pages = (hi - lo) / page;
  parallel_ranges(pages, 1024, [&](std::size_t b, std::size_t e, unsigned) {
    // Advice only: a kernel without it (EINVAL) leaves the pages to be faulted in as written.
    (void)::madvise(reinterpret_cast<void*>(lo + b * page), (e - b) * page, MADV_POPULATE_WRITE);
  });
#else
  (void)p;
  (void)bytes;
#endif
}

}  // namespace cv::core
