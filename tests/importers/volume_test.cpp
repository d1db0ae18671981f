// CloudVolume: derived maps (maximum-random overlap), the lazy cache, and the writers.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <cstring>
#include <fstream>
#include <sstream>

#include "support/nc_builder.hpp"
#include "volume/import_report.hpp"
#include "volume/cloud_volume.hpp"
#include "volume/volume_io.hpp"

namespace {
using namespace cv::core;

VolumeGrid column_grid(int nz) {
  VolumeGrid g;
  g.lon_deg = {0.0, 1.0, 1};
  g.lat_deg = {0.0, 1.0, 1};
  g.alt_m = {0.0, 1000.0, nz};
  return g;
}

TimeStepData column(const VolumeGrid& g, const std::vector<float>& cf, float ext) {
  TimeStepData d;
  d[Field::CloudFraction] = cf;
  d[Field::ExtinctionLiquid].assign(g.points(), ext);
  return d;
}

// The report's range over an array (vectorised on x86-64: SSE2, and sixteen floats a step with
// AVX) equals value-by-value adding, for floats and doubles with NaN and infinities among them, at
// every length around the vector widths and the block size, and keeps the extremes wherever they
// fall.
TEST(ValueStats, AddAllEqualsAddingEachValue) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-5.0, 5.0);
  const double special[] = {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(),
                            -std::numeric_limits<double>::infinity(), 1e300, -1e300};
  for (std::size_t n : {std::size_t(0), std::size_t(1), std::size_t(3), std::size_t(4), std::size_t(5), std::size_t(7),
                        std::size_t(15), std::size_t(16), std::size_t(17), std::size_t(33), std::size_t(64), std::size_t(1001),
                        (std::size_t(1) << 24) + 5}) {
    std::vector<double> d(n);
    for (auto& x : d) x = u(rng);
    for (std::size_t k = 0; k < n; k += 97) d[k] = special[(k / 97) % 5];
    if (n > 2) d[n - 1] = -7.5, d[n / 2] = 9.25;  // the extremes in the tail and the middle
    std::vector<float> f(d.begin(), d.end());
    ValueStats want_d, want_f, got_d, got_f;
    for (double x : d) want_d.add(x);
    for (float x : f) want_f.add(x);
    got_d.add_all(d.data(), d.size());
    got_f.add_all(f.data(), f.size());
    for (const auto& [got, want] : {std::pair{got_d, want_d}, std::pair{got_f, want_f}}) {
      EXPECT_EQ(got.count, want.count) << n;
      EXPECT_EQ(got.missing, want.missing) << n;
      EXPECT_EQ(got.min, want.min) << n;
      EXPECT_EQ(got.max, want.max) << n;
    }
  }
  // Only values that are not finite: counted as missing, the range left empty.
  const float bad[] = {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
                       -std::numeric_limits<float>::infinity(), std::numeric_limits<float>::quiet_NaN(),
                       std::numeric_limits<float>::infinity()};
  ValueStats none;
  none.add_all(bad, 5);
  EXPECT_EQ(none.count, 0u);
  EXPECT_EQ(none.missing, 5u);
  EXPECT_TRUE(none.empty());
}

