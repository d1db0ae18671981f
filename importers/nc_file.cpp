// NcFile: netCDF-C behind one-line errors, unpacking and missing-value handling.
#include "nc_file.hpp"

#include "io/input_file.hpp"
#include "io/parallel.hpp"

#include <netcdf.h>

#include <poll.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <csignal>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>

#include "io/cpu.hpp"
#endif

namespace cv::importers {
namespace {

std::vector<NcAtt> read_atts(int ncid, int varid, int natts, const std::string& path) {
  std::vector<NcAtt> out;
  for (int a = 0; a < natts; ++a) {
    char name[NC_MAX_NAME + 1] = {0};
    nc_type type;
    size_t len = 0;
    if (nc_inq_attname(ncid, varid, a, name) != NC_NOERR || nc_inq_att(ncid, varid, name, &type, &len) != NC_NOERR) {
      throw ImportError(path + ": cannot read attribute " + std::to_string(a) + " (file corrupted?)");
    }
    NcAtt att;
    att.name = name;
    if (type == NC_CHAR) {
      att.is_text = true;
      att.text.resize(len);
      if (len && nc_get_att_text(ncid, varid, name, att.text.data()) != NC_NOERR) {
        throw ImportError(path + ": cannot read text attribute '" + att.name + "'");
      }
      while (!att.text.empty() && att.text.back() == '\0') att.text.pop_back();
    } else if (type == NC_STRING) {
      att.is_text = true;
      std::vector<char*> strs(len, nullptr);
      if (len && nc_get_att_string(ncid, varid, name, strs.data()) == NC_NOERR) {
        att.text = strs[0] ? strs[0] : "";
        nc_free_string(len, strs.data());
      }
    } else if (len > 0 && len < (1u << 20)) {
      att.values.resize(len);
      if (nc_get_att_double(ncid, varid, name, att.values.data()) != NC_NOERR) att.values.clear();
    }
    out.push_back(std::move(att));
  }
  return out;
}

// The most of a file read to walk its header, and what is read first: a header is usually a few
// kilobytes, so a big file is not read 64 MiB deep to check one.
constexpr std::size_t kClassicHeaderMost = std::size_t(64) << 20, kClassicHeaderFirst = std::size_t(256) << 10;
// Thrown when the header runs past the bytes read so far but not past the file: read more.
struct NeedMoreBytes {};

// netCDF-C's classic-format reader trusts the lengths its header declares: a name length of
// 2^32 - 1 makes it memcpy a negative size (a crash), a large one makes it calloc 16 GiB and more
// (both found by fuzz/fuzz_netcdf). The header is walked here first, every declared length and
// count held to the bytes the file has, before netCDF opens it.
class ClassicHeader {
 public:
  ClassicHeader(const std::string& path, const std::vector<unsigned char>& b, std::uint64_t file_bytes)
      : path_(path), b_(b), file_bytes_(file_bytes), version_(b.size() > 3 ? b[3] : 0) {}
  void check() {
    pos_ = 4;
    take(version_ == 5 ? 8 : 4, "the record count");
    list(0x0A, "dimension", [&](std::uint64_t i) {
      name("dimension", i);
      dims_.push_back(take(version_ == 5 ? 8 : 4, "a dimension length"));
    });
    attributes("global");
    list(0x0B, "variable", [&](std::uint64_t i) {
      name("variable", i);
      const std::uint64_t nd = count("variable " + std::to_string(i) + "'s dimensions", version_ == 5 ? 8 : 4);
      const std::size_t width = version_ == 5 ? 8 : 4;
      const std::uint64_t ids_at = pos_;
      skip(nd, width, "variable " + std::to_string(i) + "'s dimension ids");
      // A dimension a variable uses is no longer than the file has bytes (each of its values takes
      // one at least; the record dimension's 0 stands for its records). netCDF-C multiplies the
      // lengths as signed integers: a CDF-5 length of 2^63 made its product 0 and its next division
      // a floating-point exception (found by fuzz/fuzz_netcdf).
      for (std::uint64_t d = 0; d < nd; ++d) {
        std::uint64_t id = 0;
        for (std::size_t k = 0; k < width; ++k) id = (id << 8) | b_[ids_at + d * width + k];
        if (id < dims_.size() && dims_[id] > file_bytes_) {
          pos_ = ids_at + d * width;
          corrupt("the length of variable " + std::to_string(i) + "'s dimension " + std::to_string(d) + " (dimension " +
                      std::to_string(id) + ")",
                  dims_[id]);
        }
      }
      attributes("variable " + std::to_string(i));
      // A type the format has: netCDF-C took NC_STRING (12) in a CDF-5 header with a size of 0,
      // and divided by it (a floating-point exception found by fuzz/fuzz_netcdf).
      const std::uint64_t type = take(4, "variable " + std::to_string(i) + "'s type");
      if (type < 1 || type > 11 || (version_ != 5 && type > 6)) corrupt("variable " + std::to_string(i) + "'s type", type);
      take(version_ == 5 ? 8 : 4, "a variable's size");
      take(version_ == 1 ? 4 : 8, "a variable's offset");
    });
  }

