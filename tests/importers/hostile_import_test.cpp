// Hostile NetCDF (issue 13): each defect the fuzzing pass found, reproduced on a copy of a real file
// mutated with netCDF (or a small file written here), and refused with one line naming the file,
// the variable and what was expected, instead of a crash, a wrong volume or a library's message.
#include <gtest/gtest.h>

#include <netcdf.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "importer.hpp"
#include "nc_file.hpp"
#include "support/scratch_dir.hpp"
#include "support/nc_builder.hpp"
#include "support/real_data.hpp"

namespace {
using namespace cv;
namespace fs = std::filesystem;
using cv::test::nc_check;

class HostileImport : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("cv_hostile_import_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  // A writable copy of a real file; "" (and the test skipped) when the real files are absent.
  std::string copy_of(const std::string& real, const std::string& name) {
    const std::string dst = (dir_ / name).string();
    fs::copy_file(real, dst, fs::copy_options::overwrite_existing);
    fs::permissions(dst, fs::perms::owner_read | fs::perms::owner_write);
    return dst;
  }
  // Flips the bits of `mask` in the byte at `offset` of the file.
  static void xor_byte(const std::string& path, std::streamoff offset, unsigned char mask) {
    std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
    f.seekg(offset);
    char c = 0;
    f.read(&c, 1);
    c = static_cast<char>(c ^ mask);
    f.seekp(offset);
    f.write(&c, 1);
  }
  // The ImportError's message of importing `path` (fails the test when it imports).
  static std::string import_error(const std::string& path, const importers::ImportOptions& o = {}) {
    try {
      core::CloudVolume v = importers::import_file(path, o);
      v.step(0);
      for (std::size_t t = 0; t < v.times.size(); ++t) v.step(t);
    } catch (const importers::ImportError& e) {
      return e.what();
    }
    ADD_FAILURE() << path << " was imported; expected an ImportError";
    return "";
  }
  fs::path dir_;
};

// Opens a file for changes in define mode.
struct Edit {
  int id = -1;
  explicit Edit(const std::string& path) {
    nc_check(nc_open(path.c_str(), NC_WRITE, &id), "open " + path);
    nc_redef(id);
  }
  ~Edit() { nc_close(id); }
  int var(const char* name) {
    int v = -1;
    nc_check(nc_inq_varid(id, name, &v), std::string("var ") + name);
    return v;
  }
  void number(int var, const char* att, double value, nc_type type = NC_FLOAT) {
    nc_check(nc_put_att_double(id, var, att, type, 1, &value), att);
  }
  void text(int var, const char* att, const std::string& value) {
    nc_check(nc_put_att_text(id, var, att, value.size(), value.c_str()), att);
  }
  // Every value of a numeric variable set by f(index).
  template <class F>
  void fill(const char* name, F f) {
    nc_enddef(id);
    const int v = var(name);
    int nd = 0;
    int dims[NC_MAX_VAR_DIMS];
    nc_check(nc_inq_varndims(id, v, &nd), "ndims");
    nc_check(nc_inq_vardimid(id, v, dims), "dims");
    std::size_t n = 1;
    for (int d = 0; d < nd; ++d) {
      std::size_t len = 0;
      nc_inq_dimlen(id, dims[d], &len);
      n *= len;
    }
    std::vector<double> values(n);
    for (std::size_t i = 0; i < n; ++i) values[i] = f(i);
    nc_check(nc_put_var_double(id, v, values.data()), std::string("put ") + name);
  }
};

TEST_F(HostileImport, NanTrueLatitudeIsNamedNotLeftToGeographicLib) {
  REAL_FILE(real, "wrf_d01_allvars_cropped.nc");
  const std::string p = copy_of(real, "truelat.nc");
  {
    Edit e(p);
    e.number(NC_GLOBAL, "TRUELAT1", std::nan(""));
  }
  const std::string msg = import_error(p);
  EXPECT_NE(msg.find(p + ": global attribute 'TRUELAT1' is nan, expected a latitude within -90..90"), std::string::npos) << msg;
}

TEST_F(HostileImport, NanXlatIsNamedNotAVectorLengthError) {
  REAL_FILE(real, "wrf_d01_allvars_cropped.nc");
  const std::string p = copy_of(real, "xlat.nc");
  {
    Edit e(p);
    e.fill("XLAT", [](std::size_t i) { return i == 5 ? std::nan("") : 30.0 + 0.01 * static_cast<double>(i); });
  }
  const std::string msg = import_error(p);
  EXPECT_NE(msg.find("variable 'XLAT' has value nan at mass point 5, expected a latitude within -90..90"), std::string::npos) << msg;
}

TEST_F(HostileImport, ImpossibleWrfTimeIsRefused) {
  REAL_FILE(real, "wrf_d01_allvars_cropped.nc");
  const std::string p = copy_of(real, "times.nc");
  {
    Edit e(p);
    nc_enddef(e.id);
    const std::string bad = "2005-13-41_25:61:61";
    const std::size_t start[2] = {1, 0}, count[2] = {1, bad.size()};
    nc_check(nc_put_vara_text(e.id, e.var("Times"), start, count, bad.c_str()), "Times");
  }
  const std::string msg = import_error(p);
  EXPECT_NE(msg.find("variable 'Times': time '2005-13-41_25:61:61' is no real date and time"), std::string::npos) << msg;
}

TEST_F(HostileImport, ConstantGeopotentialGivesNoOneLevelVolume) {
  REAL_FILE(real, "wrf_d01_allvars_cropped.nc");
  const std::string p = copy_of(real, "flat.nc");
  {
    Edit e(p);
    e.fill("PH", [](std::size_t) { return 0.0; });
    e.fill("PHB", [](std::size_t) { return 9.81 * 5000.0; });
  }
  const std::string msg = import_error(p);
  EXPECT_NE(msg.find(p + ": the levels' heights span no altitude range (all at 5000 m)"), std::string::npos) << msg;
}

TEST_F(HostileImport, HugeDzGivesNoOneLevelVolume) {
  REAL_FILE(real, "met-era5-cocip1.nc");
  importers::ImportOptions o;
  o.dz_m = 1e300;
  const std::string msg = import_error(real, o);
  EXPECT_NE(msg.find("--dz (dz_m): found a spacing of 1e+300 m"), std::string::npos) << msg;
  EXPECT_NE(msg.find("expected 2 to 1000000 levels"), std::string::npos) << msg;
  o.dz_m = 1e-300;  // and the other way: a count no int holds (float-cast-overflow before)
  const std::string tiny = import_error(real, o);
  EXPECT_NE(tiny.find("--dz (dz_m): found a spacing of 1e-300 m"), std::string::npos) << tiny;
}

TEST_F(HostileImport, AllEqualLongitudesAreRefused) {
  REAL_FILE(real, "met-era5-cocip1.nc");
  const std::string p = copy_of(real, "lon_equal.nc");
  {
    Edit e(p);
    e.fill("longitude", [](std::size_t) { return 10.0; });
  }
  const std::string msg = import_error(p);
  EXPECT_NE(msg.find(p + ": coordinate 'longitude' has 16 values at the same longitude (modulo 360), expected 16 distinct longitudes"),
            std::string::npos)
      << msg;
}

TEST_F(HostileImport, TwoInterleavedTurnsOfLongitudeAreRefused) {
  REAL_FILE(real, "met-era5-cocip1.nc");
  const std::string p = copy_of(real, "lon_720.nc");
  {
    Edit e(p);
    // 0, 360, 45, 405, ...: 0..720 with every place twice.
    e.fill("longitude", [](std::size_t i) { return 45.0 * static_cast<double>(i / 2) + 360.0 * static_cast<double>(i % 2); });
  }
  const std::string msg = import_error(p);
  EXPECT_NE(msg.find("coordinate 'longitude' has"), std::string::npos) << msg;
  EXPECT_NE(msg.find("at the same longitude (modulo 360)"), std::string::npos) << msg;
}

TEST_F(HostileImport, GarbageTimeUnitsAreNamedNotTakenAsNoTimeCoordinate) {
  REAL_FILE(real, "met-era5-cocip1.nc");
  const std::string p = copy_of(real, "time_units.nc");
  {
    Edit e(p);
    e.text(e.var("time"), "units", "fortnights, roughly");
  }
  const std::string msg = import_error(p);
  EXPECT_NE(msg.find(p + ": variable 'time' (the time coordinate) has units 'fortnights, roughly', expected '<unit> since"),
            std::string::npos)
      << msg;
}

TEST_F(HostileImport, WaterInGramsPerKilogramIsNotReadAsKilogramsPerKilogram) {
  REAL_FILE(real, "met-era5-cocip1.nc");
  const std::string p = copy_of(real, "gkg.nc");
  {
    Edit e(p);
    e.text(e.var("specific_cloud_ice_water_content"), "units", "g kg-1");
  }
  const std::string msg = import_error(p);
  EXPECT_NE(msg.find(p + ": variable 'specific_cloud_ice_water_content' (cloud ice water) has units 'g kg-1', expected a mass fraction in kg kg-1"),
            std::string::npos)
      << msg;
}

TEST_F(HostileImport, TwoDimensionalCloudWaterIsNamedNotDropped) {
  const std::string p = (dir_ / "clwc2d.nc").string();
  {
    test::NcBuilder b(p);
    const int dx = b.dim("longitude", 4), dy = b.dim("latitude", 3), dz = b.dim("level", 3);
    const int lon = b.var("longitude", NC_DOUBLE, {dx}), lat = b.var("latitude", NC_DOUBLE, {dy}), lev = b.var("level", NC_DOUBLE, {dz});
    b.text(lon, "units", "degrees_east");
    b.text(lat, "units", "degrees_north");
    b.text(lev, "units", "hPa");
    const int cc = b.var("cc", NC_FLOAT, {dz, dy, dx});
    const int clwc = b.var("clwc", NC_FLOAT, {dy, dx});
    b.put(lon, {0, 1, 2, 3});
    b.put(lat, {10, 11, 12});
    b.put(lev, {500, 700, 850});
    b.put(cc, std::vector<double>(36, 0.5));
    b.put(clwc, std::vector<double>(12, 1e-4));
    b.close();
  }
  const std::string msg = import_error(p);
  EXPECT_NE(msg.find(p + ": variable 'clwc' (cloud liquid water) has 2 dimension(s) (latitude, longitude), expected a 3-D field"),
            std::string::npos)
      << msg;
}

TEST_F(HostileImport, TextVariableWhoseSizeWrapsIsRefusedBeforeAnyRead) {
  // char Times(2^33, 2^31): rows * cols is 2^64, which wrapped to 0 and passed the size check,
  // and netCDF then wrote the whole variable into an empty buffer (a heap overflow).
  const std::string p = (dir_ / "times_wrap.nc").string();
  {
    int id = -1, d[2], v = -1;
    nc_check(nc_create(p.c_str(), NC_CLOBBER | NC_NETCDF4, &id), "create");
    nc_check(nc_def_dim(id, "Time", std::size_t(1) << 33, &d[0]), "dim");
    nc_check(nc_def_dim(id, "DateStrLen", std::size_t(1) << 31, &d[1]), "dim");
    const std::size_t chunks[2] = {1, 1024};
    nc_check(nc_def_var(id, "Times", NC_CHAR, 2, d, &v), "var");
    nc_check(nc_def_var_chunking(id, v, NC_CHUNKED, chunks), "chunking");
    nc_check(nc_close(id), "close");
  }
  importers::NcFile f(p);
  try {
    f.read_strings(f.var("Times"));
    ADD_FAILURE() << "read";
  } catch (const importers::ImportError& e) {
    EXPECT_NE(std::string(e.what()).find(p + ": variable 'Times' is 8589934592 x 2147483648 characters, expected at most 16 Mi"),
              std::string::npos)
        << e.what();
  }
}

TEST_F(HostileImport, FifoAndDeviceAreRefusedWithoutBlocking) {
  const std::string fifo = (dir_ / "pipe.nc").string();
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_EQ(import_error(fifo), fifo + ": is a FIFO (named pipe), expected a regular NetCDF file");
  EXPECT_EQ(import_error("/dev/zero"), "/dev/zero: is a character device, expected a regular NetCDF file");
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 5.0);
}