// The maps of a row are worked out four columns at a time where the processor has AVX, the rest
// column by column: every map equals walking each column alone from the top by the maps'
// definition, to the bit, for rows of every width around the vector's, with missing values,
// absent fields, fractions at and past the thresholds, 0 and 1, outside 0..1 and infinite values,
// and columns whose ground puts a level in each band.
TEST(Maps, EveryColumnAsIfWalkedAlone) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const MapOptions o;
  for (const int nx : {1, 3, 4, 5, 8, 11}) {
    for (const int absent : {-1, 0, 1, 2}) {  // which of cf, liquid, ice is left out (-1: none)
      SCOPED_TRACE("nx " + std::to_string(nx) + ", absent " + std::to_string(absent));
      VolumeGrid g;
      g.lon_deg = {0.0, 1.0, nx};
      g.lat_deg = {0.0, 1.0, 3};
      g.alt_m = {0.0, 500.0, 20};  // to 9.5 km: every band
      TimeStepData d;
      const float nan = std::numeric_limits<float>::quiet_NaN();
      auto value = [&](double scale) -> float {
        const double r = u(rng);
        if (r < 0.08) return nan;
        if (r < 0.35) return 0.0f;
        if (r < 0.40) return static_cast<float>(scale);
        return static_cast<float>(scale * u(rng) * u(rng));
      };
      const Field fields[3] = {Field::CloudFraction, Field::ExtinctionLiquid, Field::ExtinctionIce};
      const double scales[3] = {1.0, 4e-3, 2e-4};
      for (int f = 0; f < 3; ++f) {
        if (f == absent) continue;
        auto& v = d[fields[f]];
        v.resize(g.points());
        for (auto& x : v) x = value(scales[f]);
        // Past the fields' ranges (fractions outside 0..1 are clamped as they are added) and infinite.
        for (std::size_t p = 9; p < v.size(); p += 23) v[p] = static_cast<float>(1.5 * scales[f]);
        for (std::size_t p = 10; p < v.size(); p += 29) v[p] = static_cast<float>(-0.5 * scales[f]);
        for (std::size_t p = 2; p < v.size(); p += 31) v[p] = std::numeric_limits<float>::infinity();
        if (f == 0) {  // at the thresholds, past them, and just short
          for (std::size_t p = 0; p < v.size(); p += 13) v[p] = o.min_cloud_fraction;
          for (std::size_t p = 5; p < v.size(); p += 17) v[p] = std::nextafter(o.min_cloud_fraction, 0.0f);
          for (std::size_t p = 7; p < v.size(); p += 19) v[p] = 1.0f;
        } else {
          for (std::size_t p = 3; p < v.size(); p += 11) v[p] = o.min_extinction_per_m;
        }
      }
      d.ground_m.resize(g.columns());
      for (auto& x : d.ground_m) x = u(rng) < 0.2 ? nan : static_cast<float>(4500.0 * u(rng));
      derive_maps(g, d, o);
      for (int j = 0; j < g.lat_deg.count; ++j) {
        for (int i = 0; i < nx; ++i) {
          const std::size_t col = g.column(i, j);
          MaxRandomOverlap all, low, mid, high;
          double tau = 0.0, base = NAN, top = NAN;
          bool any = false;
          const double ground = std::isfinite(d.ground_m[col]) ? d.ground_m[col] : 0.0;
          for (int k = g.alt_m.count - 1; k >= 0; --k) {
            const std::size_t p = g.index(i, j, k);
            auto at = [&](Field f) { return d[f].empty() ? static_cast<double>(nan) : static_cast<double>(d[f][p]); };
            const double cf = at(Field::CloudFraction), el = at(Field::ExtinctionLiquid), ei = at(Field::ExtinctionIce);
            if (std::isnan(cf) && std::isnan(el) && std::isnan(ei)) continue;
            any = true;
            const double ext = (std::isnan(el) ? 0.0 : el) + (std::isnan(ei) ? 0.0 : ei);
            const double frac = std::isnan(cf) ? (ext > 0.0 ? 1.0 : 0.0) : cf;
            const double above = g.alt_m.at(k) - ground;
            MaxRandomOverlap& band = above < o.low_top_m ? low : above < o.mid_top_m ? mid : high;
            if (frac >= o.min_cloud_fraction && ext >= o.min_extinction_per_m) {
              all.add(frac);
              band.add(frac);
              tau += frac * ext * g.alt_m.step;
              if (std::isnan(top)) top = g.alt_m.at(k);
              base = g.alt_m.at(k);
            } else {
              all.gap();
              band.gap();
            }
          }
          const auto& m = d.maps;
          auto same = [](float a, double b) { return std::isnan(b) ? std::isnan(a) : a == static_cast<float>(b); };
          const double none = NAN;
          EXPECT_TRUE(same(m.cloud_cover[col], any ? all.cover() : none)) << i << "," << j;
          EXPECT_TRUE(same(m.low_cover[col], any ? low.cover() : none)) << i << "," << j;
          EXPECT_TRUE(same(m.mid_cover[col], any ? mid.cover() : none)) << i << "," << j;
          EXPECT_TRUE(same(m.high_cover[col], any ? high.cover() : none)) << i << "," << j;
          EXPECT_TRUE(same(m.optical_depth[col], any ? tau : none)) << i << "," << j;
          EXPECT_TRUE(same(m.cloud_base_m[col], any ? base : none)) << i << "," << j;
          EXPECT_TRUE(same(m.cloud_top_m[col], any ? top : none)) << i << "," << j;
        }
      }
    }
  }
}