 private:
  [[noreturn]] void corrupt(const std::string& what, std::uint64_t declared) const {
    throw ImportError(path_ + ": the netCDF classic header is corrupt: " + what + " declares " + std::to_string(declared) +
                      " where " + std::to_string(file_bytes_ > pos_ ? file_bytes_ - pos_ : 0) +
                      " bytes of the file are left; expected a complete netCDF file");
  }
  std::uint64_t take(std::size_t n, const std::string& what) {
    if (pos_ + n > b_.size()) {
      if (pos_ + n <= file_bytes_) {
        if (b_.size() < kClassicHeaderMost) throw NeedMoreBytes{};
        throw ImportError(path_ + ": the netCDF classic header is larger than 64 MiB; expected a smaller header");
      }
      corrupt(what, n);
    }
    std::uint64_t v = 0;
    for (std::size_t i = 0; i < n; ++i) v = (v << 8) | b_[pos_ + i];
    pos_ += n;
    return v;
  }
  std::uint64_t count(const std::string& what, std::size_t width) {
    const std::uint64_t n = take(width, what);
    if (n > file_bytes_) corrupt(what, n);  // every element takes at least a byte
    return n;
  }
  void skip(std::uint64_t n, std::uint64_t each, const std::string& what) {
    const std::uint64_t padded = (n * each + 3) / 4 * 4;
    if (n > file_bytes_ || padded > file_bytes_ - std::min<std::uint64_t>(file_bytes_, pos_)) corrupt(what, n * each);
    pos_ += padded;
    if (pos_ > b_.size()) take(1, what);  // past what was read: larger than 64 MiB or cut short
  }
  void name(const std::string& of, std::uint64_t i) {
    const std::uint64_t n = count("the name of " + of + " " + std::to_string(i), version_ == 5 ? 8 : 4);
    skip(n, 1, "the name of " + of + " " + std::to_string(i));
  }
  template <class F>
  void list(std::uint64_t tag, const char* what, F each) {
    const std::uint64_t t = take(4, std::string("the ") + what + " list's tag");
    const std::uint64_t n = count(std::string("the ") + what + " count", version_ == 5 ? 8 : 4);
    if (t == 0 && n == 0) return;  // absent
    if (t != tag) corrupt(std::string("the ") + what + " list's tag", t);
    for (std::uint64_t i = 0; i < n; ++i) each(i);
  }
  void attributes(const std::string& of) {
    list(0x0C, "attribute", [&](std::uint64_t i) {
      const std::string what = "attribute " + std::to_string(i) + " of " + of;
      name("attribute", i);
      const std::uint64_t type = take(4, what + "'s type");
      static const std::uint64_t bytes[] = {0, 1, 1, 2, 4, 4, 8, 1, 2, 4, 8, 8};
      if (type < 1 || type > 11 || (version_ != 5 && type > 6)) corrupt(what + "'s type", type);
      const std::uint64_t n = count(what + "'s length", version_ == 5 ? 8 : 4);
      skip(n, bytes[type], what + "'s values");
    });
  }
  const std::string& path_;
  const std::vector<unsigned char>& b_;
  std::vector<std::uint64_t> dims_;  // the dimensions' declared lengths (0: the record dimension)
  std::uint64_t file_bytes_;
  unsigned version_;
  std::uint64_t pos_ = 0;
};

bool is_integer_type(int t) {
  return t == NC_BYTE || t == NC_SHORT || t == NC_INT || t == NC_UBYTE || t == NC_USHORT || t == NC_UINT ||
         t == NC_INT64 || t == NC_UINT64;
}

std::size_t type_bytes(int t) {
  switch (t) {
    case NC_BYTE: case NC_UBYTE: case NC_CHAR: return 1;
    case NC_SHORT: case NC_USHORT: return 2;
    case NC_INT: case NC_UINT: case NC_FLOAT: return 4;
    default: return 8;
  }
}
}  // namespace

void check_classic_header(const std::string& path, std::uint64_t file_bytes) {
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!f) return;  // netCDF's open says why
  const std::size_t most = static_cast<std::size_t>(std::min<std::uint64_t>(file_bytes, kClassicHeaderMost));
  std::vector<unsigned char> b;
  // The first bytes, then 16 times as many each time the header runs past them (to 64 MiB).
  for (std::size_t want = std::min(most, kClassicHeaderFirst);; want = std::min(most, want * 16)) {
    const std::size_t had = b.size();
    b.resize(want);
    const std::size_t got = want > had ? std::fread(b.data() + had, 1, want - had, f.get()) : 0;
    b.resize(had + got);
    if (b.size() < 4 || b[0] != 'C' || b[1] != 'D' || b[2] != 'F' || (b[3] != 1 && b[3] != 2 && b[3] != 5)) return;  // not classic
    try {
      ClassicHeader(path, b, file_bytes).check();
      return;
    } catch (const NeedMoreBytes&) {
      // A file that is shorter than its size said (got < want - had) is read no further: its
      // header is walked against what there is.
      if (b.size() >= most || got < want - had) {
        file_bytes = b.size();
        ClassicHeader(path, b, file_bytes).check();
        return;
      }
    }
  }
}

const NcAtt* NcVar::att(const std::string& n) const {
  for (const auto& a : atts) {
    if (a.name == n) return &a;
  }
  return nullptr;
}

std::string NcVar::text(const std::string& n) const {
  const NcAtt* a = att(n);
  return a && a->is_text ? a->text : std::string();
}

std::optional<double> NcVar::number(const std::string& n) const {
  const NcAtt* a = att(n);
  if (!a || a->is_text || a->values.empty()) return std::nullopt;
  return a->values[0];
}

void NcFile::fail(int status, const std::string& what) const {
  throw ImportError(path_ + ": " + what + ": " + nc_strerror(status));
}