TEST_F(HostileImport, ReadsBeyondTheMemoryLimitAreRefusedBeforeAllocating) {
  REAL_FILE(real, "met-era5-cocip1.nc");
  core::set_memory_limit_bytes(1024);  // smaller than one read of the file's variables
  const std::string msg = import_error(real);
  core::set_memory_limit_bytes(0);
  EXPECT_NE(msg.find("values would take"), std::string::npos) << msg;
  EXPECT_NE(msg.find("expected at most the memory limit 1 KiB (set CLOUDVIEWER_MEMORY_LIMIT to change it)"), std::string::npos) << msg;
}

TEST_F(HostileImport, CorruptClassicHeaderIsRefusedBeforeNetcdfReadsIt) {
  // A name length of 2^32 - 1 in a classic header made netCDF-C memcpy a negative size (a crash
  // fuzz_netcdf found); a large one made it calloc that much. The 64-bit-offset real file with its
  // first dimension's name length patched.
  REAL_FILE(real, "met-accf-pl.nc");
  const std::string p = copy_of(real, "header.nc");
  EXPECT_NO_THROW(importers::NcFile{p});  // the file as it is opens
  for (const std::uint32_t declared : {0xFFFFFFFFu, 0x7FFFFFF0u}) {
    {
      std::fstream f(p, std::ios::in | std::ios::out | std::ios::binary);
      f.seekp(16);  // magic, record count, the dimension list's tag and count
      const unsigned char be[4] = {static_cast<unsigned char>(declared >> 24), static_cast<unsigned char>(declared >> 16),
                                   static_cast<unsigned char>(declared >> 8), static_cast<unsigned char>(declared)};
      f.write(reinterpret_cast<const char*>(be), 4);
    }
    const std::string msg = import_error(p);
    EXPECT_NE(msg.find(p + ": the netCDF classic header is corrupt: the name of dimension 0 declares " + std::to_string(declared)),
              std::string::npos)
        << msg;
  }
}