TEST(Maps, MaximumRandomOverlap) {
  const VolumeGrid g = column_grid(6);
  // Two adjacent layers of 0.5 overlap fully: cover 0.5.
  auto d = column(g, {0, 0.5f, 0.5f, 0, 0, 0}, 1e-3f);
  derive_maps(g, d);
  EXPECT_NEAR(d.maps.cloud_cover[0], 0.5, 1e-6);
  // Two layers of 0.5 separated by clear air overlap randomly: 1 - 0.5 * 0.5.
  d = column(g, {0.5f, 0, 0, 0.5f, 0, 0}, 1e-3f);
  derive_maps(g, d);
  EXPECT_NEAR(d.maps.cloud_cover[0], 0.75, 1e-6);
  EXPECT_EQ(d.maps.cloud_base_m[0], 0.0f);
  EXPECT_EQ(d.maps.cloud_top_m[0], 3000.0f);
  // Adjacent 0.3 then 0.6: max overlap gives 0.6.
  d = column(g, {0, 0, 0.3f, 0.6f, 0, 0}, 1e-3f);
  derive_maps(g, d);
  EXPECT_NEAR(d.maps.cloud_cover[0], 0.6, 1e-6);
  // Optical depth = sum of fraction x extinction x dz: (0.3 + 0.6) * 1e-3 * 1000.
  EXPECT_NEAR(d.maps.optical_depth[0], 0.9, 1e-6);
  // Low (< 2 km), mid (2-6 km), high: the layers at 2 and 3 km are mid.
  EXPECT_EQ(d.maps.low_cover[0], 0.0f);
  EXPECT_NEAR(d.maps.mid_cover[0], 0.6, 1e-6);
  // An overcast layer hides everything.
  d = column(g, {0.2f, 0, 1.0f, 0, 0.4f, 0}, 1e-3f);
  derive_maps(g, d);
  EXPECT_NEAR(d.maps.cloud_cover[0], 1.0, 1e-6);
  // No cloud at all: cover 0 and no base or top (NaN), never a crash.
  d = column(g, {0, 0, 0, 0, 0, 0}, 0.0f);
  derive_maps(g, d);
  EXPECT_EQ(d.maps.cloud_cover[0], 0.0f);
  EXPECT_TRUE(std::isnan(d.maps.cloud_base_m[0]));
}

TEST(Volume, CacheLoadsOnDemandAndEvictsTheLeastRecentlyUsed) {
  CloudVolume v;
  v.grid = column_grid(2);
  v.times.resize(4);
  int loads = 0;
  v.set_loader(
      [&](std::size_t t, ImportReport&, TimeStepData& d) {
        ++loads;
        d[Field::CloudFraction].assign(2, static_cast<float>(t) / 10.0f);
      },
      2);
  EXPECT_EQ(v.step(0)[Field::CloudFraction][0], 0.0f);
  EXPECT_EQ(v.step(1)[Field::CloudFraction][0], 0.1f);
  v.step(0);                                   // 0 is now the most recent
  EXPECT_EQ(v.step(2)[Field::CloudFraction][0], 0.2f);  // evicts 1
  EXPECT_TRUE(v.is_loaded(0));
  EXPECT_FALSE(v.is_loaded(1));
  EXPECT_EQ(loads, 3);
  EXPECT_EQ(v.loaded_steps(), 2u);
  EXPECT_THROW(v.step(4), std::out_of_range);
}

