// A time series is exposed once for all its frames (render --times): on the real WRF file from
// sunrise (00 UTC over Tibet) into the morning, no frame may be washed out by an exposure taken from
// the dawn frame alone, and the dawn frame itself is not black.
#include <gtest/gtest.h>
#include <stb_image.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string>

namespace {
namespace fs = std::filesystem;

struct Shares {
  double mean = 0.0;   // mean of the pixels' channel means, 0..1
  double white = 0.0;  // share of pixels whose channels all exceed 0.95
};

Shares png_shares(const fs::path& path) {
  int w = 0, h = 0, n = 0;
  unsigned char* px = stbi_load(path.c_str(), &w, &h, &n, 3);
  if (!px) throw std::runtime_error(path.string() + ": cannot read the PNG");
  Shares s;
  const long count = static_cast<long>(w) * h;
  for (long i = 0; i < count; ++i) {
    const unsigned char* p = px + i * 3;
    s.mean += (p[0] + p[1] + p[2]) / (3.0 * 255.0);
    s.white += (p[0] > 242 && p[1] > 242 && p[2] > 242) ? 1.0 : 0.0;
  }
  stbi_image_free(px);
  s.mean /= static_cast<double>(count), s.white /= static_cast<double>(count);
  return s;
}

TEST(SeriesExposure, AMorningSeriesIsNeitherWashedOutNorBlack) {
  const fs::path wrf = fs::path(CV_REAL_DATA_DIR) / "wrf_d01_allvars_cropped.nc";
  if (!fs::exists(wrf)) GTEST_SKIP() << wrf << " is not there";
  const fs::path out = fs::temp_directory_path() / ("cv_series_exposure_" + std::to_string(::getpid()));
  fs::remove_all(out);
  const std::string cmd = "timeout 300 " + std::string(CV_CLOUDVIEWER) + " render " + wrf.string() +
                          " --times 2005-09-21T00:00:00Z..2005-09-21T02:00:00Z --every 30m --size 32x18 --quality low -o " +
                          out.string() + " 2>&1";
  std::string text;
  FILE* p = ::popen(cmd.c_str(), "r");
  ASSERT_NE(p, nullptr);
  std::array<char, 4096> buf;
  std::size_t got;
  while ((got = std::fread(buf.data(), 1, buf.size(), p)) > 0) text.append(buf.data(), got);
  const int status = ::pclose(p);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << text;
  EXPECT_NE(text.find("exposure"), std::string::npos) << text;
  EXPECT_NE(text.find("the least of the automatic exposures of frames 0, 1, 2, 3, 4"), std::string::npos) << text;
  for (int k = 0; k < 5; ++k) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%05d.png", k);
    const Shares s = png_shares(out / name);
    std::printf("frame %d: mean %.3f, white %.1f %%\n", k, s.mean, 100.0 * s.white);
    EXPECT_LT(s.white, 0.5) << "frame " << k << " is washed out";
    EXPECT_GT(s.mean, 0.03) << "frame " << k << " is black";
    EXPECT_LT(s.mean, 0.92) << "frame " << k << " is washed out";
  }
  fs::remove_all(out);
}

}  // namespace
