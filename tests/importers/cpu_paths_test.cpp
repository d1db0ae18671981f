// The import's vector paths (AVX: int16 unpacking, the grid-box extinctions, the interpolation in
// altitude, the report's ranges, the half floats, the derived maps) against the baseline x86-64
// paths (SSE2 and scalar) that a processor without AVX takes: the same bits. On a machine with AVX
// the baseline paths otherwise run only as the vector loops' remainders.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "importer.hpp"
#include "io/cpu.hpp"
#include "support/nc_builder.hpp"
#include "support/real_data.hpp"
#include "volume/volume_io.hpp"

namespace {
using namespace cv;
namespace fs = std::filesystem;

// The baseline paths for the scope's life, also when an assertion leaves it.
struct BaselineCpu {
  explicit BaselineCpu(bool on) { core::set_baseline_cpu(on); }
  ~BaselineCpu() { core::set_baseline_cpu(false); }
  BaselineCpu(const BaselineCpu&) = delete;
  BaselineCpu& operator=(const BaselineCpu&) = delete;
};

std::string file_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

struct Imported {
  std::string cvvol, report;
};

Imported import_and_write(const std::string& path, const importers::ImportOptions& o, core::CvvolEncoding enc, bool baseline,
                          const fs::path& out) {
  BaselineCpu cpu(baseline);
  if (baseline) {
    EXPECT_FALSE(core::cpu_has_avx());
    EXPECT_FALSE(core::cpu_has_avx_f16c());
  }
  core::CloudVolume v = importers::import_file(path, o);
  core::write_cvvol(out.string(), v, nullptr, enc);  // loads every step, so the report is whole
  return {file_bytes(out), v.report.to_json()};
}

// One file imported with AVX and without, written as float16 (the steps held as half floats, as
// `import` does) and as float32: the same .cvvol bytes and the same report (whose ranges are the
// vectorised ones).
void expect_same_bits(const std::string& path, importers::ImportOptions o) {
  const fs::path dir = test::temp_dir("cpu_paths");
  for (const bool half : {true, false}) {
    SCOPED_TRACE(path + (half ? ", float16" : ", float32"));
    o.half_fields = half;
    const core::CvvolEncoding enc = half ? core::CvvolEncoding::Float16 : core::CvvolEncoding::Float32;
    const Imported vec = import_and_write(path, o, enc, false, dir / "vector.cvvol");
    const Imported base = import_and_write(path, o, enc, true, dir / "baseline.cvvol");
    ASSERT_GT(vec.cvvol.size(), 1000u);
    EXPECT_EQ(vec.cvvol.size(), base.cvvol.size());
    std::size_t differ = 0, first = 0;
    for (std::size_t i = 0; i < std::min(vec.cvvol.size(), base.cvvol.size()); ++i) {
      if (vec.cvvol[i] != base.cvvol[i] && differ++ == 0) first = i;
    }
    EXPECT_EQ(differ, 0u) << "bytes differ, the first at " << first << " of " << vec.cvvol.size();
    // The reports are long: the first difference, in context.
    const auto at = std::mismatch(vec.report.begin(), vec.report.end(), base.report.begin(), base.report.end());
    EXPECT_TRUE(at.first == vec.report.end() && at.second == base.report.end())
        << "reports differ; with AVX: ..." << vec.report.substr(static_cast<std::size_t>(std::max<std::ptrdiff_t>(0, at.first - vec.report.begin() - 60)), 120)
        << "...; without: ..." << base.report.substr(static_cast<std::size_t>(std::max<std::ptrdiff_t>(0, at.second - base.report.begin() - 60)), 120) << "...";
  }
  fs::remove_all(dir);
}

TEST(CpuPaths, TheSwitchTurnsTheVectorPathsOffAndOnAgain) {
  const bool had = core::cpu_has_avx();
  {
    BaselineCpu cpu(true);
    EXPECT_TRUE(core::baseline_cpu());
    EXPECT_FALSE(core::cpu_has_avx());
    EXPECT_FALSE(core::cpu_has_avx_f16c());
  }
  EXPECT_EQ(core::cpu_has_avx(), had);
  // Under CLOUDVIEWER_CPU=baseline the whole process is; ctest's importers.cpu_baseline run says it
  // set that (CV_EXPECT_BASELINE_CPU), so a run that lost the variable fails here instead of
  // repeating the vector paths' tests.
  const char* env = std::getenv("CLOUDVIEWER_CPU");
  if (std::getenv("CV_EXPECT_BASELINE_CPU")) {
    ASSERT_TRUE(env && std::string(env) == "baseline") << "importers.cpu_baseline without CLOUDVIEWER_CPU=baseline";
  }
  if (env && std::string(env) == "baseline") {
    EXPECT_TRUE(core::baseline_cpu());
    EXPECT_FALSE(core::cpu_has_avx());
    EXPECT_FALSE(core::cpu_has_avx_f16c());
  }
}

// The sample cyclone: float variables on a 121 x 81 grid (rows long enough for the vector loops).
TEST(CpuPaths, TheSampleImportsToTheSameBitsWithoutAvx) {
  if (!core::cpu_has_avx()) GTEST_SKIP() << "no AVX here (or CLOUDVIEWER_CPU=baseline): the baseline paths are the only ones";
  ASSERT_TRUE(fs::exists(CV_SAMPLE_FILE)) << CV_SAMPLE_FILE;
  importers::ImportOptions o;
  o.time_last = 1;
  expect_same_bits(CV_SAMPLE_FILE, o);
}

// Real files: ERA5 through grib_to_netcdf (NetCDF-4, read in the reader process through netCDF's
// doubles; tiny negatives of ice clamped), ERA5-style levels in a classic file with int16 variables
// (unpacked eight at a time with AVX) and a cloud diagnosed from humidity, and WRF (its own
// resampling into one-column rows).
TEST(CpuPaths, RealFilesImportToTheSameBitsWithoutAvx) {
  if (!core::cpu_has_avx()) GTEST_SKIP() << "no AVX here (or CLOUDVIEWER_CPU=baseline): the baseline paths are the only ones";
  {
    REAL_FILE(era5, "met-era5-cocip1.nc");
    expect_same_bits(era5, {});
  }
  {
    REAL_FILE(accf, "met-accf-pl.nc");
    importers::ImportOptions o;
    o.diagnose_cloud = true;
    expect_same_bits(accf, o);
  }
  {
    REAL_FILE(wrf, "wrf_d01_allvars_cropped.nc");
    expect_same_bits(wrf, {});
  }
}

}  // namespace