namespace {

// What the header holds, read by whoever holds the netCDF handle.
struct Header {
  int format = 0;
  std::vector<NcDim> dims;
  std::vector<NcVar> vars;
  std::vector<NcAtt> global_atts;
};

std::string open_error(const std::string& path, int status) {
  return path + ": not a readable NetCDF file (" + nc_strerror(status) +
         "); expected NetCDF-3 classic/64-bit or NetCDF-4/HDF5";
}

Header load_header(int id, const std::string& path) {
  auto fail = [&](int status, const std::string& what) { throw ImportError(path + ": " + what + ": " + nc_strerror(status)); };
  Header h;
  nc_inq_format(id, &h.format);
  int ndims = 0, nvars = 0, ngatts = 0, unlimdim = -1;
  if (const int s = nc_inq(id, &ndims, &nvars, &ngatts, &unlimdim); s != NC_NOERR) fail(s, "cannot read the header");
  for (int d = 0; d < ndims; ++d) {
    char name[NC_MAX_NAME + 1] = {0};
    size_t len = 0;
    if (const int s = nc_inq_dim(id, d, name, &len); s != NC_NOERR) fail(s, "cannot read dimension " + std::to_string(d));
    h.dims.push_back({name, len, d == unlimdim});
  }
  for (int v = 0; v < nvars; ++v) {
    char name[NC_MAX_NAME + 1] = {0};
    nc_type type;
    int nd = 0, natts = 0;
    int dimids[NC_MAX_VAR_DIMS];
    if (const int s = nc_inq_var(id, v, name, &type, &nd, dimids, &natts); s != NC_NOERR) {
      fail(s, "cannot read variable " + std::to_string(v));
    }
    NcVar var;
    var.id = v;
    var.name = name;
    var.type = type;
    for (int i = 0; i < nd; ++i) {
      if (dimids[i] < 0 || dimids[i] >= ndims) throw ImportError(path + ": variable '" + var.name + "' has a bad dimension id");
      var.dims.push_back(dimids[i]);
    }
    var.atts = read_atts(id, v, natts, path);
    h.vars.push_back(std::move(var));
  }
  h.global_atts = read_atts(id, NC_GLOBAL, ngatts, path);
  return h;
}

// The reader process's wire format: little-endian host integers and doubles, strings as a length
// and bytes. Both ends are this build, on this machine.
struct Wire {
  std::string b;
  void u64(std::uint64_t v) { b.append(reinterpret_cast<const char*>(&v), sizeof v); }
  void i64(std::int64_t v) { b.append(reinterpret_cast<const char*>(&v), sizeof v); }
  void f64(double v) { b.append(reinterpret_cast<const char*>(&v), sizeof v); }
  void str(const std::string& s) { u64(s.size()); b.append(s); }
  void atts(const std::vector<NcAtt>& as) {
    u64(as.size());
    for (const auto& a : as) {
      str(a.name);
      u64(a.is_text ? 1 : 0);
      str(a.text);
      u64(a.values.size());
      for (double x : a.values) f64(x);
    }
  }
  void header(const Header& h) {
    i64(h.format);
    u64(h.dims.size());
    for (const auto& d : h.dims) str(d.name), u64(d.length), u64(d.unlimited ? 1 : 0);
    u64(h.vars.size());
    for (const auto& v : h.vars) {
      i64(v.id), str(v.name), i64(v.type);
      u64(v.dims.size());
      for (int d : v.dims) i64(d);
      atts(v.atts);
    }
    atts(h.global_atts);
  }
};

bool send_all(int fd, const void* data, std::size_t n) {
  const char* p = static_cast<const char*>(data);
  while (n) {
    const ssize_t k = ::send(fd, p, n, MSG_NOSIGNAL);
    if (k < 0 && errno == EINTR) continue;
    if (k <= 0) return false;
    p += k, n -= static_cast<std::size_t>(k);
  }
  return true;
}

// Blocking receive of exactly n bytes (the reader's side; it has nothing else to do).
bool recv_all(int fd, void* data, std::size_t n) {
  char* p = static_cast<char*>(data);
  while (n) {
    const ssize_t k = ::recv(fd, p, n, 0);
    if (k < 0 && errno == EINTR) continue;
    if (k <= 0) return false;
    p += k, n -= static_cast<std::size_t>(k);
  }
  return true;
}

// Parses what the reader sent; a malformed message is this program's bug, not the file's.
struct Unwire {
  const std::string& b;
  std::size_t pos = 0;
  template <class T>
  T get() {
    if (pos + sizeof(T) > b.size()) throw std::runtime_error("NetCDF reader process: short message");
    T v;
    std::memcpy(&v, b.data() + pos, sizeof v);
    pos += sizeof v;
    return v;
  }
  std::string str() {
    const auto n = get<std::uint64_t>();
    if (n > b.size() - pos) throw std::runtime_error("NetCDF reader process: short message");
    std::string s = b.substr(pos, n);
    pos += n;
    return s;
  }
  std::vector<NcAtt> atts() {
    std::vector<NcAtt> out;
    const auto n = get<std::uint64_t>();
    for (std::uint64_t i = 0; i < n && pos < b.size(); ++i) {
      NcAtt a;
      a.name = str();
      a.is_text = get<std::uint64_t>() != 0;
      a.text = str();
      const auto nv = get<std::uint64_t>();
      if (nv > (b.size() - pos) / sizeof(double)) throw std::runtime_error("NetCDF reader process: short message");
      for (std::uint64_t k = 0; k < nv; ++k) a.values.push_back(get<double>());
      out.push_back(std::move(a));
    }
    return out;
  }
  Header header() {
    Header h;
    h.format = static_cast<int>(get<std::int64_t>());
    const auto nd = get<std::uint64_t>();
    for (std::uint64_t i = 0; i < nd && pos < b.size(); ++i) {
      NcDim d;
      d.name = str();
      d.length = get<std::uint64_t>();
      d.unlimited = get<std::uint64_t>() != 0;
      h.dims.push_back(std::move(d));
    }
    const auto nv = get<std::uint64_t>();
    for (std::uint64_t i = 0; i < nv && pos < b.size(); ++i) {
      NcVar v;
      v.id = static_cast<int>(get<std::int64_t>());
      v.name = str();
      v.type = static_cast<int>(get<std::int64_t>());
      const auto n = get<std::uint64_t>();
      for (std::uint64_t k = 0; k < n && pos < b.size(); ++k) v.dims.push_back(static_cast<int>(get<std::int64_t>()));
      v.atts = atts();
      h.vars.push_back(std::move(v));
    }
    h.global_atts = atts();
    return h;
  }
};

bool send_message(int fd, const std::string& m) {
  const std::uint64_t n = m.size();
  return send_all(fd, &n, sizeof n) && send_all(fd, m.data(), m.size());
}

// Seconds the reader may take to open the file and send its header, and to answer one read, before
// it is taken for hung (HDF5 1.10.8 loops forever in nc_open on some corrupt files: one changed byte
// of the shared ERA5 file does it). A header takes well under a second even for thousands of
// variables; a read is one slab of a variable.
struct Wait {
  const char* env;
  int default_s;
  int seconds() const {
    if (const char* v = std::getenv(env); v && std::atoi(v) > 0) return std::atoi(v);
    return default_s;
  }
};
constexpr Wait kOpenWait{"CLOUDVIEWER_OPEN_TIMEOUT_S", 30}, kReadWait{"CLOUDVIEWER_READ_TIMEOUT_S", 300};

// The reader process: opens the file, sends its header (or the error), then answers reads until
// the socket closes. It never returns; _exit keeps the parent's buffers and exit handlers out.
[[noreturn]] void reader_main(int fd, const std::string& path) {
  // Default actions: not the parent's temporary-file cleanup, and not a sanitizer's or a fuzzer's
  // crash report for what the parent turns into an ImportError.
  for (int sig : {SIGTERM, SIGINT, SIGHUP, SIGQUIT, SIGSEGV, SIGBUS, SIGILL, SIGFPE, SIGABRT, SIGALRM}) std::signal(sig, SIG_DFL);
  // Only its own socket stays open: a copy of another reader's socket held here would keep that
  // reader from seeing its end. When the parent dies, its end closes and the reader's next receive
  // ends it (no PR_SET_PDEATHSIG: that follows the forking thread, not the process).
  if (fd > 2) {
    ::close_range(3, static_cast<unsigned>(fd - 1), 0);
    ::close_range(static_cast<unsigned>(fd + 1), ~0u, 0);
  }
  int id = -1;
  {
    Wire w;
    try {
      // Each netCDF call runs under an alarm a little past the parent's wait: when HDF5 loops for
      // ever, SIGALRM ends the reader even if the parent is gone (killed, or interrupted) and so
      // cannot kill it, instead of a process spinning on alone.
      ::alarm(static_cast<unsigned>(kOpenWait.seconds() + 5));
      const int st = nc_open(path.c_str(), NC_NOWRITE, &id);
      if (st != NC_NOERR) throw ImportError(open_error(path, st));
      w.u64(0);
      w.header(load_header(id, path));
    } catch (const std::exception& e) {
      w.b.clear();
      w.u64(1);
      w.str(e.what());
    }
    ::alarm(0);
    if (!send_message(fd, w.b)) ::_exit(0);
  }
  std::vector<char> buf;
  for (;;) {
    std::uint64_t op = 0;
    if (!recv_all(fd, &op, sizeof op) || (op != 1 && op != 2)) break;
    std::int64_t varid = 0;
    std::uint64_t nd = 0, n = 0;
    if (!recv_all(fd, &varid, sizeof varid) || !recv_all(fd, &nd, sizeof nd) || nd > NC_MAX_VAR_DIMS) break;
    std::vector<std::size_t> start(nd), count(nd);
    if ((nd && (!recv_all(fd, start.data(), nd * sizeof(std::size_t)) || !recv_all(fd, count.data(), nd * sizeof(std::size_t)))) ||
        !recv_all(fd, &n, sizeof n)) {
      break;
    }
    const std::size_t bytes = op == 1 ? n * sizeof(double) : n;
    buf.resize(bytes);
    ::alarm(static_cast<unsigned>(kReadWait.seconds() + 5));
    std::int64_t st = op == 1 ? nc_get_vara_double(id, static_cast<int>(varid), start.data(), count.data(),
                                                   reinterpret_cast<double*>(buf.data()))
                              : nc_get_var_text(id, static_cast<int>(varid), buf.data());
    ::alarm(0);
    if (!send_all(fd, &st, sizeof st)) break;
    if (st == NC_NOERR && !send_all(fd, buf.data(), bytes)) break;
  }
  ::_exit(0);
}


bool classic_magic(const std::string& path) {
  unsigned char m[4] = {0, 0, 0, 0};
  if (std::FILE* f = std::fopen(path.c_str(), "rb")) {
    const std::size_t got = std::fread(m, 1, 4, f);
    std::fclose(f);
    if (got != 4) return false;
  }
  return m[0] == 'C' && m[1] == 'D' && m[2] == 'F' && (m[3] == 1 || m[3] == 2 || m[3] == 5);
}

}  // namespace

