// Light between the two-stream's columns (core/kernel/ms_lateral): the 3-D diffusion against the
// independent columns' on the same finite volumes. A horizontally uniform slab keeps its columns'
// light away from the grid's edges, a narrow tower loses light through its sides with its
// horizontal flux pointing out of them, the light put in leaves through the boundaries, the
// longitudes wrap, the answer does not depend on the number of threads, and no input gives NaN.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "kernel/ms_lateral.hpp"
#include "kernel/ms_source.hpp"
#include "settings/march_settings.hpp"
#include "support/bubble_scene.hpp"

namespace cv::core {
namespace {

// A medium of transport coefficient kappa(i, j, k) (droplets' g = 0.86), lit by a beam travelling
// along dir (east, north, up) with the plane-parallel exp(-tau' / mu0) down each column.
LateralMedium medium_of(const VolumeGrid& grid, const std::function<double(int, int, int)>& kappa,
                        glm::dvec3 dir, double ground = 0.0) {
  const double g = 0.86;
  LateralMedium m;
  const std::size_t n = grid.points();
  m.kappa.assign(n, 0.0f);
  m.scaled.assign(n, 0.0f);
  m.gcoef.assign(n, 0.0f);
  m.beam.assign(n, 1.0f);
  m.beam_dir.assign(grid.columns(), glm::normalize(dir));
  m.ground.assign(grid.columns(), ground);
  const double mu0 = std::max(-glm::normalize(dir).z, 1e-3);
  for (int j = 0; j < grid.lat_deg.count; ++j)
    for (int i = 0; i < grid.lon_deg.count; ++i) {
      double tau = 0.0;
      for (int k = grid.alt_m.count - 1; k >= 0; --k) {
        const std::size_t a = grid.index(i, j, k);
        const double kap = kappa(i, j, k);
        const double sigma = kap / (1.0 - g);
        if (k + 1 < grid.alt_m.count)
          tau += 0.5 * (1.0 - g * g) * (sigma + double(m.kappa[a + grid.columns()]) / (1.0 - g)) *
                 grid.alt_m.step;
        m.beam[a] = static_cast<float>(std::exp(-tau / mu0));
        if (!(kap > 0.0)) continue;
        m.kappa[a] = static_cast<float>(kap);
        m.scaled[a] = static_cast<float>(sigma * (1.0 - g * g));
        m.gcoef[a] = static_cast<float>(g);
      }
    }
  return m;
}

VolumeGrid box(double step_deg, int n, int levels, double dz = 100.0) {
  VolumeGrid grid;
  grid.lon_deg = {-0.5 * step_deg * (n - 1), step_deg, n};
  grid.lat_deg = {-0.5 * step_deg * (n - 1), step_deg, n};
  grid.alt_m = {0.0, dz, levels};
  return grid;
}

// A uniform slab of optical depth about 20 (1 km deep) over a box 22 km across: far from the
// box's edges the columns keep their light and no horizontal flux arises; at the edges light
// leaves through the box's sides.
TEST(Lateral, AUniformSlabKeepsItsColumnsLightAwayFromTheEdges) {
  const VolumeGrid grid = box(0.005, 41, 21);
  const auto slab = [](int, int, int k) { return k >= 5 && k <= 15 ? 0.0028 : 0.0; };
  for (const glm::dvec3 dir : {glm::dvec3(0.0, 0.0, -1.0), glm::dvec3(0.0, 0.5, -0.866)}) {
    const LateralRatio r = lateral_ratio(grid, medium_of(grid, slab, dir));
    EXPECT_LT(r.residual, 1e-6);
    for (int k = 5; k <= 15; ++k) {
      const std::size_t centre = grid.index(20, 20, k);
      EXPECT_NEAR(r.ratio[centre], 1.0, 2e-3) << "level " << k;
      EXPECT_NEAR(r.east[centre], 0.0, 2e-3) << "level " << k;
      EXPECT_NEAR(r.north[centre], 0.0, 2e-3) << "level " << k;
      EXPECT_LT(r.ratio[grid.index(0, 20, k)], 0.97) << "the west edge, level " << k;
      EXPECT_GT(r.east[grid.index(40, 20, k)], 0.01) << "the east edge's light flows east, level " << k;
      EXPECT_LT(r.east[grid.index(0, 20, k)], -0.01) << "the west edge's light flows west, level " << k;
    }
    // The clear fringe of a cloudy column takes its nearest cloudy node's values.
    EXPECT_EQ(r.ratio[grid.index(0, 20, 18)], r.ratio[grid.index(0, 20, 15)]);
    EXPECT_EQ(r.ratio[grid.index(0, 20, 2)], r.ratio[grid.index(0, 20, 5)]);
  }
}

// A tower 3 x 3 columns wide (1.7 km) and 3 km tall: its columns alone would keep the light that
// enters their tops; in 3-D it leaves through the sides, symmetrically under an overhead sun.
TEST(Lateral, ANarrowTowerLosesLightThroughItsSidesAndItsFluxPointsOutOfThem) {
  const VolumeGrid grid = box(0.005, 21, 41);
  const auto tower = [](int i, int j, int k) {
    return std::abs(i - 10) <= 1 && std::abs(j - 10) <= 1 && k >= 5 && k <= 35 ? 0.004 : 0.0;
  };
  const LateralRatio r = lateral_ratio(grid, medium_of(grid, tower, {0.0, 0.0, -1.0}));
  EXPECT_LT(r.residual, 1e-6);
  double sum = 0.0;
  int count = 0;
  for (int k = 5; k <= 35; ++k)
    for (int j = 9; j <= 11; ++j)
      for (int i = 9; i <= 11; ++i) sum += r.ratio[grid.index(i, j, k)], ++count;
  EXPECT_LT(sum / count, 0.8) << "the tower keeps what its columns alone would keep";
  EXPECT_GT(sum / count, 0.05);
  for (int k = 10; k <= 30; k += 5) {
    const float e = r.east[grid.index(11, 10, k)], w = r.east[grid.index(9, 10, k)];
    const float n = r.north[grid.index(10, 11, k)], s = r.north[grid.index(10, 9, k)];
    EXPECT_GT(e, 0.05) << k;
    EXPECT_NEAR(w, -e, 1e-3 * e) << k;
    EXPECT_NEAR(n, e, 0.02 * e) << k;  // north and east differ only by the sphere's metric
    EXPECT_NEAR(s, -n, 1e-3 * n) << k;
    EXPECT_NEAR(r.east[grid.index(10, 10, k)], 0.0, 1e-3 * e) << "the axis, level " << k;
  }
  // The sunlit ground around the tower (albedo 0.3 under an overhead sun) lights its sides: more
  // light in the side columns, and less flowing out of them.
  LateralMedium lit = medium_of(grid, tower, {0.0, 0.0, -1.0}, 0.3);
  const LateralRatio r_dark = lateral_ratio(grid, lit);
  lit.ground_light.assign(grid.columns(), 0.3);
  const LateralRatio r_lit = lateral_ratio(grid, lit);
  for (int k = 10; k <= 30; k += 5) {
    EXPECT_GT(r_lit.ratio[grid.index(11, 10, k)], r_dark.ratio[grid.index(11, 10, k)] * 1.02) << k;
    EXPECT_LT(r_lit.east[grid.index(11, 10, k)], r_dark.east[grid.index(11, 10, k)]) << k;
  }
}

// The 3-D solution's balance: all the light the beam puts into the diffuse field (and the ground
// returns) leaves through the cloud's boundaries; the inner faces' flows cancel in pairs.
TEST(Lateral, TheLightPutInLeavesThroughTheBoundaries) {
  for (const double lat : {0.0, 70.0}) {  // the sphere's metric: east-west spacing by cos(latitude)
    VolumeGrid grid = box(0.005, 21, 31);
    grid.lat_deg.start += lat;
    const auto blob = [](int i, int j, int k) {
      const double r2 =
          ((i - 9.0) * (i - 9.0) + (j - 11.0) * (j - 11.0)) / 16.0 + (k - 14.0) * (k - 14.0) / 64.0;
      return r2 < 1.0 ? 0.006 * (1.0 - r2) : 0.0;
    };
    for (const double ground : {0.0, 0.3, 1.0}) {
      LateralMedium m = medium_of(grid, blob, {0.3, -0.4, -0.866}, ground);
      m.ground_light.assign(grid.columns(), 0.866 * ground);  // the sunlit ground beside it lights its sides
      const LateralRatio r = lateral_ratio(grid, m);
      EXPECT_LT(r.residual, 1e-6);
      ASSERT_GT(r.put_in, 0.0);
      EXPECT_NEAR(r.let_out / r.put_in, 1.0, 1e-5) << "ground " << ground << ", latitude " << lat;
    }
  }
}

// A thin forward-scattering cloud (optical depth about 3 through its middle, the droplets' g) under
// an overhead and an oblique sun: both solutions stay positive, so no node's ratio falls to 0,
// reaches the clamp or is left at 1 for want of column light.
TEST(Lateral, AThinCloudKeepsPositiveLight) {
  const VolumeGrid grid = box(0.005, 21, 31);
  const auto blob = [](int i, int j, int k) {
    const double r2 =
        ((i - 9.0) * (i - 9.0) + (j - 11.0) * (j - 11.0)) / 16.0 + (k - 14.0) * (k - 14.0) / 64.0;
    return r2 < 1.0 ? 0.0006 * (1.0 - r2) : 0.0;
  };
  for (const glm::dvec3 dir : {glm::dvec3(0.0, 0.0, -1.0), glm::dvec3(0.85, 0.0, -0.5)}) {
    const LateralRatio r = lateral_ratio(grid, medium_of(grid, blob, dir));
    int cloudy = 0;
    for (int k = 0; k < grid.alt_m.count; ++k)
      for (int j = 0; j < grid.lat_deg.count; ++j)
        for (int i = 0; i < grid.lon_deg.count; ++i) {
          if (!(blob(i, j, k) > 0.0)) continue;
          ++cloudy;
          const std::size_t a = grid.index(i, j, k);
          ASSERT_GT(r.ratio[a], 0.0f) << i << " " << j << " " << k << " sun " << dir.x;
          ASSERT_LT(r.ratio[a], float(kLateralRatioMax)) << i << " " << j << " " << k << " sun " << dir.x;
          ASSERT_NE(r.ratio[a], 1.0f)
              << "no column light at " << i << " " << j << " " << k << " sun " << dir.x;
        }
    EXPECT_GT(cloudy, 300);
  }
}

// Longitudes wrap on a global grid: a blob across the seam gives the same field as the blob in
// the middle, shifted.
TEST(Lateral, TheLongitudesWrapOnAGlobalGrid) {
  VolumeGrid grid;
  grid.lon_deg = {0.0, 10.0, 36};
  grid.lat_deg = {-10.0, 10.0, 3};
  grid.alt_m = {0.0, 500.0, 11};
  grid.earth_radius_m = 60000.0;  // a small planet, so a 10-degree cell is about 10 km
  auto blob_at = [](int centre) {
    return [centre](int i, int j, int k) {
      const int d = std::min((i - centre + 36) % 36, (centre - i + 36) % 36);
      return d <= 2 && j == 1 && k >= 2 && k <= 8 ? 0.001 * (3 - d) : 0.0;
    };
  };
  const LateralRatio seam = lateral_ratio(grid, medium_of(grid, blob_at(0), {0.0, 0.0, -1.0}));
  const LateralRatio middle = lateral_ratio(grid, medium_of(grid, blob_at(18), {0.0, 0.0, -1.0}));
  for (int k = 2; k <= 8; ++k) {
    for (int d = -2; d <= 2; ++d) {
      const std::size_t a = grid.index((d + 36) % 36, 1, k), b = grid.index(18 + d, 1, k);
      EXPECT_NEAR(seam.ratio[a], middle.ratio[b], 1e-5) << d << " " << k;
      EXPECT_NEAR(seam.east[a], middle.east[b], 1e-5) << d << " " << k;
    }
    EXPECT_LT(seam.ratio[grid.index(0, 1, k)], 0.999) << "light leaves the blob across the seam";
  }
}

// The sums are taken in a fixed order: one thread and three give the same bits (about 2 300
// cloudy columns: the sums run over several blocks).
TEST(Lateral, TheAnswerDoesNotDependOnTheNumberOfThreads) {
  const VolumeGrid grid = box(0.005, 61, 31);
  const auto blob = [](int i, int j, int k) {
    const double r2 =
        ((i - 30.0) * (i - 30.0) + (j - 29.0) * (j - 29.0)) / 729.0 + (k - 15.0) * (k - 15.0) / 81.0;
    return r2 < 1.0 ? 0.005 * (1.0 - r2) : 0.0;
  };
  const LateralMedium m = medium_of(grid, blob, {0.5, 0.0, -0.866});
  const char* before = std::getenv("CLOUDVIEWER_THREADS");
  const std::string saved = before ? before : "";
  setenv("CLOUDVIEWER_THREADS", "1", 1);
  const LateralRatio one = lateral_ratio(grid, m);
  setenv("CLOUDVIEWER_THREADS", "3", 1);
  const LateralRatio three = lateral_ratio(grid, m);
  if (before) {
    setenv("CLOUDVIEWER_THREADS", saved.c_str(), 1);
  } else {
    unsetenv("CLOUDVIEWER_THREADS");
  }
  EXPECT_EQ(one.iterations, three.iterations);
  EXPECT_EQ(one.ratio, three.ratio);
  EXPECT_EQ(one.east, three.east);
  EXPECT_EQ(one.north, three.north);
}

// Optical depths from 1e-9 to 1e7 per metre, NaN and infinite inputs, one level, one column: every
// output finite, the ratio within its bounds.
TEST(Lateral, ExtremeInputsGiveFiniteLight) {
  const double inf = std::numeric_limits<double>::infinity(), nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<VolumeGrid> grids = {box(0.005, 9, 9), box(0.005, 1, 9), box(0.005, 9, 1)};
  for (const VolumeGrid& grid : grids) {
    for (const double value : {1e-9, 1e-3, 1e7, nan, inf}) {
      LateralMedium m = medium_of(
          grid, [&](int i, int, int k) { return (i + k) % 3 == 0 ? value : 0.004; }, {0.2, 0.1, -0.3}, 0.9);
      // Bad beams, directions, forward shares and grounds on a cloudy node (i = 1, k = 1) and its column.
      const std::size_t a =
          grid.index(std::min(1, grid.lon_deg.count - 1), 0, std::min(1, grid.alt_m.count - 1));
      if (std::isnan(value))
        m.beam[a] = static_cast<float>(nan), m.beam_dir[a % grid.columns()] = glm::dvec3(nan);
      if (std::isinf(value)) m.gcoef[a] = static_cast<float>(inf), m.ground[a % grid.columns()] = inf;
      m.ground_light.assign(grid.columns(), value);
      const LateralRatio r = lateral_ratio(grid, m);
      for (std::size_t a = 0; a < grid.points(); ++a) {
        ASSERT_TRUE(r.ratio[a] >= 0.0f && r.ratio[a] <= float(kLateralRatioMax))
            << value << " node " << a << " " << r.ratio[a];
        ASSERT_TRUE(std::isfinite(r.east[a]) && std::isfinite(r.north[a])) << value << " node " << a;
        ASSERT_LE(std::hypot(r.east[a], r.north[a]), 1.0f + 1e-6f);
      }
    }
  }
}

// Through the source's build: off, the columns are on their own as before and carry no horizontal
// moment; on, the bubble's columns lose light to its sides, and a clear column beside cloud takes
// the light at the cloud's edge where it was dark.
TEST(Lateral, TheSourceTakesTheLightBetweenItsColumns) {
  cv::test::BubbleScene bubble(false);
  for (int k = 0; k < bubble.grid.alt_m.count; ++k)  // the bubble cut at r2 = 1, so clear columns surround it
    for (int j = 0; j < bubble.grid.lat_deg.count; ++j)
      for (int i = 0; i < bubble.grid.lon_deg.count; ++i) {
        float& v = bubble.data[Field::ExtinctionLiquid][bubble.grid.index(i, j, k)];
        if (v < 0.02f * std::exp(-2.0f)) v = 0.0f;
      }
  const PreparedVolume v = prepare_volume(bubble.grid, bubble.data);
  MarchSettings s;
  const glm::dvec3 to_sun = glm::normalize(glm::dvec3(1.0, 0.3, 0.2));  // over (0, 0), whose up is +x
  MsSourceKey off = ms_source_key(s, to_sun);
  off.lateral = false;
  const MsSourceKey on = ms_source_key(s, to_sun);
  EXPECT_TRUE(on.lateral);
  EXPECT_FALSE(on == off);
  const MsSource columns = build_ms_source(v, off), lateral = build_ms_source(v, on);
  EXPECT_TRUE(columns.i1e.empty() && columns.i1n.empty());
  EXPECT_EQ(columns.lateral_iterations, -1);
  EXPECT_NE(columns.columns_alone.find("turned off"), std::string::npos) << columns.columns_alone;
  ASSERT_EQ(lateral.i1e.size(), lateral.i0.size());
  EXPECT_GT(lateral.lateral_iterations, 0);
  EXPECT_TRUE(lateral.columns_alone.empty()) << lateral.columns_alone;
  const VolumeGrid& g = bubble.grid;
  const int k = 10;  // 3 km, the bubble's middle
  EXPECT_LT(lateral.i0[g.index(20, 20, k)], columns.i0[g.index(20, 20, k)])
      << "the core loses light to the sides";
  int edge = -1;  // the first clear column east of the centre
  for (int i = 20; i < g.lon_deg.count && edge < 0; ++i) {
    if (bubble.data[Field::ExtinctionLiquid][g.index(i, 20, k)] == 0.0f) edge = i;
  }
  ASSERT_GT(edge, 20);
  EXPECT_EQ(columns.i0[g.index(edge, 20, k)], 0.0f);
  EXPECT_GT(lateral.i0[g.index(edge, 20, k)], 0.0f)
      << "the clear column beside the cloud takes the light at its edge";
  EXPECT_GT(lateral.i1e[g.index(edge - 1, 20, k)], 0.0f) << "the east side's light flows east";
  EXPECT_EQ(lateral.i0[g.index(edge + 2, 20, k)], 0.0f) << "further out, no light of the cloud's";
  EXPECT_EQ(lateral.i0[g.index(edge, 20, 0)], 0.0f)
      << "the ground beside the cloud takes no light from under it";
  EXPECT_GT(lateral.i0[g.index(20, 20, 0)], 0.0f) << "the ground under it does";
  const std::vector<float> moments = ms_moments_texels(lateral), horizontal = ms_horizontal_texels(lateral);
  ASSERT_EQ(moments.size(), 2 * lateral.i0.size());
  EXPECT_EQ(moments[2 * g.index(20, 20, k)], lateral.i0[g.index(20, 20, k)]);
  EXPECT_EQ(moments[2 * g.index(20, 20, k) + 1], lateral.i1[g.index(20, 20, k)]);
  EXPECT_EQ(horizontal[2 * g.index(edge - 1, 20, k)], lateral.i1e[g.index(edge - 1, 20, k)]);
  EXPECT_TRUE(ms_horizontal_texels(columns).empty());
}

// The fringe's light falls with the columns' spacing against the cloud's height: a block of cloud
// 1-3 km up (its levels' span and a level: 2.25 km high), 5 x 5 columns. On columns 1.1 km apart
// the clear column east of it takes its cloudy neighbours' mean at each level (the side's light
// reaches it whole); on columns 111 km apart (a global model's), about H / dx of it (a fringe 50
// cloud heights wide is its own thin column's: there, 2 to 3 % of the edge's light).
TEST(Lateral, TheFringesLightFallsWithTheColumnsSpacing) {
  for (const double step : {0.01, 1.0}) {
    VolumeGrid g;
    g.lon_deg = {-10.0 * step, step, 21};
    g.lat_deg = {-10.0 * step, step, 21};
    g.alt_m = {500.0, 250.0, 17};
    TimeStepData d;
    d[Field::ExtinctionLiquid].assign(g.points(), 0.0f);
    for (int k = 0; k < g.alt_m.count; ++k)
      for (int j = 8; j <= 12; ++j)
        for (int i = 8; i <= 12; ++i)
          if (g.alt_m.at(k) >= 1000.0 && g.alt_m.at(k) <= 3000.0) d[Field::ExtinctionLiquid][g.index(i, j, k)] = 0.02f;
    MarchSettings s;
    const glm::dvec3 to_sun = glm::normalize(glm::dvec3(1.0, 0.1, 0.2));  // over (0, 0), whose up is +x
    const MsSourceKey key = ms_source_key(s, to_sun);
    ASSERT_TRUE(key.lateral);
    const MsSource src = build_ms_source(prepare_volume(g, d), key);
    int levels = 0;
    for (int k = 2; k <= 10; ++k) {  // 1-3 km
      const double mean = (src.i0[g.index(12, 9, k)] + src.i0[g.index(12, 10, k)] + src.i0[g.index(12, 11, k)]) / 3.0;
      ASSERT_GT(mean, 0.0) << "level " << k;
      const double ratio = src.i0[g.index(13, 10, k)] / mean;
      if (step < 0.1) {
        EXPECT_NEAR(ratio, 1.0, 1e-5) << "level " << k;
      } else {
        EXPECT_GT(ratio, 0.01) << "level " << k;
        EXPECT_LT(ratio, 0.03) << "level " << k;
      }
      ++levels;
    }
    EXPECT_EQ(levels, 9);
  }
}

// What `render` says when the columns stay on their own: the reason, not a budget the grid is within.
TEST(Lateral, SaysWhyTheColumnsStayOnTheirOwn) {
  MsSourceKey key;
  VolumeGrid g = box(0.005, 21, 31);
  EXPECT_EQ(ms_columns_alone_why(g, key), "");
  key.lateral = false;
  EXPECT_NE(ms_columns_alone_why(g, key).find("turned off"), std::string::npos);
  key.lateral = true;
  g.lon_deg.count = g.lat_deg.count = 1;  // one column: no neighbours
  EXPECT_EQ(ms_columns_alone_why(g, key), "the grid has one column");
  g.lon_deg.count = 2048, g.lat_deg.count = 1024, g.alt_m.count = 8;  // 16 Mi nodes: counts only, nothing allocated
  const std::string big = ms_columns_alone_why(g, key);
  EXPECT_NE(big.find("16777216 nodes"), std::string::npos) << big;
  EXPECT_NE(big.find(std::to_string(kLateralMaxNodes)), std::string::npos) << big;
}

}  // namespace
}  // namespace cv::core