TEST_F(HostileImport, AClassicHeaderLongerThanItsFirstReadIsWalkedToItsEnd) {
  // The header is read 256 KiB at first and further only as it needs (a big file is not read
  // 64 MiB deep to check a header of a few kilobytes): a valid header of 600 KB opens, and a
  // corrupt length beyond the first read is still found before netCDF reads it.
  const std::string p = (dir_ / "long_header.nc").string();
  const std::string history(600000, 'h');
  {
    int nc, x, v;
    ASSERT_EQ(nc_create(p.c_str(), NC_CLOBBER | NC_64BIT_OFFSET, &nc), NC_NOERR);
    ASSERT_EQ(nc_def_dim(nc, "x", 1 << 20, &x), NC_NOERR);
    ASSERT_EQ(nc_put_att_text(nc, NC_GLOBAL, "history", history.size(), history.data()), NC_NOERR);
    ASSERT_EQ(nc_def_var(nc, "v", NC_FLOAT, 1, &x, &v), NC_NOERR);
    ASSERT_EQ(nc_enddef(nc), NC_NOERR);
    ASSERT_EQ(nc_close(nc), NC_NOERR);  // the variable's fill values follow: about 4.8 MB in all
  }
  ASSERT_GT(std::filesystem::file_size(p), std::uintmax_t(4) << 20);
  EXPECT_NO_THROW(importers::NcFile{p});
  // The variable's name length: after the magic and record count (8), the dimension list (8 + 12),
  // the attribute list's tag and count (8), the attribute's name (4 + 8), type and length (8), its
  // values (600 000) and the variable list's tag and count (8).
  const std::streamoff at = 8 + 20 + 8 + 12 + 8 + 600000 + 8;
  {
    std::fstream f(p, std::ios::in | std::ios::out | std::ios::binary);
    f.seekg(at);
    unsigned char was[4] = {};
    f.read(reinterpret_cast<char*>(was), 4);
    ASSERT_EQ(was[3], 1u) << "the layout above is not the file's: 'v' has a name of length 1";
    f.seekp(at);
    const unsigned char be[4] = {0x7F, 0xFF, 0xFF, 0xF0};
    f.write(reinterpret_cast<const char*>(be), 4);
  }
  const std::string msg = import_error(p);
  EXPECT_NE(msg.find(p + ": the netCDF classic header is corrupt: the name of variable 0 declares 2147483632"), std::string::npos)
      << msg;
}