TEST(VolumeIo, CvvolHeaderAndPayloadAndVti) {
  const auto dir = cv::test::temp_dir("volume_io");
  CloudVolume v;
  v.grid = column_grid(3);
  v.times = {{0, "1970-01-01T00:00:00Z"}, {3600, "1970-01-01T01:00:00Z"}};
  v.has_field[static_cast<int>(Field::CloudFraction)] = true;
  v.set_loader([](std::size_t t, ImportReport&, TimeStepData& d) { d[Field::CloudFraction] = {0.1f * static_cast<float>(t), 0.5f, NAN}; });
  const std::string path = (dir / "v.cvvol").string();
  write_cvvol(path, v);
  std::ifstream in(path, std::ios::binary);
  std::string magic(8, '\0');
  in.read(magic.data(), 8);
  EXPECT_EQ(magic, "CVVOL02\n");
  std::uint64_t len = 0;
  in.read(reinterpret_cast<char*>(&len), 8);
  std::string header(len, '\0');
  in.read(header.data(), static_cast<std::streamsize>(len));
  EXPECT_NE(header.find("\"cloud_fraction\""), std::string::npos) << header;
  EXPECT_NE(header.find("1970-01-01T01:00:00Z"), std::string::npos);
  EXPECT_NE(header.find("\"version\": 2, \"zero_planes\": \"left out\""), std::string::npos) << header;
  EXPECT_EQ((16 + len) % 8, 0u) << "the data starts 8-byte aligned";
  // Step 0: the plane table (one field, 3 levels, padded to 8 bytes); the first level (0.1 x 0)
  // is zero and left out, the third (NaN only) is a mask of its one column.
  std::uint8_t table[8];
  in.read(reinterpret_cast<char*>(table), sizeof table);
  const std::uint8_t expected_table[8] = {0, 1, 2, 0, 0, 0, 0, 0};
  EXPECT_EQ(std::memcmp(table, expected_table, 8), 0);
  float first;
  in.read(reinterpret_cast<char*>(&first), sizeof first);
  EXPECT_EQ(first, 0.5f);
  std::uint8_t mask[8];
  in.read(reinterpret_cast<char*>(mask), sizeof mask);
  const std::uint8_t expected_mask[8] = {1, 0, 0, 0, 0, 0, 0, 0};
  EXPECT_EQ(std::memcmp(mask, expected_mask, 8), 0);
  // Per step: the table, the stored values (1, then 2), the mask and 7 one-column maps.
  in.seekg(0, std::ios::end);
  EXPECT_EQ(static_cast<std::uint64_t>(in.tellg()), 16 + len + 8 * 2 + (1 + 7 + 2 + 7) * sizeof(float) + 8 * 2);
  {
    CloudVolume r = read_cvvol(path);
    const std::vector<float>& back = r.step(0)[Field::CloudFraction];
    ASSERT_EQ(back.size(), 3u);
    EXPECT_EQ(back[0], 0.0f);
    EXPECT_FALSE(std::signbit(back[0]));
    EXPECT_EQ(back[1], 0.5f);
    EXPECT_TRUE(std::isnan(back[2]));
    // The second step, found after the first's smaller one.
    const std::vector<float>& second = r.step(1)[Field::CloudFraction];
    ASSERT_EQ(second.size(), 3u);
    EXPECT_EQ(second[0], 0.1f);
    EXPECT_EQ(second[1], 0.5f);
    EXPECT_TRUE(std::isnan(second[2]));
  }
  // No temporary file left behind.
  int files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir)) files += e.is_regular_file();
  EXPECT_EQ(files, 1);
  write_vti((dir / "v.vti").string(), v.grid, v.step(1), v.has_field);
  std::ifstream vti(dir / "v.vti", std::ios::binary);
  std::stringstream ss;
  ss << vti.rdbuf();
  EXPECT_NE(ss.str().find("WholeExtent=\"0 0 0 0 0 2\""), std::string::npos);
  EXPECT_NE(ss.str().find("Name=\"cloud_fraction\""), std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST(VolumeIo, CvvolRoundTrip) {
  const auto dir = cv::test::temp_dir("volume_roundtrip");
  CloudVolume v;
  v.grid.lon_deg = {170.0, 5.0, 3};
  v.grid.lat_deg = {40.0, 5.0, 2};
  v.grid.alt_m = {100.0, 500.0, 4};
  v.times = {{1705276800, "2024-01-15T00:00:00Z"}, {1705287600, "2024-01-15T03:00:00Z"}};
  v.liquid_r_eff_um = 7.5;  // the renderer's droplet diameter comes from it
  for (Field f : {Field::CloudFraction, Field::ExtinctionLiquid, Field::Temperature}) v.has_field[static_cast<int>(f)] = true;
  v.set_loader([&](std::size_t t, ImportReport&, TimeStepData& d) {
    for (Field f : {Field::CloudFraction, Field::ExtinctionLiquid, Field::Temperature}) {
      d[f].resize(v.grid.points());
      for (std::size_t p = 0; p < d[f].size(); ++p) d[f][p] = static_cast<float>(p * 0.01 + t + static_cast<int>(f));
    }
    d[Field::ExtinctionLiquid][3] = NAN;
  });
  const std::string path = (dir / "rt.cvvol").string();
  write_cvvol(path, v);
  CloudVolume r = read_cvvol(path);
  EXPECT_EQ(r.liquid_r_eff_um, 7.5);
  EXPECT_EQ(r.grid.lon_deg.start, 170.0);
  EXPECT_EQ(r.grid.alt_m.count, 4);
  ASSERT_EQ(r.times.size(), 2u);
  EXPECT_EQ(r.times[1].iso_utc, "2024-01-15T03:00:00Z");
  EXPECT_EQ(r.times[1].unix_s, 1705287600);
  EXPECT_TRUE(r.has_field[static_cast<int>(Field::Temperature)]);
  EXPECT_FALSE(r.has_field[static_cast<int>(Field::WindU)]);
  for (std::size_t t = 0; t < 2; ++t) {
    for (Field f : {Field::CloudFraction, Field::Temperature}) EXPECT_EQ(r.step(t)[f], v.step(t)[f]);
    EXPECT_TRUE(std::isnan(r.step(t)[Field::ExtinctionLiquid][3]));
    EXPECT_EQ(r.step(t).maps.cloud_cover, v.step(t).maps.cloud_cover);
  }
  // A cut file and a file of another kind are refused with the reason.
  std::filesystem::resize_file(path, std::filesystem::file_size(path) - 4);
  EXPECT_THROW(read_cvvol(path), std::runtime_error);
  std::ofstream(dir / "other.cvvol") << "not a volume";
  try {
    read_cvvol((dir / "other.cvvol").string());
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("not a cloud volume"), std::string::npos);
  }
  std::filesystem::remove_all(dir);
}

