// The benchmark's resumable Monte Carlo references: a reference read back and extended equals one
// rendered in one go, bit for bit; a file of other settings, size or length is not taken.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include <unistd.h>

#include "bench/reference_cache.hpp"
#include "bench/standard_scenes.hpp"
#include "reference/raymarcher.hpp"

namespace {
using namespace cv::core;
using namespace cv::bench;
namespace fs = std::filesystem;

struct ReferenceCache : ::testing::Test {
  StandardScene scene = standard_scene("cumulus_field", 12, 7);
  GridMeanExtinction ext = grid_mean_extinction(scene.grid, scene.data);
  MonteCarloSettings mc;
  fs::path dir = fs::temp_directory_path() / ("cv_refcache_" + std::to_string(::getpid()));
  MonteCarloRenderer renderer{scene.grid, ext, scene.camera, scene.sun, scene.march, mc};
  std::string path = (dir / "ref.bin").string();
  std::uint64_t key = reference_key_hash("settings A");
  void SetUp() override { fs::create_directories(dir); }
  void TearDown() override { fs::remove_all(dir); }
  // A reference of spp samples per pixel, written to `path` under `key`.
  MonteCarloImage written(int spp) {
    MonteCarloImage img = renderer.start();
    renderer.add_samples(img, spp);
    write_reference_cache(path, key, img);
    return img;
  }
};

bool same_sums(const MonteCarloImage& a, const MonteCarloImage& b) {
  return a.spp == b.spp && a.sum == b.sum && a.sum_sq == b.sum_sq && a.lum_sum == b.lum_sum && a.lum_sq == b.lum_sq &&
         a.stats.paths == b.stats.paths && a.stats.scatterings == b.stats.scatterings &&
         a.stats.shadow_lookups == b.stats.shadow_lookups;
}

TEST_F(ReferenceCache, AReferenceExtendedFromItsCacheEqualsOneRenderedInOneGo) {
  const MonteCarloImage first = written(3);
  const MonteCarloRenderer& r = renderer;

  MonteCarloImage resumed;
  std::string why;
  ASSERT_TRUE(read_reference_cache(path, key, 12, 7, resumed, &why)) << why;
  EXPECT_TRUE(same_sums(resumed, first));
  r.add_samples(resumed, 5);

  MonteCarloImage whole = r.start();
  r.add_samples(whole, 8);
  EXPECT_TRUE(same_sums(resumed, whole));
  EXPECT_GT(whole.stats.scatterings, 0u);
}

TEST_F(ReferenceCache, AFileOfOtherSettingsSizeOrLengthIsNotTaken) {
  written(2);
  MonteCarloImage out;
  std::string why;
  EXPECT_FALSE(read_reference_cache(path, reference_key_hash("settings B"), 12, 7, out, &why));
  EXPECT_NE(why.find("key"), std::string::npos) << why;
  EXPECT_FALSE(read_reference_cache(path, key, 13, 7, out, &why));
  EXPECT_NE(why.find("12x7"), std::string::npos) << why;
  EXPECT_FALSE(read_reference_cache((dir / "missing.bin").string(), key, 12, 7, out, &why));
  // Cut short: the last bytes missing.
  const auto size = fs::file_size(path);
  fs::resize_file(path, size - 8);
  EXPECT_FALSE(read_reference_cache(path, key, 12, 7, out, &why));
  EXPECT_EQ(why, "cut short");
  // Trailing bytes.
  fs::resize_file(path, size);
  { std::ofstream(path, std::ios::app | std::ios::binary) << 'x'; }
  EXPECT_FALSE(read_reference_cache(path, key, 12, 7, out, &why));
  EXPECT_EQ(out.spp, 0u);  // nothing taken from a bad file
}

TEST_F(ReferenceCache, ExtendReferenceResumesFromItsFolderAndStopsAtTheError) {
  MarchSettings m = scene.march;
  std::FILE* log = std::tmpfile();
  ASSERT_NE(log, nullptr);
  const ExtendedReference a = extend_reference(dir.string(), "cumulus_field", scene, ext, m, mc, 3, 0.0, nullptr, log);
  EXPECT_EQ(a.cached_spp, 0u);
  EXPECT_EQ(a.img.spp, 3u);
  ASSERT_TRUE(fs::exists(a.path));
  EXPECT_NE(a.path.find("ref_cumulus_field_12x7_"), std::string::npos) << a.path;

  // The second call reads the three samples back and adds five: the image of eight in one go.
  const ExtendedReference b = extend_reference(dir.string(), "cumulus_field", scene, ext, m, mc, 8, 0.0, nullptr, log);
  EXPECT_EQ(b.cached_spp, 3u);
  EXPECT_EQ(b.path, a.path);
  MonteCarloImage whole = renderer.start();
  renderer.add_samples(whole, 8);
  EXPECT_TRUE(same_sums(b.img, whole));

  // Fewer samples than the file holds: nothing is rendered, the file's image is returned.
  const ExtendedReference c = extend_reference(dir.string(), "cumulus_field", scene, ext, m, mc, 4, 0.0, nullptr, log);
  EXPECT_EQ(c.img.spp, 8u);
  EXPECT_EQ(c.seconds, 0.0);

  // Other settings are another reference (another key, another file), rendered afresh.
  MarchSettings other = m;
  other.medium.droplet_diameter_um = 31.0;
  const ExtendedReference d = extend_reference(dir.string(), "cumulus_field", scene, ext, other, mc, 2, 0.0, nullptr, log);
  EXPECT_EQ(d.cached_spp, 0u);
  EXPECT_NE(d.path, a.path);

  // A target error already met stops once the 16 samples the check needs first are there (the
  // chunk in flight then ends), far short of the 1000 asked.
  const ExtendedReference e = extend_reference(dir.string(), "cumulus_field", scene, ext, m, mc, 1000, 1e3, nullptr, log);
  EXPECT_GE(e.img.spp, 16u);
  EXPECT_LT(e.img.spp, 64u);
  std::fclose(log);
}

}  // namespace
