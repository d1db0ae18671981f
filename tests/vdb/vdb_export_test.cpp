// OpenVDB export (issue 16): a synthetic volume across the date line written by cv_vdb, read back
// with OpenVDB, and every active voxel compared with the volume sampled at the voxel's position
// (found here from the grid's metadata and transform, through the geodesy, not the exporter's code).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>

#include <openvdb/openvdb.h>

#include "geo/geodesy.hpp"
#include "io/output_file.hpp"
#include "vdb/vdb_export.hpp"
#include "volume/time_interpolation.hpp"

namespace {
using namespace cv;

struct Synthetic {
  core::VolumeGrid g;
  core::TimeStepData step;
  std::array<bool, core::kFieldCount> has{};
  Synthetic() {
    g.lon_deg = {170.0, 1.0, 21};  // 170E .. 190E (170W): across the date line
    g.lat_deg = {30.0, 1.0, 11};
    g.alt_m = {0.0, 500.0, 21};
    const std::size_t n = g.points();
    step[core::Field::ExtinctionLiquid].resize(n);
    step[core::Field::ExtinctionIce].resize(n);
    step[core::Field::CloudFraction].resize(n);
    for (int k = 0; k < g.alt_m.count; ++k) {
      for (int j = 0; j < g.lat_deg.count; ++j) {
        for (int i = 0; i < g.lon_deg.count; ++i) {
          const std::size_t p = g.index(i, j, k);
          step[core::Field::ExtinctionLiquid][p] = static_cast<float>(1e-3 * (1.0 + 0.1 * i + 0.05 * j + 0.02 * k));
          step[core::Field::ExtinctionIce][p] = k >= 12 ? static_cast<float>(2e-4 * (1 + j)) : 0.0f;
          step[core::Field::CloudFraction][p] = static_cast<float>(0.3 + 0.02 * i + 0.01 * k);
        }
      }
    }
    // One column with no data: its cells stay inactive.
    for (int k = 0; k < g.alt_m.count; ++k) step[core::Field::ExtinctionLiquid][g.index(4, 4, k)] = std::numeric_limits<float>::quiet_NaN();
    has[static_cast<int>(core::Field::ExtinctionLiquid)] = has[static_cast<int>(core::Field::ExtinctionIce)] =
        has[static_cast<int>(core::Field::CloudFraction)] = true;
  }
  // The renderer's medium at a node: fraction x in-cloud extinction (liquid), no data as 0.
  double node(int f, int i, int j, int k) const {
    const std::size_t p = g.index(i, j, k);
    const double frac = step[core::Field::CloudFraction][p];
    if (f == 2) return frac;
    const double e = step[f == 0 ? core::Field::ExtinctionLiquid : core::Field::ExtinctionIce][p];
    return std::isnan(e) ? 0.0 : e * frac;
  }
  // Trilinear at lat/lon/alt, or NaN outside the grid.
  double at(int f, double lat, double lon, double alt) const {
    while (lon < 0.0) lon += 360.0;
    const double x = (lon - g.lon_deg.start) / g.lon_deg.step, y = (lat - g.lat_deg.start) / g.lat_deg.step,
                 z = (alt - g.alt_m.start) / g.alt_m.step;
    if (x < 0 || y < 0 || z < 0 || x > g.lon_deg.count - 1 || y > g.lat_deg.count - 1 || z > g.alt_m.count - 1) return NAN;
    const int i = std::min<int>(static_cast<int>(x), g.lon_deg.count - 2), j = std::min<int>(static_cast<int>(y), g.lat_deg.count - 2),
              k = std::min<int>(static_cast<int>(z), g.alt_m.count - 2);
    const double a = x - i, b = y - j, c = z - k;
    double v = 0.0;
    for (int dk = 0; dk < 2; ++dk)
      for (int dj = 0; dj < 2; ++dj)
        for (int di = 0; di < 2; ++di) v += (di ? a : 1 - a) * (dj ? b : 1 - b) * (dk ? c : 1 - c) * node(f, i + di, j + dj, k + dk);
    return v;
  }
};

TEST(VdbExport, ReadBackMatchesTheVolumeAtEveryActiveVoxel) {
  const Synthetic s;
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("cv_vdb_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "v_t000.vdb").string();
  core::OutputGroup group;
  const vdb::VdbSummary summary = vdb::write_vdb(group, path, s.g, s.step, s.has, "2024-01-15T03:00:00Z");
  EXPECT_FALSE(std::filesystem::exists(path)) << "the file appeared before the group was committed";
  group.commit();

  openvdb::initialize();
  openvdb::io::File file(path);
  file.open();
  const char* names[3] = {"extinction_liquid", "extinction_ice", "cloud_fraction"};
  for (int f = 0; f < 3; ++f) {
    SCOPED_TRACE(names[f]);
    const auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid(names[f]));
    ASSERT_TRUE(grid);
    EXPECT_EQ(grid->getGridClass(), openvdb::GRID_FOG_VOLUME);
    EXPECT_EQ(grid->metaValue<std::string>("valid_utc"), "2024-01-15T03:00:00Z");
    EXPECT_NE(grid->metaValue<std::string>("units").find(f == 2 ? "fraction" : "1/m"), std::string::npos);
    EXPECT_NE(grid->metaValue<std::string>("frame").find("x east, y north, z up"), std::string::npos);
    const double lat0 = grid->metaValue<double>("origin_lat_deg"), lon0 = grid->metaValue<double>("origin_lon_deg");
    EXPECT_DOUBLE_EQ(lat0, 35.0);
    EXPECT_DOUBLE_EQ(lon0, 180.0);
    const double r0 = grid->metaValue<double>("earth_radius_m");
    const glm::dvec3 origin = geo::sphere_to_ecef({lat0, lon0, 0.0}, r0);
    const geo::EnuFrame e = geo::sphere_enu(lat0, lon0);
    std::size_t active = 0;
    double worst = 0.0;
    for (auto it = grid->cbeginValueOn(); it; ++it) {
      const openvdb::Vec3d w = grid->transform().indexToWorld(it.getCoord());
      const geo::Geodetic p = geo::ecef_to_sphere(origin + w.x() * e.east + w.y() * e.north + w.z() * e.up, r0);
      const double want = s.at(f, p.lat_deg, p.lon_deg, p.alt_m);
      ASSERT_FALSE(std::isnan(want)) << "an active voxel outside the volume at " << p.lat_deg << ", " << p.lon_deg << ", " << p.alt_m;
      worst = std::max(worst, std::abs(*it - want) / want);
      ++active;
    }
    EXPECT_EQ(active, summary.active_voxels[f]);
    EXPECT_GT(active, 1000u);
    EXPECT_LT(worst, 1e-5) << "worst relative difference from the volume";  // float32 voxels
    // The volume's centre is in a voxel, with the volume's value there.
    const openvdb::Coord c = grid->transform().worldToIndexNodeCentered(openvdb::Vec3d(0.0, 0.0, 5000.0));
    EXPECT_TRUE(grid->tree().isValueOn(c) || f == 1) << "the centre's voxel is inactive";
  }
  file.close();
  std::filesystem::remove_all(dir);
}

// From the renderer's medium at an instant between two steps (record --vdb): the grid-mean
// extinction as core::interpolate_extinction blends it (linear, halfway), and no cloud_fraction
// grid, which the interpolation does not carry. Every active voxel holds the blend at its place.
TEST(VdbExport, AnInstantBetweenStepsWritesTheBlendedMedium) {
  const Synthetic a;
  Synthetic b;
  for (float& v : b.step[core::Field::ExtinctionLiquid]) v = std::isnan(v) ? v : 2.0f * v;  // the later step: twice the water
  const core::GridMeanExtinction ea = core::grid_mean_extinction(a.g, a.step), eb = core::grid_mean_extinction(b.g, b.step);
  const core::GridMeanExtinction mid =
      core::interpolate_extinction(a.g, ea, eb, {}, {}, 3600.0, 0.5, core::TimeInterpolation::Linear);
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("cv_vdb_mid_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "frame_00001.vdb").string();
  core::OutputGroup group;
  vdb::write_vdb(group, path, a.g, mid, nullptr, "2024-01-15T03:30:00Z");
  group.commit();
  openvdb::initialize();
  openvdb::io::File file(path);
  file.open();
  EXPECT_FALSE(file.hasGrid("cloud_fraction"));
  const auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid("extinction_liquid"));
  ASSERT_TRUE(grid);
  EXPECT_EQ(grid->metaValue<std::string>("valid_utc"), "2024-01-15T03:30:00Z");
  const double lat0 = grid->metaValue<double>("origin_lat_deg"), lon0 = grid->metaValue<double>("origin_lon_deg");
  const double r0 = grid->metaValue<double>("earth_radius_m");
  const glm::dvec3 origin = geo::sphere_to_ecef({lat0, lon0, 0.0}, r0);
  const geo::EnuFrame e = geo::sphere_enu(lat0, lon0);
  std::size_t active = 0;
  double worst = 0.0;
  for (auto it = grid->cbeginValueOn(); it; ++it) {
    const openvdb::Vec3d w = grid->transform().indexToWorld(it.getCoord());
    const geo::Geodetic p = geo::ecef_to_sphere(origin + w.x() * e.east + w.y() * e.north + w.z() * e.up, r0);
    const double want = 1.5 * a.at(0, p.lat_deg, p.lon_deg, p.alt_m);  // halfway between 1x and 2x
    ASSERT_FALSE(std::isnan(want));
    worst = std::max(worst, std::abs(*it - want) / want);
    ++active;
  }
  EXPECT_GT(active, 1000u);
  EXPECT_LT(worst, 1e-5);
  file.close();
  std::filesystem::remove_all(dir);
}

}  // namespace
