// Writing outputs so that no failure, signal or planted file can leave a wrong file behind:
// - every output is written to a temporary file created exclusively in the output's own folder
//   (an unnamed O_TMPFILE where the file system has it, so even SIGKILL leaves nothing; else a
//   mkstemp-style name opened with O_CREAT | O_EXCL | O_NOFOLLOW, so no symbolic link planted in
//   the folder is ever followed), then renamed into place;
// - the temporary is removed when writing fails and when the process gets SIGTERM, SIGINT, SIGHUP
//   or SIGQUIT (install_output_cleanup);
// - files that belong together (a PNG and its PFMs, a volume with its report and VTI files) are
//   written in an OutputGroup and committed together: renamed into place only once all of them
//   are written, and the ones already renamed rolled back when a later rename fails.
#pragma once

#include <cstdio>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace cv::core {

// A failure of the output stream itself (disk full, I/O error), thrown by writers without the
// path; write_file_atomically and OutputGroup::write add the path.
class WriteError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// One output being written. The destructor removes the temporary unless commit() succeeded.
class OutputFile {
 public:
  explicit OutputFile(std::string path);
  ~OutputFile();
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  const std::string& path() const { return path_; }
  std::FILE* stream() { return f_; }
  // Flushes and syncs the data; throws std::runtime_error "<path>: write failed (<reason>)".
  void finish();
  // finish(), then the file takes its place at path() (replacing what was there).
  void commit();

  // For tests: false forces the named (mkstemp-style) temporary even where O_TMPFILE works.
  static void set_unnamed_temporaries(bool on);

 private:
  friend class OutputGroup;
  std::string link_to_hidden_name();  // the temporary under a fresh hidden name in the folder
  std::string path_, temp_;           // temp_: the named temporary ("" while unnamed)
  std::FILE* f_ = nullptr;
  int slot_ = -1;                     // its entry among the temporaries a signal removes
  bool unnamed_ = false, finished_ = false, committed_ = false;
};

// Calls write(stream) into an OutputFile and commits it. A std::runtime_error for a failure of the
// file itself names the path; anything `write` throws passes through unchanged. Either way nothing
// is left at `path` but what was there before.
void write_file_atomically(const std::string& path, const std::function<void(std::FILE*)>& write);

// Outputs committed together or not at all.
class OutputGroup {
 public:
  // Writes one member now (into its temporary); nothing appears at `path` before commit().
  void write(const std::string& path, const std::function<void(std::FILE*)>& write);
  // Every member takes its place; if one cannot, those already placed are put back as they were.
  void commit();
  std::vector<std::string> paths() const;

 private:
  std::vector<std::unique_ptr<OutputFile>> files_;
};

// Removes the temporaries in progress and re-raises on SIGTERM, SIGINT, SIGHUP and SIGQUIT.
void install_output_cleanup();

// Output paths, checked before any work starts. Each throws InputError naming the option.
// The folder of `path` exists, is a folder and can be written; `path` is not a folder.
void check_output_path(const std::string& path, const std::string& option);
// `path` ends with one of `extensions` (".png"; compared without regard to case).
void check_output_extension(const std::string& path, const std::string& option, const std::vector<std::string>& extensions);
// `output` is not the same file as `input` (the same path, or an existing file reached through
// another name: a link, "..", a hard link).
bool same_file(const std::string& a, const std::string& b);
void check_output_not_input(const std::string& output, const std::string& option, const std::string& input,
                            const std::string& input_what);

}  // namespace cv::core