// Version 2 leaves out each (field, level) plane whose values are all zero: of either sign, or, in
// float16, small enough to round to a zero half float. The file is smaller by exactly those
// planes, reads back the values it would have held (a left-out plane as +0), and a step held as
// half floats (the import's way) is written with the same bytes as its float fields. A corrupt
// plane table is refused with its byte named.
TEST(VolumeIo, CvvolLeavesOutPlanesOfZeros) {
  const auto dir = cv::test::temp_dir("volume_zero_planes");
  const std::size_t cols = 6, levels = 6;
  const Field cf = Field::CloudFraction, liquid = Field::ExtinctionLiquid, temp = Field::Temperature;
  // The values, level by level.
  std::array<std::vector<float>, kFieldCount> values;
  for (Field f : {cf, liquid, temp}) values[static_cast<std::size_t>(f)].assign(cols * levels, 0.0f);
  const auto at = [&](Field f, std::size_t z, std::size_t c) -> float& { return values[static_cast<std::size_t>(f)][z * cols + c]; };
  const float tie = std::ldexp(1.0f, -25);  // half way to the least half float: rounds to zero (even)
  for (std::size_t c = 0; c < cols; ++c) {
    at(cf, 0, c) = 0.5f;
    at(cf, 2, c) = c % 2 ? -0.0f : 0.0f;  // zeros of both signs
    at(cf, 3, c) = 1e-9f;                 // zero as a half float only
    at(temp, 0, c) = at(temp, 1, c) = at(temp, 2, c) = at(temp, 3, c) = at(temp, 4, c) = at(temp, 5, c) = 250.0f;
  }
  at(cf, 4, 1) = tie;
  at(cf, 4, 4) = -tie;
  at(cf, 5, 2) = 3.0e-8f;  // just past the tie: the least half float
  for (std::size_t c = 0; c < cols; ++c) at(cf, 1, c) = NAN;  // no data at all: a mask of NaNs
  at(liquid, 1, 0) = NAN;       // NaN with infinity: stored
  at(liquid, 1, 1) = INFINITY;
  at(liquid, 2, 2) = NAN;       // NaN with zeros and a value that is zero only as a half float
  at(liquid, 2, 3) = -0.0f;
  at(liquid, 2, 4) = 1e-12f;
  at(liquid, 3, 5) = NAN;       // NaN with zeros: a mask
  at(liquid, 5, 0) = 1e-12f;    // 1e-9 /km: zero as a half float
  // 0: left out (zeros), 1: stored, 2: a mask of the NaNs among zeros.
  const std::vector<std::vector<std::uint8_t>> stored_f32 = {{1, 2, 0, 1, 1, 1}, {0, 1, 1, 2, 0, 1}, {1, 1, 1, 1, 1, 1}};
  const std::vector<std::vector<std::uint8_t>> stored_f16 = {{1, 2, 0, 0, 0, 1}, {0, 1, 2, 2, 0, 0}, {1, 1, 1, 1, 1, 1}};
  const auto volume = [&](bool as_halves) {
    CloudVolume v;
    v.grid.lon_deg = {0.0, 1.0, 3};
    v.grid.lat_deg = {0.0, 1.0, 2};
    v.grid.alt_m = {0.0, 1000.0, static_cast<int>(levels)};
    v.times = {{0, "1970-01-01T00:00:00Z"}};
    for (Field f : {cf, liquid, temp}) v.has_field[static_cast<std::size_t>(f)] = true;
    v.set_loader([&values, as_halves](std::size_t, ImportReport&, TimeStepData& d) {
      for (Field f : {Field::CloudFraction, Field::ExtinctionLiquid, Field::Temperature}) {
        const auto& x = values[static_cast<std::size_t>(f)];
        if (!as_halves) {
          d[f] = x;
          continue;
        }
        auto& h = d.halves[static_cast<std::size_t>(f)];
        h.resize(x.size());
        floats_to_halves(x.data(), half_field_scale(f), h.data(), x.size());
      }
    });
    return v;
  };
  const auto file_bytes = [](const std::string& p) {
    std::ifstream in(p, std::ios::binary);
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
  };
  // Writes `content` to `p` and opens it, loading its first step when `load`: the refusal's
  // message, or "(accepted)".
  const auto refusal = [](const std::string& p, const std::string& content, bool load) -> std::string {
    std::ofstream(p, std::ios::binary | std::ios::trunc) << content;
    try {
      CloudVolume c = read_cvvol(p);
      if (load) c.step(0);
    } catch (const VolumeFileError& e) {
      return e.what();
    }
    return "(accepted)";
  };
  for (const bool f16 : {false, true}) {
    SCOPED_TRACE(f16 ? "float16" : "float32");
    const std::string path = (dir / (f16 ? "h.cvvol" : "f.cvvol")).string();
    CloudVolume v = volume(false);
    write_cvvol(path, v, {}, f16 ? CvvolEncoding::Float16 : CvvolEncoding::Float32);
    const std::string bytes = file_bytes(path);
    std::uint64_t len = 0;
    std::memcpy(&len, bytes.data() + 8, 8);
    const auto& expected = f16 ? stored_f16 : stored_f32;
    // The table's fields come in the header's order, the fields' own (Field) order.
    std::vector<std::pair<Field, std::size_t>> order = {{cf, 0}, {liquid, 1}, {temp, 2}};
    std::sort(order.begin(), order.end());
    std::size_t planes = 0, masks = 0;
    for (std::size_t fi = 0; fi < 3; ++fi) {
      for (std::size_t z = 0; z < levels; ++z) {
        const int want = expected[order[fi].second][z];
        EXPECT_EQ(static_cast<int>(bytes[16 + len + fi * levels + z]), want) << field_name(order[fi].first) << " level " << z;
        planes += want == 1;
        masks += want == 2;
      }
    }
    // A mask of 6 values takes 8 bytes (a byte, padded to 8).
    EXPECT_EQ(bytes.size(), 16 + len + 24 + planes * cols * (f16 ? 2 : 4) + masks * 8 + 7 * cols * 4);
    CloudVolume r = read_cvvol(path);
    // What `info` prints of the storage.
    ASSERT_EQ(r.report.notes.size(), 1u);
    EXPECT_EQ(r.report.notes[0], std::string("storage: ") + (f16 ? "float16" : "float32") + " fields, " +
                                     std::to_string(planes) + " of 18 field planes stored (" + std::to_string(masks) +
                                     " of zeros and no data as masks, " + std::to_string(18 - planes - masks) +
                                     " holding only zeros left out)");
    for (Field f : {cf, liquid, temp}) {
      const auto& back = r.step(0)[f];
      const auto& x = values[static_cast<std::size_t>(f)];
      ASSERT_EQ(back.size(), x.size());
      for (std::size_t i = 0; i < x.size(); ++i) {
        const float k = half_field_scale(f);
        const float want = f16 ? half_to_float(float_to_half(x[i] * k)) * (1.0f / k) : x[i];
        if (std::isnan(want)) {
          EXPECT_TRUE(std::isnan(back[i])) << field_name(f) << " " << i;
        } else {
          EXPECT_EQ(back[i], want) << field_name(f) << " " << i;
        }
      }
    }
    EXPECT_FALSE(std::signbit(r.step(0)[cf][2 * cols + 1])) << "a left-out plane reads as +0";
    if (!f16) {
      // Version 1 (every plane stored, no table) is still read: the same file made dense by hand.
      std::string v1 = bytes.substr(0, 16 + len);
      v1.replace(0, 8, "CVVOL01\n");
      const std::string key = "\"version\": 2, \"zero_planes\": \"left out\",";
      const std::size_t k = v1.find(key);
      ASSERT_NE(k, std::string::npos);
      const std::string key1 = "\"version\": 1,";
      v1.replace(k, key.size(), key1 + std::string(key.size() - key1.size(), ' '));
      std::size_t from = 16 + len + 24;
      for (std::size_t fi = 0; fi < 3; ++fi) {
        for (std::size_t z = 0; z < levels; ++z) {
          if (bytes[16 + len + fi * levels + z] == 1) {
            v1 += bytes.substr(from, cols * 4);
            from += cols * 4;
          } else if (bytes[16 + len + fi * levels + z] == 2) {
            // The mask's bits, LSB first, to NaN or +0.
            for (std::size_t c = 0; c < cols; ++c) {
              const float x = (static_cast<unsigned char>(bytes[from + c / 8]) >> (c % 8)) & 1u ? std::numeric_limits<float>::quiet_NaN() : 0.0f;
              v1.append(reinterpret_cast<const char*>(&x), sizeof x);
            }
            from += 8;
          } else {
            v1 += std::string(cols * 4, '\0');
          }
        }
      }
      v1 += bytes.substr(from);
      const std::string path1 = (dir / "v1.cvvol").string();
      std::ofstream(path1, std::ios::binary | std::ios::trunc) << v1;
      CloudVolume r1 = read_cvvol(path1);
      ASSERT_EQ(r1.report.notes.size(), 1u);
      EXPECT_EQ(r1.report.notes[0], "storage: float32 fields, 18 of 18 field planes stored (version 1: every plane stored)");
      for (Field f : {cf, liquid, temp}) {
        const auto& a = r.step(0)[f];
        const auto& b = r1.step(0)[f];
        ASSERT_EQ(a.size(), b.size());
        EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(float)), 0) << field_name(f);
      }
      // A version this reader does not know is refused, not misread.
      std::string v3 = bytes;
      v3.replace(v3.find(key), 12, "\"version\": 3");
      EXPECT_EQ(refusal(path1, v3, false), path1 + ": header key 'version': found 3, expected 1 or 2 (written by a newer cloudviewer?)");
      // A version 1 header in a version 2 file (or the other way) is refused.
      std::string mixed = bytes;
      mixed.replace(mixed.find(key), 12, "\"version\": 1");
      EXPECT_EQ(refusal(path1, mixed, false), path1 + ": header key 'version': found 1, expected 2 in a file that starts CVVOL02");
    }
    if (f16) {
      // The import's way: the same step held as half floats gives the same file.
      const std::string path2 = (dir / "held.cvvol").string();
      CloudVolume held = volume(true);
      write_cvvol(path2, held, {}, CvvolEncoding::Float16);
      EXPECT_TRUE(file_bytes(path2) == bytes);
      // Held half floats written as float32: the planes as the halves have them.
      {
        const std::string path3 = (dir / "held32.cvvol").string();
        CloudVolume held32 = volume(true);
        write_cvvol(path3, held32, {}, CvvolEncoding::Float32);
        const std::string b32 = file_bytes(path3);
        std::uint64_t len32 = 0;
        std::memcpy(&len32, b32.data() + 8, 8);
        for (std::size_t fi = 0; fi < 3; ++fi) {
          for (std::size_t z = 0; z < levels; ++z) {
            EXPECT_EQ(static_cast<int>(b32[16 + len32 + fi * levels + z]), stored_f16[order[fi].second][z])
                << "float32 from halves, " << field_name(order[fi].first) << " level " << z;
          }
        }
      }
      // Corrupt plane tables: a byte other than 0, 1 or 2, padding that is not zero, a table that
      // claims a plane the file does not hold.
      const std::pair<std::size_t, std::string> cases[] = {
          {0, ": plane table of time step 0, byte 0: found 3, expected 0, 1 or 2"},
          {20, ": plane table of time step 0, byte 20: found 3, expected 0 (padding)"},
      };
      for (const auto& [byte, message] : cases) {
        std::string bad = bytes;
        bad[16 + len + byte] = 3;
        EXPECT_EQ(refusal(path2, bad, false), path2 + message);
      }
      // A mask with a bit set past the plane's values, found when the step is read.
      std::size_t offset = 16 + len + 24, mask_field = 0, mask_level = 0;
      bool found = false;
      for (std::size_t fi = 0; fi < 3 && !found; ++fi) {
        for (std::size_t z = 0; z < levels && !found; ++z) {
          const int code = bytes[16 + len + fi * levels + z];
          if (code == 2) {
            found = true;
            mask_field = fi;
            mask_level = z;
          } else {
            offset += code == 1 ? cols * 2 : 0;
          }
        }
      }
      ASSERT_TRUE(found);
      std::string stray = bytes;
      stray[offset] = static_cast<char>(stray[offset] | 0x80);
      const std::string mask_name = path2 + ": NaN mask of time step 0, field " + field_name(order[mask_field].first) + ", level " +
                                    std::to_string(mask_level);
      EXPECT_EQ(refusal(path2, stray, true), mask_name + ": bit 7 past its 6 values is set, expected 0");
      // A mask with no bit set (such a plane is left out instead).
      std::string empty_mask = bytes;
      empty_mask[offset] = 0;
      EXPECT_EQ(refusal(path2, empty_mask, true), mask_name + ": no bit set, expected at least one (a plane of zeros is left out)");
      std::string more = bytes;
      more[16 + len + 2] = 1;  // cloud fraction's level 2, left out
      const std::string claimed = refusal(path2, more, false);
      EXPECT_NE(claimed.find("holds " + std::to_string(bytes.size()) + " bytes, expected more"), std::string::npos) << claimed;
    }
  }
  std::filesystem::remove_all(dir);
}