// fuzz_netcdf: netCDF-C took a CDF-5 variable of type NC_STRING (12, a netCDF-4 type) with a size
// of 0 and divided by it while opening the file (a floating-point exception). A CDF-5 file with one
// variable v(x, y), its type and then its first dimension's length patched; each is named before
// netCDF reads the header.
TEST_F(HostileImport, AClassicVariableOfNoClassicTypeOrAnEndlessDimensionIsNamedNotACrash) {
  const std::string p = (dir_ / "types.nc").string();
  auto write = [&] {
    int nc, x, y, v;
    ASSERT_EQ(nc_create(p.c_str(), NC_CLOBBER | NC_64BIT_DATA, &nc), NC_NOERR);
    ASSERT_EQ(nc_def_dim(nc, "x", 4, &x), NC_NOERR);
    ASSERT_EQ(nc_def_dim(nc, "y", 3, &y), NC_NOERR);
    const int dims[2] = {x, y};
    ASSERT_EQ(nc_def_var(nc, "v", NC_FLOAT, 2, dims, &v), NC_NOERR);
    ASSERT_EQ(nc_close(nc), NC_NOERR);
  };
  // The header: magic 4, record count 8, the dimension list (tag 4, count 8, then per dimension a
  // name length 8, the name padded to 4 and a length 8), no attributes (12), the variable list
  // (tag 4, count 8), v's name (8 + 4), its dimension count and ids (8 + 16), no attributes (12),
  // then its type.
  auto patch = [&](std::streamoff at, int width, std::uint64_t expected, std::uint64_t value) {
    std::fstream f(p, std::ios::in | std::ios::out | std::ios::binary);
    f.seekg(at);
    std::uint64_t was = 0;
    for (int k = 0; k < width; ++k) was = (was << 8) | static_cast<unsigned char>(f.get());
    ASSERT_EQ(was, expected) << "the layout above is not the file's at byte " << at;
    f.seekp(at);
    for (int k = width - 1; k >= 0; --k) f.put(static_cast<char>((value >> (8 * k)) & 0xFF));
  };
  write();
  EXPECT_NO_THROW(importers::NcFile{p});
  patch(136, 4, NC_FLOAT, 12);  // NC_STRING
  std::string msg = import_error(p);
  EXPECT_NE(msg.find(p + ": the netCDF classic header is corrupt: variable 0's type declares 12"), std::string::npos) << msg;
  write();
  patch(36, 8, 4, std::uint64_t(1) << 63);  // x's length
  msg = import_error(p);
  EXPECT_NE(msg.find(p + ": the netCDF classic header is corrupt: the length of variable 0's dimension 0 (dimension 0) declares " +
                     std::to_string(std::uint64_t(1) << 63)),
            std::string::npos)
      << msg;
}