NcFile::NcFile(const std::string& path) : path_(path) {
  std::error_code ec;
  // A FIFO, a device or a folder is refused before netCDF opens it (it would block or read forever).
  if (const std::string kind = core::file_kind(path); !kind.empty()) {
    throw ImportError(path + (kind == "no such file" ? ": no such file" : ": is " + kind + ", expected a regular NetCDF file"));
  }
  file_bytes_ = static_cast<long long>(std::filesystem::file_size(path, ec));
  check_classic_header(path, static_cast<std::uint64_t>(std::max<long long>(file_bytes_, 0)));
  // Whatever fails from here on releases what was opened: the netCDF handle, or the reader process.
  try {
    Header h;
    if (classic_magic(path)) {
      const int st = nc_open(path.c_str(), NC_NOWRITE, &id_);
      if (st != NC_NOERR) {
        id_ = -1;
        throw ImportError(open_error(path, st));
      }
      h = load_header(id_, path);
    } else {
      isolated_ = true;
      start_reader();
      std::uint64_t n = 0;
      receive(&n, sizeof n, "opening it", true);
      if (n > (std::uint64_t(1) << 32)) throw std::runtime_error("NetCDF reader process: a header of " + std::to_string(n) + " bytes");
      std::string m(n, '\0');
      receive(m.data(), n, "opening it", true);
      Unwire u{m};
      if (u.get<std::uint64_t>() != 0) throw ImportError(u.str());
      h = u.header();
    }
    compressed_format_ = h.format == NC_FORMAT_NETCDF4 || h.format == NC_FORMAT_NETCDF4_CLASSIC;
    dims_ = std::move(h.dims);
    vars_ = std::move(h.vars);
    global_atts_ = std::move(h.global_atts);
    for (const auto& v : vars_) {
      for (int d : v.dims) {
        if (d < 0 || static_cast<std::size_t>(d) >= dims_.size()) throw ImportError(path + ": variable '" + v.name + "' has a bad dimension id");
      }
    }
    // A classic-format file stores every value uncompressed: if its variables need more bytes than
    // the file has, it was cut short (netCDF would read the missing part as zeros).
    if (!compressed_format_) {
      long double need = 0;
      for (const auto& v : vars_) need += static_cast<long double>(size(v)) * type_bytes(v.type);
      if (need > static_cast<long double>(file_bytes_)) {
        // Beyond 2^63 the count is no integer type's (a declared record count of 2^62 gets here):
        // written as a float.
        char needed[32];
        if (need < 9.0e18L) std::snprintf(needed, sizeof needed, "%lld", static_cast<long long>(need));
        else std::snprintf(needed, sizeof needed, "%.3Lg", need);
        throw ImportError(path + ": its variables need " + needed + " bytes but the file has " +
                          std::to_string(file_bytes_) + " (truncated); expected a complete file");
      }
    }
  } catch (...) {
    release();
    throw;
  }
}

void NcFile::start_reader() {
  int fds[2];
  if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, fds) != 0) {
    throw ImportError(path_ + ": cannot start the NetCDF reader process (socketpair: " + std::strerror(errno) + ")");
  }
  std::fflush(nullptr);  // nothing buffered is written twice
  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(fds[0]), ::close(fds[1]);
    throw ImportError(path_ + ": cannot start the NetCDF reader process (fork: " + std::strerror(errno) + ")");
  }
  if (pid == 0) {
    ::close(fds[0]);
    reader_main(fds[1], path_);
  }
  ::close(fds[1]);
  sock_ = fds[0];
  reader_pid_ = pid;
}