TEST(VolumeIo, CvvolMasksLongerThanAByte) {
  // 70 columns: a mask of 9 bytes of bits, padded to 16; NaN at columns 0, 9, 64 and 69.
  const auto dir = cv::test::temp_dir("volume_masks");
  const std::size_t cols = 70;
  std::vector<float> cf(cols * 2, 0.0f);
  for (std::size_t c : {0, 9, 64, 69}) cf[c] = NAN;
  for (std::size_t c = 0; c < cols; ++c) cf[cols + c] = 0.5f;
  CloudVolume v;
  v.grid.lon_deg = {0.0, 1.0, static_cast<int>(cols)};
  v.grid.lat_deg = {0.0, 1.0, 1};
  v.grid.alt_m = {0.0, 1000.0, 2};
  v.times = {{0, "1970-01-01T00:00:00Z"}};
  v.has_field[static_cast<std::size_t>(Field::CloudFraction)] = true;
  v.set_loader([&cf](std::size_t, ImportReport&, TimeStepData& d) { d[Field::CloudFraction] = cf; });
  const std::string path = (dir / "m.cvvol").string();
  write_cvvol(path, v, {}, CvvolEncoding::Float16);
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string bytes = ss.str();
  std::uint64_t len = 0;
  std::memcpy(&len, bytes.data() + 8, 8);
  EXPECT_EQ(bytes[16 + len], 2);
  EXPECT_EQ(bytes[16 + len + 1], 1);
  std::array<std::uint8_t, 16> want{};
  want[0] = 0x01;  // column 0
  want[1] = 0x02;  // column 9
  want[8] = 0x21;  // columns 64 and 69
  EXPECT_EQ(std::memcmp(bytes.data() + 16 + len + 8, want.data(), want.size()), 0);
  EXPECT_EQ(bytes.size(), 16 + len + 8 + 16 + cols * 2 + 7 * cols * 4);
  CloudVolume r = read_cvvol(path);
  const auto& back = r.step(0)[Field::CloudFraction];
  ASSERT_EQ(back.size(), cols * 2);
  for (std::size_t i = 0; i < cols; ++i) {
    const bool nan = i == 0 || i == 9 || i == 64 || i == 69;
    EXPECT_EQ(std::isnan(back[i]), nan) << i;
    if (!nan) {
      EXPECT_EQ(back[i], 0.0f) << i;
    }
    EXPECT_NEAR(back[cols + i], 0.5f, 1e-3f) << i;
  }
  std::filesystem::remove_all(dir);
}

