// Exclusive temporaries in the output's folder, renamed into place; cleaned up on failure and signals.
#include "io/output_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <random>
#include <stdexcept>

#include "io/input_file.hpp"

namespace cv::core {
namespace {

namespace fs = std::filesystem;

// Named temporaries in progress, for the signal handler: fixed slots, written before the name
// exists on disk and cleared after it is gone, read by the handler with nothing but unlink().
constexpr int kSlots = 256;
constexpr std::size_t kPathMax = 4096;
struct Slot {
  std::atomic<bool> used{false};
  char path[kPathMax];
};
Slot g_slots[kSlots];
std::atomic<bool> g_unnamed{true};

int register_temp(const std::string& path) {
  if (path.size() >= kPathMax) return -1;
  for (int i = 0; i < kSlots; ++i) {
    bool expected = false;
    if (g_slots[i].used.load() || !g_slots[i].used.compare_exchange_strong(expected, true)) continue;
    std::memcpy(g_slots[i].path, path.c_str(), path.size() + 1);
    return i;
  }
  return -1;  // more than kSlots at once: still removed on failure, not on a signal
}
void unregister_temp(int slot) {
  if (slot >= 0) g_slots[slot].used.store(false);
}
// A registered name, removed from the registry as it is removed from disk.
struct TempName {
  std::string path;
  int slot = -1;
  explicit TempName(std::string p = {}) : path(std::move(p)), slot(path.empty() ? -1 : register_temp(path)) {}
  void remove() {
    if (!path.empty()) ::unlink(path.c_str());
    forget();
  }
  void forget() {
    unregister_temp(slot);
    slot = -1;
    path.clear();
  }
};

extern "C" void cleanup_and_reraise(int sig) {
  for (Slot& s : g_slots) {
    if (s.used.load()) ::unlink(s.path);
  }
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}

mode_t file_mode() {
  static const mode_t mode = [] {
    const mode_t m = ::umask(022);
    ::umask(m);
    return static_cast<mode_t>(0666 & ~m);
  }();
  return mode;
}

std::string folder_of(const std::string& path) {
  const fs::path parent = fs::path(path).parent_path();
  return parent.empty() ? std::string(".") : parent.string();
}

std::string random_suffix() {
  static thread_local std::mt19937_64 rng{std::random_device{}() ^ (static_cast<std::uint64_t>(::getpid()) << 32)};
  static const char chars[] = "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789";
  std::string s(12, 'x');
  for (char& c : s) c = chars[rng() % (sizeof chars - 1)];
  return s;
}

// The hidden name a temporary of `path` gets: ".NAME.cvtmp-XXXXXXXXXXXX" in the same folder.
std::string hidden_name(const std::string& path) {
  const fs::path p(path);
  std::string name(1, '.');
  name.append(p.filename().string()).append(".cvtmp-").append(random_suffix());
  return (p.parent_path() / name).string();
}

[[noreturn]] void fail_create(const std::string& path, int err) {
  throw std::runtime_error(path + ": cannot create (" + std::strerror(err) + " in the folder '" + folder_of(path) + "')");
}

}  // namespace

void OutputFile::set_unnamed_temporaries(bool on) { g_unnamed = on; }

OutputFile::OutputFile(std::string path) : path_(std::move(path)) {
  int fd = -1;
#ifdef O_TMPFILE
  if (g_unnamed) {
    fd = ::open(folder_of(path_).c_str(), O_TMPFILE | O_WRONLY | O_CLOEXEC, 0666);
    unnamed_ = fd >= 0;
    if (fd < 0 && errno != EOPNOTSUPP && errno != EISDIR && errno != EINVAL && errno != ENOENT) fail_create(path_, errno);
  }
#endif
  if (fd < 0) {
    for (int attempt = 0; attempt < 100 && fd < 0; ++attempt) {
      TempName name(hidden_name(path_));
      fd = ::open(name.path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0600);
      if (fd >= 0) {
        temp_ = name.path;
        slot_ = name.slot;
      } else {
        const int err = errno;
        name.forget();
        if (err != EEXIST) fail_create(path_, err);
      }
    }
    if (fd < 0) fail_create(path_, EEXIST);
    ::fchmod(fd, file_mode());
  }
  f_ = ::fdopen(fd, "wb");
  if (!f_) {
    const int err = errno;
    ::close(fd);
    if (!temp_.empty()) ::unlink(temp_.c_str());
    unregister_temp(slot_);
    fail_create(path_, err);
  }
}

OutputFile::~OutputFile() {
  if (f_) std::fclose(f_);
  if (!committed_ && !temp_.empty()) ::unlink(temp_.c_str());
  unregister_temp(slot_);
}

void OutputFile::finish() {
  if (finished_) return;
  if (std::ferror(f_) || std::fflush(f_) != 0 || ::fsync(::fileno(f_)) != 0) {
    const int err = errno;
    throw std::runtime_error(path_ + ": write failed (" + std::strerror(err ? err : EIO) + ")");
  }
  finished_ = true;
}

std::string OutputFile::link_to_hidden_name() {
  finish();
  if (!unnamed_) return temp_;
  const std::string proc = "/proc/self/fd/" + std::to_string(::fileno(f_));
  for (int attempt = 0; attempt < 100; ++attempt) {
    TempName name(hidden_name(path_));
    if (::linkat(AT_FDCWD, proc.c_str(), AT_FDCWD, name.path.c_str(), AT_SYMLINK_FOLLOW) == 0) {
      temp_ = name.path;
      slot_ = name.slot;
      unnamed_ = false;
      return temp_;
    }
    const int err = errno;
    name.forget();
    if (err != EEXIST) throw std::runtime_error(path_ + ": cannot give the written file a name (" + std::strerror(err) + ")");
  }
  throw std::runtime_error(path_ + ": cannot give the written file a name (" + std::strerror(EEXIST) + ")");
}

void OutputFile::commit() {
  const std::string temp = link_to_hidden_name();
  if (::rename(temp.c_str(), path_.c_str()) != 0) {
    const int err = errno;
    throw std::runtime_error(path_ + ": cannot rename into place (" + std::strerror(err) + ")");
  }
  committed_ = true;
  unregister_temp(slot_);
  slot_ = -1;
  temp_.clear();
}

void write_file_atomically(const std::string& path, const std::function<void(std::FILE*)>& write) {
  OutputFile out(path);
  try {
    write(out.stream());
  } catch (const WriteError& e) {
    throw std::runtime_error(path + ": " + e.what());
  }
  out.commit();
}

void OutputGroup::write(const std::string& path, const std::function<void(std::FILE*)>& write) {
  for (const auto& f : files_) {
    if (same_file(f->path(), path)) throw InputError(path + ": written twice in one set of outputs (also as " + f->path() + ")");
  }
  auto out = std::make_unique<OutputFile>(path);
  try {
    write(out->stream());
  } catch (const WriteError& e) {
    throw std::runtime_error(path + ": " + e.what());
  }
  out->finish();
  files_.push_back(std::move(out));
}

std::vector<std::string> OutputGroup::paths() const {
  std::vector<std::string> out;
  for (const auto& f : files_) out.push_back(f->path());
  return out;
}

void OutputGroup::commit() {
  // Every member under a name in its folder first, and what each replaces kept under another.
  std::vector<std::string> temps;
  std::vector<TempName> backups(files_.size());
  for (auto& f : files_) temps.push_back(f->link_to_hidden_name());
  auto drop_backups = [&] {
    for (TempName& b : backups) b.remove();
  };
  for (std::size_t i = 0; i < files_.size(); ++i) {
    struct stat st {};
    if (::lstat(files_[i]->path().c_str(), &st) != 0) continue;  // nothing there to put back
    for (int attempt = 0; attempt < 100; ++attempt) {
      TempName b(hidden_name(files_[i]->path()));
      if (::link(files_[i]->path().c_str(), b.path.c_str()) == 0) {
        backups[i] = b;
        break;
      }
      const int err = errno;
      b.forget();
      if (err != EEXIST) break;  // no hard links here: that member cannot be put back
    }
  }
  for (std::size_t i = 0; i < files_.size(); ++i) {
    if (::rename(temps[i].c_str(), files_[i]->path().c_str()) == 0) {
      files_[i]->committed_ = true;
      files_[i]->temp_.clear();
      unregister_temp(files_[i]->slot_);
      files_[i]->slot_ = -1;
      continue;
    }
    const int err = errno;
    for (std::size_t j = 0; j < i; ++j) {  // put back what the placed ones replaced
      if (!backups[j].path.empty()) ::rename(backups[j].path.c_str(), files_[j]->path().c_str());
      else ::unlink(files_[j]->path().c_str());
    }
    drop_backups();
    throw std::runtime_error(files_[i]->path() + ": cannot rename into place (" + std::strerror(err) +
                             "); none of " + std::to_string(files_.size()) + " outputs written");
  }
  drop_backups();
}

void install_output_cleanup() {
  for (int sig : {SIGTERM, SIGINT, SIGHUP, SIGQUIT}) {
    struct sigaction sa {};
    sa.sa_handler = cleanup_and_reraise;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = SA_RESETHAND;
    ::sigaction(sig, &sa, nullptr);
  }
}

void check_output_path(const std::string& path, const std::string& option) {
  const std::string folder = folder_of(path);
  const std::string head = "cloudviewer: " + option + ": found '" + path + "'";
  if (path.empty() || fs::path(path).filename().empty()) throw InputError(head + ", expected a file name");
  struct stat st {};
  if (::stat(folder.c_str(), &st) != 0) throw InputError(head + ": its folder '" + folder + "' does not exist, expected an existing folder");
  if (!S_ISDIR(st.st_mode)) throw InputError(head + ": '" + folder + "' is not a folder, expected an existing folder");
  if (::access(folder.c_str(), W_OK | X_OK) != 0) {
    throw InputError(head + ": the folder '" + folder + "' cannot be written (" + std::strerror(errno) + "), expected a writable folder");
  }
  if (::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode)) throw InputError(head + ": it is a folder, expected a file name");
}