void NcFile::reader_lost(const std::string& what, bool timed_out, bool opening) const {
  int status = 0;
  if (reader_pid_ > 0) {
    if (timed_out) ::kill(reader_pid_, SIGKILL);
    ::close(sock_);
    while (::waitpid(reader_pid_, &status, 0) < 0 && errno == EINTR) {
    }
  }
  sock_ = -1;
  reader_pid_ = -1;
  if (timed_out) {
    const Wait& w = opening ? kOpenWait : kReadWait;
    throw ImportError(path_ + ": the NetCDF-4/HDF5 library did not answer within " + std::to_string(w.seconds()) + " s while " + what +
                      "; expected an intact NetCDF file (" + w.env + " sets the wait)");
  }
  std::string how = "stopped";
  if (WIFSIGNALED(status)) how = std::string("crashed (") + strsignal(WTERMSIG(status)) + ")";
  else if (WIFEXITED(status)) how = "stopped (exit status " + std::to_string(WEXITSTATUS(status)) + ")";
  throw ImportError(path_ + ": the NetCDF-4/HDF5 library " + how + " while " + what +
                    ": the file is corrupt; expected an intact NetCDF file");
}

void NcFile::receive(void* out, std::size_t bytes, const std::string& what, bool opening) const {
  if (sock_ < 0) throw ImportError(path_ + ": the NetCDF reader process stopped earlier; cannot go on " + what);
  char* p = static_cast<char*>(out);
  const int timeout_ms = (opening ? kOpenWait : kReadWait).seconds() * 1000;
  while (bytes) {
    pollfd pfd{sock_, POLLIN, 0};
    const int r = ::poll(&pfd, 1, timeout_ms);
    if (r < 0 && errno == EINTR) continue;
    if (r == 0) reader_lost(what, true, opening);
    const ssize_t k = ::recv(sock_, p, bytes, 0);
    if (k < 0 && errno == EINTR) continue;
    if (k <= 0) reader_lost(what, false, opening);
    p += k, bytes -= static_cast<std::size_t>(k);
  }
}

int NcFile::ask_reader(const std::string& request, const std::string& what) const {
  if (sock_ < 0) throw ImportError(path_ + ": the NetCDF reader process stopped earlier; cannot go on " + what);
  if (!send_all(sock_, request.data(), request.size())) reader_lost(what, false);
  std::int64_t st = 0;
  receive(&st, sizeof st, what);
  return static_cast<int>(st);
}

void NcFile::get_doubles(const NcVar& v, const std::vector<std::size_t>& start, const std::vector<std::size_t>& count,
                         double* out, std::size_t n) const {
  const std::string what = "reading variable '" + v.name + "'";
  if (!isolated_) {
    if (const int s = nc_get_vara_double(id_, v.id, start.data(), count.data(), out); s != NC_NOERR) {
      fail(s, "variable '" + v.name + "': cannot read values");
    }
    return;
  }
  Wire w;
  w.u64(1), w.i64(v.id), w.u64(start.size());
  for (std::size_t x : start) w.u64(x);
  for (std::size_t x : count) w.u64(x);
  w.u64(n);
  if (const int s = ask_reader(w.b, what); s != NC_NOERR) fail(s, "variable '" + v.name + "': cannot read values");
  receive(out, n * sizeof(double), what);
}

void NcFile::get_text(const NcVar& v, char* out, std::size_t n) const {
  if (!isolated_) {
    if (const int s = nc_get_var_text(id_, v.id, out); s != NC_NOERR) fail(s, "variable '" + v.name + "'");
    return;
  }
  Wire w;
  w.u64(2), w.i64(v.id), w.u64(0), w.u64(n);
  if (const int s = ask_reader(w.b, "reading variable '" + v.name + "'"); s != NC_NOERR) fail(s, "variable '" + v.name + "'");
  receive(out, n, "reading variable '" + v.name + "'");
}

NcFile::~NcFile() { release(); }

void NcFile::release() noexcept {
  if (id_ >= 0) nc_close(id_);
  id_ = -1;
  if (reader_pid_ > 0) {
    if (sock_ >= 0) ::close(sock_);
    ::kill(reader_pid_, SIGKILL);  // it holds nothing to save
    while (::waitpid(reader_pid_, nullptr, 0) < 0 && errno == EINTR) {
    }
  }
  sock_ = -1;
  reader_pid_ = -1;
}

const NcVar* NcFile::find(const std::string& name) const {
  for (const auto& v : vars_) {
    if (v.name == name) return &v;
  }
  return nullptr;
}

const NcVar& NcFile::var(const std::string& name) const {
  if (const NcVar* v = find(name)) return *v;
  throw ImportError(path_ + ": variable '" + name + "' is missing");
}

std::size_t NcFile::size(const NcVar& v) const {
  std::size_t n = 1;
  for (int d : v.dims) {
    const std::size_t len = dims_[static_cast<std::size_t>(d)].length;
    if (len != 0 && n > std::numeric_limits<std::size_t>::max() / len) return std::numeric_limits<std::size_t>::max();
    n *= len;
  }
  return n;
}

std::string NcFile::global_text(const std::string& name) const {
  for (const auto& a : global_atts_) {
    if (a.name == name && a.is_text) return a.text;
  }
  return "";
}

std::optional<double> NcFile::global_number(const std::string& name) const {
  for (const auto& a : global_atts_) {
    if (a.name == name && !a.is_text && !a.values.empty()) return a.values[0];
  }
  return std::nullopt;
}

void NcFile::whole_if_empty(const NcVar& v, std::vector<std::size_t>& start, std::vector<std::size_t>& count) const {
  if (start.empty()) start.assign(v.dims.size(), 0);
  if (count.empty()) {
    for (std::size_t i = 0; i < v.dims.size(); ++i) count.push_back(dim_length(v, i));
  }
}

std::vector<double> NcFile::read(const NcVar& v, std::vector<std::size_t> start, std::vector<std::size_t> count,
                                 UnpackInfo* info) const {
  std::vector<double> out;
  read_into(out, v, std::move(start), std::move(count), info);
  return out;
}

std::size_t NcFile::checked_read_count(const NcVar& v, const std::vector<std::size_t>& start,
                                       const std::vector<std::size_t>& count) const {
  const std::size_t nd = v.dims.size();
  if (start.size() != nd || count.size() != nd) {
    throw ImportError(path_ + ": variable '" + v.name + "': read with " + std::to_string(start.size()) +
                      " indices, expected " + std::to_string(nd));
  }
  std::size_t n = 1;
  for (std::size_t i = 0; i < nd; ++i) {
    if (start[i] + count[i] > dim_length(v, i)) {
      throw ImportError(path_ + ": variable '" + v.name + "': read beyond dimension '" + dim_name(v, i) + "'");
    }
    if (count[i] != 0 && n > kMaxReadValues / count[i]) n = kMaxReadValues + 1;
    else n *= count[i];
  }
  if (n > kMaxReadValues) {
    throw ImportError(path_ + ": variable '" + v.name + "': a read of more than " + std::to_string(kMaxReadValues) +
                      " values was asked for; subset the region, levels or times");
  }
  if (v.type == NC_CHAR || v.type == NC_STRING) {
    throw ImportError(path_ + ": variable '" + v.name + "' holds text, expected numbers");
  }
  try {
    core::require_within_memory_limit(path_, "variable '" + v.name + "': a read of " + std::to_string(n) + " values",
                                      core::checked_product({n, sizeof(double)}));
  } catch (const core::InputError& e) {
    throw ImportError(e.what());
  }
  return n;
}