TEST_F(HostileImport, ARecordCountBeyondAnyIntegerIsNamedNotOverflowed) {
  // fuzz_netcdf: a classic header declaring 2^62 records made the truncation check's byte count
  // overflow its conversion to long long (undefined behaviour; UBSan's float-cast-overflow). A
  // CDF-5 file with a record variable of two records, its record count patched.
  const std::string p = (dir_ / "records.nc").string();
  {
    int nc, t, x, v;
    ASSERT_EQ(nc_create(p.c_str(), NC_CLOBBER | NC_64BIT_DATA, &nc), NC_NOERR);
    ASSERT_EQ(nc_def_dim(nc, "time", NC_UNLIMITED, &t), NC_NOERR);
    ASSERT_EQ(nc_def_dim(nc, "x", 4, &x), NC_NOERR);
    const int dims[2] = {t, x};
    ASSERT_EQ(nc_def_var(nc, "v", NC_FLOAT, 2, dims, &v), NC_NOERR);
    ASSERT_EQ(nc_enddef(nc), NC_NOERR);
    const std::size_t start[2] = {0, 0}, count[2] = {2, 4};
    const std::vector<double> ones(8, 1.0);
    ASSERT_EQ(nc_put_vara_double(nc, v, start, count, ones.data()), NC_NOERR);
    ASSERT_EQ(nc_close(nc), NC_NOERR);
  }
  {
    std::fstream f(p, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(4);  // after the magic: the record count, 8 bytes big-endian in CDF-5
    const unsigned char be[8] = {0x40, 0, 0, 0, 0, 0, 0, 0};
    f.write(reinterpret_cast<const char*>(be), 8);
  }
  const std::string msg = import_error(p);
  EXPECT_NE(msg.find(p + ": its variables need 7.38e+19 bytes but the file has "), std::string::npos) << msg;
}


// The HDF5 library (Debian 12's 1.10.8) segfaults in nc_open on some NetCDF-4 files with a single
// flipped bit: found by flipping bytes of the shared real files (docs/BENCHMARKS.md, "NetCDF-4 under
// byte flips"). NcFile reads such files in a child process, so the crash is one line naming the
// file and what was being done, never a crash of the importer.
TEST_F(HostileImport, ABitFlippedNetcdf4FileThatCrashesHdf5IsNamedNotACrash) {
  REAL_FILE(real, "wrf_d01_allvars_cropped.nc");
  const struct {
    std::streamoff offset;
    unsigned char mask;
  } flips[] = {{86262, 0x02}, {119010, 0x08}};
  for (const auto& flip : flips) {
    const std::string p = copy_of(real, "flip" + std::to_string(flip.offset) + ".nc");
    xor_byte(p, flip.offset, flip.mask);
    const std::string msg = import_error(p);
    // A segmentation fault in this build; under the sanitizers' allocator it may be an abort.
    EXPECT_NE(msg.find(p + ": the NetCDF-4/HDF5 library crashed ("), std::string::npos) << msg;
    EXPECT_NE(msg.find(") while opening it: the file is corrupt; expected an intact NetCDF file"), std::string::npos) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
  }
}

// HDF5 1.10.8 loops forever in nc_open (H5DSget_num_scales reading a global heap) on the shared
// ERA5 file with one byte changed: found by bench_flip_campaign. The header's wait ends it with one
// line naming the file, the wait and its setting, and the reader is killed.
TEST_F(HostileImport, ANetcdf4FileThatHangsHdf5InOpenIsNamedAfterTheWait) {
  REAL_FILE(real, "met-era5-cocip1.nc");
  const std::string p = copy_of(real, "hang.nc");
  xor_byte(p, 19631, 0x02);  // 0 -> 2
  ::setenv("CLOUDVIEWER_OPEN_TIMEOUT_S", "2", 1);
  const auto t0 = std::chrono::steady_clock::now();
  const std::string msg = import_error(p);
  ::unsetenv("CLOUDVIEWER_OPEN_TIMEOUT_S");
  EXPECT_NE(msg.find(p + ": the NetCDF-4/HDF5 library did not answer within 2 s while opening it; expected an intact NetCDF file "
                         "(CLOUDVIEWER_OPEN_TIMEOUT_S sets the wait)"),
            std::string::npos)
      << msg;
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 30.0);
}