void check_output_extension(const std::string& path, const std::string& option, const std::vector<std::string>& extensions) {
  auto lower = [](std::string s) {
    for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return s;
  };
  const std::string p = lower(path);
  std::string list;
  for (const std::string& e : extensions) {
    if (p.size() > e.size() && p.compare(p.size() - e.size(), e.size(), lower(e)) == 0) return;
    list += (list.empty() ? "" : " or ") + e;
  }
  throw InputError("cloudviewer: " + option + ": found '" + path + "', expected a file name ending in " + list +
                   " (the only format" + (extensions.size() > 1 ? "s" : "") + " it writes)");
}

bool same_file(const std::string& a, const std::string& b) {
  struct stat sa {}, sb {};
  if (::stat(a.c_str(), &sa) == 0 && ::stat(b.c_str(), &sb) == 0) return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
  std::error_code ec1, ec2;
  const fs::path ca = fs::weakly_canonical(fs::absolute(a), ec1), cb = fs::weakly_canonical(fs::absolute(b), ec2);
  return !ec1 && !ec2 && ca == cb;
}

void check_output_not_input(const std::string& output, const std::string& option, const std::string& input,
                            const std::string& input_what) {
  if (output.empty() || input.empty() || !same_file(output, input)) return;
  throw InputError("cloudviewer: " + option + ": found '" + output + "', which is " + input_what + " ('" + input +
                   "'); expected an output that is not one of the inputs");
}

}  // namespace cv::core
