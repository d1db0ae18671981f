// A thin, safe view of a NetCDF file (netCDF-C): dimensions, variables, attributes, and reads that
// unpack scale_factor/add_offset, turn _FillValue, missing_value and valid-range violations into NaN,
// and refuse sizes the file cannot hold. Private to the importers target.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "import_error.hpp"

namespace cv::importers {

struct NcDim {
  std::string name;
  std::size_t length = 0;
  bool unlimited = false;
};

struct NcAtt {
  std::string name;
  bool is_text = false;
  std::string text;
  std::vector<double> values;  // numeric attributes as double (NaN kept)
};

struct NcVar {
  int id = -1;
  std::string name;
  int type = 0;               // nc_type
  std::vector<int> dims;      // indices into NcFile::dims()
  std::vector<NcAtt> atts;
  const NcAtt* att(const std::string& name) const;
  std::string text(const std::string& name) const;           // "" when absent or not text
  std::optional<double> number(const std::string& name) const;
};

// How a variable's raw values were turned into numbers, for the import report.
struct UnpackInfo {
  double scale = 1.0;
  double offset = 0.0;
  bool packed = false;
  std::size_t missing = 0;  // values that became NaN
};

// netCDF-C's classic-format reader trusts the lengths its header declares (a crash and 16 GiB
// callocs, found by fuzzing): walks a classic (CDF-1, -2, -5) header first and throws ImportError
// when a declared length or count exceeds the file's bytes. Other formats pass. NcFile calls it
// before netCDF opens a file; anything else that hands netCDF untrusted bytes must too.
void check_classic_header(const std::string& path, std::uint64_t file_bytes);

// A NetCDF-4 file is read through the HDF5 library, which crashes on some corrupt files (a single
// flipped bit in a real WRF file makes nc_open segfault; found by flipping bytes of the shared
// files). NcFile therefore reads every file that is not classic-format in a child process that
// holds the netCDF handle and answers header and read requests over a socket: a crash or a hang
// there becomes an ImportError naming the file and what was being read, never a crash of the
// caller. Classic files, whose header NcFile checks itself first, are read in-process. The waits:
// CLOUDVIEWER_OPEN_TIMEOUT_S (default 30 s) for the header, CLOUDVIEWER_READ_TIMEOUT_S (300 s) a read.
class NcFile {
 public:
  explicit NcFile(const std::string& path);
  ~NcFile();
  NcFile(const NcFile&) = delete;
  NcFile& operator=(const NcFile&) = delete;

  const std::string& path() const { return path_; }
  const std::vector<NcDim>& dims() const { return dims_; }
  const std::vector<NcVar>& vars() const { return vars_; }
  const std::vector<NcAtt>& global_atts() const { return global_atts_; }
  const NcVar* find(const std::string& name) const;
  const NcVar& var(const std::string& name) const;  // throws ImportError when absent
  std::size_t dim_length(const NcVar& v, std::size_t axis) const { return dims_[v.dims[axis]].length; }
  std::string dim_name(const NcVar& v, std::size_t axis) const { return dims_[v.dims[axis]].name; }
  std::size_t size(const NcVar& v) const;  // number of values
  std::string global_text(const std::string& name) const;
  std::optional<double> global_number(const std::string& name) const;

  // Reads a hyperslab as double with unpacking and missing values as NaN. start/count have one
  // entry per dimension (empty: the whole variable).
  std::vector<double> read(const NcVar& v, std::vector<std::size_t> start = {}, std::vector<std::size_t> count = {},
                           UnpackInfo* info = nullptr) const;
  // The same into `out`, reusing its memory (a global step's slab is hundreds of megabytes: fresh
  // memory for it each step cost page faults and a clearing pass).
  void read_into(std::vector<double>& out, const NcVar& v, std::vector<std::size_t> start = {},
                 std::vector<std::size_t> count = {}, UnpackInfo* info = nullptr) const;
  // The same read into float, unpacked in double a chunk at a time, so a large slab never exists in
  // double (half the memory of read()).
  std::vector<float> read_float(const NcVar& v, std::vector<std::size_t> start = {}, std::vector<std::size_t> count = {},
                                UnpackInfo* info = nullptr) const;
  // The same into `out`, reusing its memory.
  void read_float_into(std::vector<float>& out, const NcVar& v, std::vector<std::size_t> start,
                       std::vector<std::size_t> count, UnpackInfo* info = nullptr) const;
  // Whether any value of the hyperslab, read as read_float_into reads it, is at least `threshold`
  // (NaN, missing, never is). For int16 variables read in process, the file's int16 values are
  // tested against a table of what each of the 65536 unpacks to, with no unpacking pass.
  bool any_at_least(const NcVar& v, std::vector<std::size_t> start, std::vector<std::size_t> count,
                    double threshold) const;
  // A text variable (e.g. WRF's Times) as one string per leading index.
  std::vector<std::string> read_strings(const NcVar& v) const;

  // The largest read, in values, this importer allows (guards against absurd headers).
  static constexpr std::size_t kMaxReadValues = std::size_t(1) << 31;

 private:
  [[noreturn]] void fail(int status, const std::string& what) const;
  void start_reader();  // forks the reader process and takes the header from it
  void release() noexcept;  // closes the netCDF handle, or stops and reaps the reader
  // nc_get_vara_double / nc_get_var_text, in-process or through the reader.
  void get_doubles(const NcVar& v, const std::vector<std::size_t>& start, const std::vector<std::size_t>& count,
                   double* out, std::size_t n) const;
  void get_text(const NcVar& v, char* out, std::size_t n) const;
  // The checks every read makes (indices, size, type, memory limit); returns the values asked for.
  std::size_t checked_read_count(const NcVar& v, const std::vector<std::size_t>& start,
                                 const std::vector<std::size_t>& count) const;
  // Sends a request and receives its status, or throws naming `what` when the reader died or hung.
  int ask_reader(const std::string& request, const std::string& what) const;
  // opening: the header, under the open wait (CLOUDVIEWER_OPEN_TIMEOUT_S), else a read's wait.
  void receive(void* out, std::size_t bytes, const std::string& what, bool opening = false) const;
  [[noreturn]] void reader_lost(const std::string& what, bool timed_out, bool opening = false) const;
  // An empty start means all zeros, an empty count the whole extent.
  void whole_if_empty(const NcVar& v, std::vector<std::size_t>& start, std::vector<std::size_t>& count) const;
  std::string path_;
  int id_ = -1;
  long long file_bytes_ = 0;
  bool compressed_format_ = false;
  bool isolated_ = false;        // read through the reader process
  mutable int sock_ = -1;        // the reader's socket; -1 once it is gone
  mutable int reader_pid_ = -1;
  // The reads' buffers, reused from call to call (their pages faulted in once): members rather
  // than thread_local, since a file is read from one thread at a time but not always the same one
  // (the CF import reads each band on a thread of its own).
  mutable std::vector<std::int16_t> shorts_;
  mutable std::vector<double> doubles_;
  mutable std::vector<float> floats_;
  std::vector<NcDim> dims_;
  std::vector<NcVar> vars_;
  std::vector<NcAtt> global_atts_;
};

}  // namespace cv::importers