// A process's state letter from /proc (R, S, Z, ...), or 0 when it is gone.
char process_state(int pid) {
  std::ifstream f("/proc/" + std::to_string(pid) + "/stat");
  std::string stat;
  if (!std::getline(f, stat)) return 0;
  const std::size_t close = stat.rfind(')');
  return close != std::string::npos && close + 2 < stat.size() ? stat[close + 2] : 0;
}

// When the process that opened a file is killed while HDF5 loops in its reader (a user's Ctrl-C,
// a batch job's kill), nothing is left to kill the reader: its own alarm, a little past the wait,
// ends it instead of a process spinning on alone.
TEST_F(HostileImport, AReaderLeftAloneInAnHdf5LoopEndsOnItsOwn) {
  REAL_FILE(real, "met-era5-cocip1.nc");
  const std::string p = copy_of(real, "orphan.nc");
  xor_byte(p, 19631, 0x02);  // 0 -> 2
  // The opener's wait, 3 s, and so the reader's alarm, 3 + 5 s; the opener is killed well before.
  const pid_t opener = ::fork();
  if (opener == 0) {
    ::setenv("CLOUDVIEWER_OPEN_TIMEOUT_S", "3", 1);
    try {
      importers::NcFile f(p);
    } catch (...) {
    }
    ::_exit(0);
  }
  ASSERT_GT(opener, 0);
  int reader = -1;
  for (int i = 0; i < 100 && reader < 0; ++i) {  // the opener's child: its reader
    std::ifstream kids("/proc/" + std::to_string(opener) + "/task/" + std::to_string(opener) + "/children");
    if (!(kids >> reader)) reader = -1;
    if (reader < 0) ::usleep(50000);
  }
  ASSERT_GT(reader, 0) << "the opener started no reader";
  ::usleep(500000);
  EXPECT_EQ(process_state(reader), 'R') << "HDF5 spins in nc_open on this file";
  ::kill(opener, SIGKILL);
  ::waitpid(opener, nullptr, 0);
  const auto t0 = std::chrono::steady_clock::now();
  char state = process_state(reader);
  while (state != 0 && state != 'Z' && std::chrono::steady_clock::now() - t0 < std::chrono::seconds(60)) {
    ::usleep(100000);
    state = process_state(reader);
  }
  const double waited = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_TRUE(state == 0 || state == 'Z') << "the reader still runs after " << waited << " s (state " << state << ")";
  EXPECT_LT(waited, 30.0);
  if (state != 0 && state != 'Z') ::kill(reader, SIGKILL);  // not left spinning when this fails
}

// The reader process's pid: the one child of this test process that appeared since `before`.
std::vector<int> children() {
  std::vector<int> out;
  for (const auto& task : fs::directory_iterator("/proc/self/task")) {
    std::ifstream f(task.path() / "children");
    for (int pid; f >> pid;) out.push_back(pid);
  }
  return out;
}

int new_child(const std::vector<int>& before) {
  for (int pid : children()) {
    if (std::find(before.begin(), before.end(), pid) == before.end()) return pid;
  }
  return -1;
}

// The mechanism itself, independent of which files crash HDF5: the reader killed by a signal, or
// stopped, between two reads of an intact file.
TEST_F(HostileImport, AReaderThatCrashesOrHangsBetweenReadsIsNamed) {
  REAL_FILE(real, "met-era5-cocip1.nc");
  const std::string p = copy_of(real, "era5.nc");
  {
    const std::vector<int> before = children();
    importers::NcFile f(p);
    const int reader = new_child(before);
    ASSERT_GT(reader, 0) << "a NetCDF-4 file is read in a child process";
    const importers::NcVar& lat = f.var("latitude");
    EXPECT_FALSE(f.read(lat).empty());
    ASSERT_EQ(::kill(reader, SIGSEGV), 0);
    try {
      (void)f.read(lat);
      ADD_FAILURE() << "read after the reader died";
    } catch (const importers::ImportError& e) {
      EXPECT_NE(std::string(e.what()).find(p + ": the NetCDF-4/HDF5 library crashed (Segmentation fault) while reading variable 'latitude'"),
                std::string::npos)
          << e.what();
    }
    // Every later read says so too, without netCDF in this process.
    EXPECT_THROW((void)f.read(lat), importers::ImportError);
  }
  {
    ::setenv("CLOUDVIEWER_READ_TIMEOUT_S", "1", 1);
    const std::vector<int> before = children();
    importers::NcFile f(p);
    const int reader = new_child(before);
    ASSERT_GT(reader, 0);
    ASSERT_EQ(::kill(reader, SIGSTOP), 0);
    const auto t0 = std::chrono::steady_clock::now();
    try {
      (void)f.read(f.var("longitude"));
      ADD_FAILURE() << "read from a stopped reader";
    } catch (const importers::ImportError& e) {
      EXPECT_NE(std::string(e.what()).find(p + ": the NetCDF-4/HDF5 library did not answer within 1 s while reading variable 'longitude'"),
                std::string::npos)
          << e.what();
    }
    ::unsetenv("CLOUDVIEWER_READ_TIMEOUT_S");
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 30.0);
    EXPECT_EQ(::kill(reader, 0), -1) << "the hung reader was killed and reaped";
  }
}

