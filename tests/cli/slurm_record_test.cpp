// scripts/slurm/record.sbatch on a real single-node Slurm cluster (issue 16): tests/cli/slurm_record.sh
// starts one with scripts/slurm-local, submits a 4-task array and its dependent assemble job, checks
// that the frames and the MP4 equal a single-process run's, and stops and removes the cluster. Skipped,
// with the reason, only where the cluster cannot run: not root, or slurm-wlm and munge not installed.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <string>

namespace {

bool on_path(const std::string& program) {
  const char* path = std::getenv("PATH");
  std::string dirs = path ? path : "";
  std::size_t start = 0;
  while (start <= dirs.size()) {
    const std::size_t end = std::min(dirs.find(':', start), dirs.size());
    const std::filesystem::path p = std::filesystem::path(dirs.substr(start, end - start)) / program;
    if (::access(p.c_str(), X_OK) == 0) return true;
    start = end + 1;
  }
  return false;
}

TEST(SlurmRecord, ArrayJobEqualsOneProcess) {
  if (::geteuid() != 0) GTEST_SKIP() << "needs root: scripts/slurm-local runs munged and slurmd as root";
  for (const char* p : {"munged", "slurmctld", "slurmd", "sbatch", "squeue", "sinfo", "ffmpeg"}) {
    if (!on_path(p)) GTEST_SKIP() << p << " is not installed (Debian's slurm-wlm, munge and ffmpeg; scripts/setup installs them)";
  }
  const std::string cmd = std::string(CV_SOURCE_DIR) + "/tests/cli/slurm_record.sh '" + CV_CLOUDVIEWER + "' '" + CV_SAMPLE_FILE + "' '" +
                          CV_BINARY_DIR + "/cli_slurm_record' '" + CV_SOURCE_DIR + "'";
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0) << "tests/cli/slurm_record.sh failed (its output is above)";
}

}  // namespace