namespace {
#if defined(__x86_64__) && defined(__GNUC__)
// read_float_into's int16 unpacking eight values at a time with AVX where the processor has it:
// each value sign-extended and widened to double, tested against the valid range and the two
// markers, and x * scale + offset rounded to float, the same operations as the SSE2 and scalar
// loops. Unpacks the first n / 8 * 8 values into o, adds the missing ones to `missed`, and
// returns how many it unpacked.
__attribute__((target("avx"))) std::size_t unpack_shorts_avx(const std::int16_t* r, std::size_t n, double lo, double hi,
                                                             double m0, double m1, double scale, double offset, float* o,
                                                             std::size_t& missed) {
  const __m256d vlo = _mm256_set1_pd(lo), vhi = _mm256_set1_pd(hi), vm0 = _mm256_set1_pd(m0), vm1 = _mm256_set1_pd(m1);
  const __m256d vscale = _mm256_set1_pd(scale), voffset = _mm256_set1_pd(offset);
  const __m128 vnan = _mm_set1_ps(std::numeric_limits<float>::quiet_NaN());
  std::size_t i = 0, count = 0;
  for (; i + 8 <= n; i += 8) {
    const __m128i eight = _mm_loadu_si128(reinterpret_cast<const __m128i*>(r + i));
    const __m128i lo4 = _mm_cvtepi16_epi32(eight), hi4 = _mm_cvtepi16_epi32(_mm_unpackhi_epi64(eight, eight));
    for (int half = 0; half < 2; ++half) {
      const __m256d x = _mm256_cvtepi32_pd(half ? hi4 : lo4);
      const __m256d miss = _mm256_or_pd(_mm256_or_pd(_mm256_cmp_pd(x, vlo, _CMP_LT_OQ), _mm256_cmp_pd(x, vhi, _CMP_GT_OQ)),
                                        _mm256_or_pd(_mm256_cmp_pd(x, vm0, _CMP_EQ_OQ), _mm256_cmp_pd(x, vm1, _CMP_EQ_OQ)));
      const __m128 y = _mm256_cvtpd_ps(_mm256_add_pd(_mm256_mul_pd(x, vscale), voffset));
      const int bits = _mm256_movemask_pd(miss);
      // The four lanes' masks as floats' (each 64-bit all-ones or zero packs to a 32-bit one).
      const __m128 m = _mm256_cvtpd_ps(miss);  // NaN where missed, 0 elsewhere
      const __m128 missf = _mm_cmpunord_ps(m, m);
      _mm_storeu_ps(o + i + 4 * static_cast<std::size_t>(half), _mm_or_ps(_mm_and_ps(missf, vnan), _mm_andnot_ps(missf, y)));
      count += core::mask_lanes(static_cast<unsigned>(bits));
    }
  }
  missed += count;
  return i;
}
#endif

// How a variable's stored values become physical ones (CF): markers of missing values compared in
// the packed domain (exactly for integer types, to 1e-6 for floats), a valid range, then
// x * scale + offset.
struct UnpackRules {
  std::vector<double> exact, approx;
  double lo = -std::numeric_limits<double>::infinity(), hi = std::numeric_limits<double>::infinity();
  double scale = 1.0, offset = 0.0;
  bool packed = false;
};
UnpackRules unpack_rules(const NcVar& v) {
  UnpackRules u;
  std::vector<double> missing;
  for (const char* a : {"_FillValue", "missing_value"}) {
    if (const NcAtt* att = v.att(a); att && !att->is_text) {
      for (double x : att->values) missing.push_back(x);
    }
  }
  if (!v.att("_FillValue") && v.type != NC_BYTE && v.type != NC_CHAR) {
    // netCDF's default fill for the type marks never-written values.
    double def = v.type == NC_SHORT ? NC_FILL_SHORT : v.type == NC_INT ? NC_FILL_INT
               : v.type == NC_FLOAT ? static_cast<double>(NC_FILL_FLOAT) : v.type == NC_DOUBLE ? NC_FILL_DOUBLE : NAN;
    if (!std::isnan(def)) missing.push_back(def);
  }
  std::optional<double> vmin, vmax;  // in the packed domain, as CF says
  if (const NcAtt* vr = v.att("valid_range"); vr && vr->values.size() == 2) vmin = vr->values[0], vmax = vr->values[1];
  if (auto x = v.number("valid_min")) vmin = x;
  if (auto x = v.number("valid_max")) vmax = x;
  u.scale = v.number("scale_factor").value_or(1.0);
  u.offset = v.number("add_offset").value_or(0.0);
  u.packed = v.att("scale_factor") || v.att("add_offset");
  const bool integer = is_integer_type(v.type);
  // Split the markers once: exact ones (integer types) and float ones matched to 1e-6. A NaN
  // marker needs no entry: isnan() catches exactly the values it marks.
  for (double m : missing) {
    if (!std::isnan(m)) (integer ? u.exact : u.approx).push_back(m);
  }
  u.lo = vmin.value_or(u.lo);
  u.hi = vmax.value_or(u.hi);
  return u;
}
}  // namespace