// A classic file is read in this process (its header is checked first); a NetCDF-4 one reads the
// same values through the reader as netCDF gives here.
TEST_F(HostileImport, TheReaderProcessGivesNetcdfsOwnValues) {
  REAL_FILE(real, "met-era5-cocip1.nc");
  importers::NcFile f(real);
  int id = -1;
  ASSERT_EQ(nc_open(real.c_str(), NC_NOWRITE, &id), NC_NOERR);
  for (const char* name : {"latitude", "longitude", "specific_cloud_ice_water_content", "fraction_of_cloud_cover", "time"}) {
    const importers::NcVar* v = f.find(name);
    ASSERT_NE(v, nullptr) << name;
    int vid = -1;
    ASSERT_EQ(nc_inq_varid(id, name, &vid), NC_NOERR);
    std::vector<double> direct(f.size(*v));
    ASSERT_EQ(nc_get_var_double(id, vid, direct.data()), NC_NOERR);
    importers::UnpackInfo info;
    const std::vector<double> got = f.read(*v, {}, {}, &info);
    ASSERT_EQ(got.size(), direct.size()) << name;
    for (std::size_t i = 0; i < got.size(); ++i) {
      if (std::isnan(got[i])) continue;  // a missing value
      ASSERT_EQ(got[i], direct[i] * info.scale + info.offset) << name << " at " << i;
    }
  }
  nc_close(id);
  // A classic file: no reader process.
  const std::string classic = (dir_ / "classic.nc").string();
  {
    int nc, x, v;
    ASSERT_EQ(nc_create(classic.c_str(), NC_CLOBBER | NC_64BIT_DATA, &nc), NC_NOERR);
    ASSERT_EQ(nc_def_dim(nc, "x", 3, &x), NC_NOERR);
    ASSERT_EQ(nc_def_var(nc, "v", NC_DOUBLE, 1, &x, &v), NC_NOERR);
    ASSERT_EQ(nc_enddef(nc), NC_NOERR);
    const double vals[3] = {1.5, 2.5, 3.5};
    ASSERT_EQ(nc_put_var_double(nc, v, vals), NC_NOERR);
    ASSERT_EQ(nc_close(nc), NC_NOERR);
  }
  const std::vector<int> before = children();
  importers::NcFile c(classic);
  EXPECT_EQ(new_child(before), -1) << "a classic file is read in this process";
  EXPECT_EQ(c.read(c.var("v")), (std::vector<double>{1.5, 2.5, 3.5}));
}

}  // namespace