TEST(VolumeIo, AnErrorWhileLoadingKeepsItsTypeAndMessageAndLeavesNoFile) {
  struct BadData : std::runtime_error {
    using std::runtime_error::runtime_error;
  };
  const auto dir = cv::test::temp_dir("volume_io_bad");
  CloudVolume v;
  v.grid = column_grid(1);
  v.times.resize(2);
  v.set_loader([](std::size_t t, ImportReport&, TimeStepData& d) {
    if (t == 1) throw BadData("f.nc: variable 'cc' has value 7, expected a fraction between 0 and 1");
    d[Field::CloudFraction] = {0.5f};
  });
  v.has_field[static_cast<int>(Field::CloudFraction)] = true;
  try {
    write_cvvol((dir / "v.cvvol").string(), v);
    FAIL();
  } catch (const BadData& e) {
    EXPECT_STREQ(e.what(), "f.nc: variable 'cc' has value 7, expected a fraction between 0 and 1");
  }
  EXPECT_TRUE(std::filesystem::is_empty(dir));
  std::filesystem::remove_all(dir);
}

TEST(VolumeIo, AFailedWriteLeavesNoFile) {
  const auto dir = cv::test::temp_dir("volume_io_fail");
  const std::string path = (dir / "out.bin").string();
  EXPECT_THROW(write_file_atomically(path, [](std::FILE*) { throw std::runtime_error("disk full"); }), std::runtime_error);
  EXPECT_FALSE(std::filesystem::exists(path));
  EXPECT_TRUE(std::filesystem::is_empty(dir));
  std::filesystem::remove_all(dir);
}

}  // namespace