void NcFile::read_into(std::vector<double>& out, const NcVar& v, std::vector<std::size_t> start,
                       std::vector<std::size_t> count, UnpackInfo* info) const {
  whole_if_empty(v, start, count);
  const std::size_t n = checked_read_count(v, start, count);
  // Every value is written by get_doubles: a buffer of the right size is not cleared first.
  core::reserve_exact(out, n);
  if (out.size() != n) out.resize(n);
  if (n == 0) return;
  get_doubles(v, start, count, out.data(), n);
  const UnpackRules u = unpack_rules(v);
  const double scale = u.scale, offset = u.offset, lo = u.lo, hi = u.hi;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::size_t nmissing = 0;
  const std::vector<double>& exact = u.exact;
  const std::vector<double>& approx = u.approx;
  if (approx.empty() && exact.size() <= 2) {
    // The usual case (integer packing with a fill value and perhaps a missing value), without
    // branches: an unused marker is NaN, which equals nothing.
    const double m0 = exact.empty() ? nan : exact[0], m1 = exact.size() < 2 ? nan : exact[1];
    const double lo_ = lo, hi_ = hi, scale_ = scale, offset_ = offset;
    double* p = out.data();
    const std::size_t count_ = out.size();
    std::uint64_t missed = 0;
    std::size_t i = 0;
#if defined(__SSE2__)
    // Two at a time (GCC keeps the scalar loop below branchy and unvectorised).
    const __m128d vlo = _mm_set1_pd(lo_), vhi = _mm_set1_pd(hi_), vm0 = _mm_set1_pd(m0), vm1 = _mm_set1_pd(m1);
    const __m128d vscale = _mm_set1_pd(scale_), voffset = _mm_set1_pd(offset_), vnan = _mm_set1_pd(nan);
    __m128i vmissed = _mm_setzero_si128();
    for (; i + 2 <= count_; i += 2) {
      const __m128d x = _mm_loadu_pd(p + i);
      const __m128d miss = _mm_or_pd(_mm_or_pd(_mm_cmpunord_pd(x, x), _mm_or_pd(_mm_cmplt_pd(x, vlo), _mm_cmpgt_pd(x, vhi))),
                                     _mm_or_pd(_mm_cmpeq_pd(x, vm0), _mm_cmpeq_pd(x, vm1)));
      const __m128d y = _mm_add_pd(_mm_mul_pd(x, vscale), voffset);
      _mm_storeu_pd(p + i, _mm_or_pd(_mm_and_pd(miss, vnan), _mm_andnot_pd(miss, y)));
      vmissed = _mm_sub_epi64(vmissed, _mm_castpd_si128(miss));  // a miss lane is all ones: -1
    }
    alignas(16) std::uint64_t lanes[2];
    _mm_store_si128(reinterpret_cast<__m128i*>(lanes), vmissed);
    missed += lanes[0] + lanes[1];
#endif
    for (; i < count_; ++i) {
      const double x = p[i];
      const bool miss = (x != x) | (x < lo_) | (x > hi_) | (x == m0) | (x == m1);
      missed += miss ? 1 : 0;
      p[i] = miss ? nan : x * scale_ + offset_;
    }
    nmissing += missed;
  } else {
    for (double& x : out) {
      bool miss = std::isnan(x) || x < lo || x > hi;
      for (double m : exact) miss |= x == m;
      for (double m : approx) miss |= std::abs(x - m) <= 1e-6 * std::abs(m);
      if (miss) {
        x = nan;
        ++nmissing;
      } else {
        x = x * scale + offset;
      }
    }
  }
  if (info) *info = {scale, offset, u.packed, nmissing};
}

std::vector<float> NcFile::read_float(const NcVar& v, std::vector<std::size_t> start, std::vector<std::size_t> count,
                                      UnpackInfo* info) const {
  std::vector<float> out;
  read_float_into(out, v, std::move(start), std::move(count), info);
  return out;
}

bool NcFile::any_at_least(const NcVar& v, std::vector<std::size_t> start, std::vector<std::size_t> count,
                          double threshold) const {
  whole_if_empty(v, start, count);
  const UnpackRules rules = unpack_rules(v);
  if (isolated_ || v.type != NC_SHORT || !rules.approx.empty() || rules.exact.size() > 2) {
    std::vector<float>& values = floats_;
    read_float_into(values, v, std::move(start), std::move(count));
    for (float x : values) {
      if (x >= threshold) return true;
    }
    return false;
  }
  // What read_float_into's int16 path makes of each int16 value (the same tests and arithmetic),
  // compared as it is compared above: a table of 65536 answers.
  std::array<bool, 65536> hit{};
  const double lo = rules.lo, hi = rules.hi, scale = rules.scale, offset = rules.offset;
  const double m0 = rules.exact.empty() ? NAN : rules.exact[0], m1 = rules.exact.size() < 2 ? NAN : rules.exact[1];
  bool any_hit = false;
  for (int raw = -32768; raw <= 32767; ++raw) {
    const double x = raw;
    const bool miss = (x < lo) | (x > hi) | (x == m0) | (x == m1);
    const bool h = !miss && static_cast<double>(static_cast<float>(x * scale + offset)) >= threshold;
    hit[static_cast<std::uint16_t>(static_cast<std::int16_t>(raw))] = h;  // indexed by the int16's bits
    any_hit |= h;
  }
  if (!any_hit) {
    checked_read_count(v, start, count);  // the same checks a read makes, though nothing is read
    return false;
  }
  const std::size_t m = checked_read_count(v, start, count);
  std::vector<std::int16_t>& raw = shorts_;
  core::reserve_exact(raw, m);
  raw.resize(m);
  if (m) {
    if (const int st = nc_get_vara_short(id_, v.id, start.data(), count.data(), raw.data()); st != NC_NOERR) {
      fail(st, "variable '" + v.name + "': cannot read values");
    }
  }
  for (std::int16_t x : raw) {
    if (hit[static_cast<std::uint16_t>(x)]) return true;
  }
  return false;
}