namespace {
using cv::test::NcBuilder;

// int16 variables of classic files are read straight to float (NcFile::read_float_into's short
// path, one pass with AVX or SSE2); every value, fill and range rule must come out as the general path
// (netCDF's doubles, unpacked in double) rounded to float, and the missing count the same.
TEST(NcShortReads, UnpackToTheSameFloatsAsTheDoublePath) {
  // The process's scratch folder: removed when the process ends, a failed assertion included.
  const fs::path dir = fs::path(cv::test_support::scratch_dir()) / "short_reads";
  fs::create_directories(dir);
  // Every int16 value once, in a 2 x 3 x 127 x 86 array (not a multiple of the SIMD width per row).
  const std::size_t nt = 2, nz = 3, ny = 127, nx = 86, n = nt * nz * ny * nx;
  std::vector<short> raw(n);
  for (std::size_t i = 0; i < n; ++i) raw[i] = static_cast<short>(static_cast<int>(i % 65536) - 32768);
  struct Case {
    const char* name;
    int mode;
    bool fill, missing, range, pack;
  };
  const Case cases[] = {
      {"fill_packed", NC_CLOBBER | NC_64BIT_OFFSET, true, false, false, true},
      {"fill_missing_range", NC_CLOBBER | NC_64BIT_OFFSET, true, true, true, true},
      {"default_fill_unpacked", NC_CLOBBER | NC_64BIT_OFFSET, false, false, false, false},
      {"netcdf4_reader_process", NC_CLOBBER | NC_NETCDF4, true, true, false, true},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const std::string p = (dir / (std::string(c.name) + ".nc")).string();
    {
      NcBuilder b(p, c.mode);
      const int t = b.dim("time", nt), z = b.dim("level", nz), y = b.dim("lat", ny), x = b.dim("lon", nx);
      const int v = b.var("q", NC_SHORT, {t, z, y, x});
      if (c.fill) b.number(v, "_FillValue", NC_SHORT, {-32767});
      if (c.missing) b.number(v, "missing_value", NC_SHORT, {12345});
      if (c.range) b.number(v, "valid_range", NC_SHORT, {-30000, 30000});
      if (c.pack) {
        b.number(v, "scale_factor", NC_DOUBLE, {1.52597204419215e-08});
        b.number(v, "add_offset", NC_DOUBLE, {0.0005});
      }
      b.put_short(v, raw);
      b.close();
    }
    importers::NcFile f(p);
    const importers::NcVar& v = f.var("q");
    // The whole variable, and a hyperslab that starts inside it.
    for (const auto& [start, count] :
         std::vector<std::pair<std::vector<std::size_t>, std::vector<std::size_t>>>{{{0, 0, 0, 0}, {nt, nz, ny, nx}},
                                                                                     {{1, 1, 3, 5}, {1, 2, 101, 77}}}) {
      importers::UnpackInfo as_double_info, as_float_info;
      std::vector<double> d;
      f.read_into(d, v, start, count, &as_double_info);
      std::vector<float> fl;
      f.read_float_into(fl, v, start, count, &as_float_info);
      ASSERT_EQ(fl.size(), d.size());
      std::size_t nan = 0;
      for (std::size_t i = 0; i < d.size(); ++i) {
        if (std::isnan(d[i])) {
          ++nan;
          ASSERT_TRUE(std::isnan(fl[i])) << "at " << i;
        } else {
          ASSERT_EQ(fl[i], static_cast<float>(d[i])) << "at " << i;
        }
      }
      if (start[0] == 0) {
        // Against CF's rules directly: markers and the valid range in the packed domain, then
        // x * scale + offset.
        EXPECT_GT(nan, 0u);  // the whole variable holds the fill value
        const double scale = c.pack ? 1.52597204419215e-08 : 1.0, offset = c.pack ? 0.0005 : 0.0;
        for (std::size_t i = 0; i < n; ++i) {
          const int r = raw[i];
          const bool missing = r == -32767 || (c.missing && r == 12345) || (c.range && (r < -30000 || r > 30000));
          if (missing) {
            ASSERT_TRUE(std::isnan(fl[i])) << "raw " << r;
            ASSERT_TRUE(std::isnan(d[i])) << "raw " << r;
          } else {
            ASSERT_EQ(fl[i], static_cast<float>(r * scale + offset)) << "raw " << r;
            ASSERT_EQ(d[i], r * scale + offset) << "raw " << r;  // the double read's own int16 path too
          }
        }
      }
      // any_at_least (the importer's search for the levels with cloud) answers as a scan of
      // these floats would, around the largest valid value (values past the valid range and the
      // markers unpack larger but are missing) and elsewhere.
      float lo = INFINITY, hi = -INFINITY;
      for (float x : fl) {
        if (!std::isnan(x)) lo = std::min(lo, x), hi = std::max(hi, x);
      }
      ASSERT_LT(lo, hi);
      for (double threshold : {static_cast<double>(lo), static_cast<double>(hi), std::nextafter(static_cast<double>(hi), INFINITY),
                               static_cast<double>(std::nextafter(hi, INFINITY)), 0.5 * (static_cast<double>(lo) + hi),
                               static_cast<double>(INFINITY), -static_cast<double>(INFINITY)}) {
        bool want = false;
        for (float x : fl) want = want || x >= threshold;
        EXPECT_EQ(f.any_at_least(v, start, count, threshold), want) << "threshold " << threshold;
      }
      EXPECT_EQ(as_float_info.missing, as_double_info.missing);
      EXPECT_EQ(as_float_info.missing, nan);
      EXPECT_EQ(as_float_info.packed, as_double_info.packed);
      EXPECT_EQ(as_float_info.scale, as_double_info.scale);
      EXPECT_EQ(as_float_info.offset, as_double_info.offset);
    }
  }
}

}  // namespace