void NcFile::read_float_into(std::vector<float>& out, const NcVar& v, std::vector<std::size_t> start,
                             std::vector<std::size_t> count, UnpackInfo* info) const {
  const std::size_t nd = v.dims.size();
  whole_if_empty(v, start, count);
  // int16 variables of an in-process file with the usual markers (at most two exact ones) are
  // read whole, straight into int16 and unpacked to float in one pass: netCDF's conversion to
  // double, the unpacking pass in double, and a netCDF call per level were most of a read.
  const UnpackRules rules = unpack_rules(v);
  const bool short_path = !isolated_ && v.type == NC_SHORT && rules.approx.empty() && rules.exact.size() <= 2;
  std::vector<std::int16_t>& raw = shorts_;
  // Else split along the first axis with more than one index; each chunk goes through read_into().
  std::size_t axis = 0;
  while (axis + 1 < nd && count[axis] == 1) ++axis;
  UnpackInfo total;
  const std::size_t chunks = short_path || !nd ? 1 : count[axis];
  // One chunk's doubles, reused from chunk to chunk (and call to call), written into
  // `out` in place: `out` keeps its memory when the caller reuses it.
  std::vector<double>& d = doubles_;
  std::size_t filled = 0;
  for (std::size_t c = 0; c < chunks; ++c) {
    std::vector<std::size_t> s = start, n = count;
    if (nd && chunks > 1) {
      s[axis] = start[axis] + c;
      n[axis] = 1;
    }
    UnpackInfo part;
    if (short_path) {
      // Straight from the file's int16 to float, in one pass: the values and the arithmetic are
      // those of read_into (x * scale + offset in double, then rounded to float).
      const std::size_t m = checked_read_count(v, s, n);
      core::reserve_exact(raw, m);
      raw.resize(m);
      if (m) {
        if (const int st = nc_get_vara_short(id_, v.id, s.data(), n.data(), raw.data()); st != NC_NOERR) {
          fail(st, "variable '" + v.name + "': cannot read values");
        }
      }
      if (c == 0 && out.size() != m * chunks) {
        core::reserve_exact(out, m * chunks);
        out.resize(m * chunks);
      }
      const double lo = rules.lo, hi = rules.hi, scale = rules.scale, offset = rules.offset;
      const double m0 = rules.exact.empty() ? NAN : rules.exact[0], m1 = rules.exact.size() < 2 ? NAN : rules.exact[1];
      const float nanf = std::numeric_limits<float>::quiet_NaN();
      float* o = out.data() + filled;
      const std::int16_t* r = raw.data();
      std::vector<std::size_t> missed_part(core::worker_count(), 0);
      core::parallel_ranges(m, std::size_t(1) << 20, [&](std::size_t b, std::size_t e, unsigned p) {
        std::size_t missed = 0;
        std::size_t i = b;
#if defined(__x86_64__) && defined(__GNUC__)
        if (core::cpu_has_avx()) i += unpack_shorts_avx(r + i, e - i, lo, hi, m0, m1, scale, offset, o + i, missed);
#endif
#if defined(__SSE2__) && defined(__x86_64__)
        // Four at a time in double pairs, as read_into unpacks (GCC leaves the scalar loop unvectorised).
        const __m128d vlo = _mm_set1_pd(lo), vhi = _mm_set1_pd(hi), vm0 = _mm_set1_pd(m0), vm1 = _mm_set1_pd(m1);
        const __m128d vscale = _mm_set1_pd(scale), voffset = _mm_set1_pd(offset);
        const __m128 vnan = _mm_set1_ps(nanf);
        __m128i vmissed = _mm_setzero_si128();
        for (; i + 4 <= e; i += 4) {
          std::int64_t four;
          std::memcpy(&four, r + i, sizeof four);
          // Four int16 to int32 (sign-extended), then to two pairs of doubles.
          const __m128i w = _mm_srai_epi32(_mm_unpacklo_epi16(_mm_cvtsi64_si128(four), _mm_cvtsi64_si128(four)), 16);
          const __m128d x0 = _mm_cvtepi32_pd(w), x1 = _mm_cvtepi32_pd(_mm_shuffle_epi32(w, 0x0e));
          auto miss_of = [&](__m128d x) {
            return _mm_or_pd(_mm_or_pd(_mm_cmplt_pd(x, vlo), _mm_cmpgt_pd(x, vhi)), _mm_or_pd(_mm_cmpeq_pd(x, vm0), _mm_cmpeq_pd(x, vm1)));
          };
          const __m128d miss0 = miss_of(x0), miss1 = miss_of(x1);
          const __m128 y = _mm_movelh_ps(_mm_cvtpd_ps(_mm_add_pd(_mm_mul_pd(x0, vscale), voffset)),
                                         _mm_cvtpd_ps(_mm_add_pd(_mm_mul_pd(x1, vscale), voffset)));
          const __m128 miss = _mm_movelh_ps(_mm_cvtpd_ps(miss0), _mm_cvtpd_ps(miss1));  // NaN lanes where missed
          const __m128i missi = _mm_castps_si128(_mm_cmpunord_ps(miss, miss));
          _mm_storeu_ps(o + i, _mm_or_ps(_mm_and_ps(_mm_castsi128_ps(missi), vnan), _mm_andnot_ps(_mm_castsi128_ps(missi), y)));
          vmissed = _mm_sub_epi32(vmissed, missi);
        }
        alignas(16) std::uint32_t lanes[4];
        _mm_store_si128(reinterpret_cast<__m128i*>(lanes), vmissed);
        missed += std::size_t(lanes[0]) + lanes[1] + lanes[2] + lanes[3];
#endif
        for (; i < e; ++i) {
          const double x = r[i];
          const bool miss = (x < lo) | (x > hi) | (x == m0) | (x == m1);
          missed += miss ? 1 : 0;
          o[i] = miss ? nanf : static_cast<float>(x * scale + offset);
        }
        missed_part[p] += missed;
      });
      std::size_t missed = 0;
      for (std::size_t k : missed_part) missed += k;
      filled += m;
      total.scale = scale, total.offset = offset, total.packed = rules.packed;
      total.missing += missed;
      continue;
    }
    read_into(d, v, s, n, &part);
    if (c == 0 && out.size() != d.size() * chunks) {
      core::reserve_exact(out, d.size() * chunks);
      out.resize(d.size() * chunks);
    }
    float* o = out.data() + filled;
    for (std::size_t i = 0; i < d.size(); ++i) o[i] = static_cast<float>(d[i]);
    filled += d.size();
    total.scale = part.scale, total.offset = part.offset, total.packed = part.packed;
    total.missing += part.missing;
  }
  out.resize(filled);
  if (info) *info = total;
}

std::vector<std::string> NcFile::read_strings(const NcVar& v) const {
  if (v.type != NC_CHAR || v.dims.size() != 2) {
    throw ImportError(path_ + ": variable '" + v.name + "': expected a 2-D character array");
  }
  const std::size_t rows = dim_length(v, 0), cols = dim_length(v, 1);
  // rows * cols checked for overflow: a wrapped product passed the bound and read past the buffer.
  const auto chars = core::checked_product({rows, cols});
  if (!chars || *chars > (1u << 24)) {
    throw ImportError(path_ + ": variable '" + v.name + "' is " + std::to_string(rows) + " x " + std::to_string(cols) +
                      " characters, expected at most 16 Mi characters of text");
  }
  std::vector<char> buf(rows * cols);
  if (!buf.empty()) {
    get_text(v, buf.data(), buf.size());
  }
  std::vector<std::string> out;
  for (std::size_t r = 0; r < rows; ++r) {
    std::string s(buf.data() + r * cols, cols);
    while (!s.empty() && (s.back() == '\0' || s.back() == ' ')) s.pop_back();
    out.push_back(s);
  }
  return out;
}

}  // namespace cv::importers
