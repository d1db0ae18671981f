// The viewer's playhead: the grid of instants, play with loop or stop at the end, step to the
// file's steps, the instants prefetching asks for; and the local solar time.
#include <gtest/gtest.h>

#include "geo/solar.hpp"
#include "scene/instant.hpp"
#include "viewer/playback.hpp"

namespace cv::viewer {
namespace {

std::vector<core::ValidTime> three_hourly(int n) {
  std::vector<core::ValidTime> t;
  for (int i = 0; i < n; ++i) t.push_back({1705276800 + i * 10800, core::format_iso_utc(1705276800 + i * 10800)});
  return t;
}

TEST(Playhead, PlaysOnAGridOfInstantsAndLoopsOrStops) {
  Playhead p;
  p.frames_per_step = 4;
  p.reset(three_hourly(3));  // 00, 03, 06 UTC
  EXPECT_DOUBLE_EQ(p.quantum_s, 2700.0);
  EXPECT_EQ(p.shown(), 1705276800);
  p.playing = true;
  p.speed_h_per_s = 1.0;
  p.advance(0.5);  // half an hour: on the grid, 45 min
  EXPECT_EQ(p.shown(), 1705276800 + 2700);
  EXPECT_EQ(p.upcoming(3), (std::vector<std::int64_t>{1705276800 + 5400, 1705276800 + 8100, 1705276800 + 10800}));
  p.t_s = p.last_s;
  p.advance_one();  // past the end: back to the start on loop
  EXPECT_EQ(p.shown(), 1705276800);
  p.loop = false;
  p.t_s = p.last_s;
  p.advance_one();
  EXPECT_FALSE(p.playing);
  EXPECT_EQ(p.shown(), 1705276800 + 21600);
  EXPECT_TRUE(p.upcoming(2).empty());
}

TEST(Playhead, StepsToTheFilesStepsAndAOneStepFileIsAStill) {
  const auto times = three_hourly(3);
  Playhead p;
  p.reset(times);
  p.t_s = 1705276800 + 4000;
  p.step(times, +1);
  EXPECT_EQ(p.shown(), 1705276800 + 10800);
  p.step(times, -1);
  EXPECT_EQ(p.shown(), 1705276800);
  Playhead one;
  one.playing = true;
  one.reset(three_hourly(1));
  EXPECT_TRUE(one.still());
  EXPECT_FALSE(one.playing);
  one.advance(10.0);
  EXPECT_EQ(one.shown(), 1705276800);
}

TEST(LocalSolarTime, IsNoonUnderTheSun) {
  const std::int64_t t = 1705276800;  // 2024-01-15T00:00:00Z: the sun is near 177 E (the equation of time)
  const double lon = geo::subsolar_point(t).lon_deg;
  EXPECT_NEAR(local_solar_time_h(lon, t), 12.0, 1e-9);
  EXPECT_NEAR(local_solar_time_h(lon + 90.0, t), 18.0, 1e-9);
  EXPECT_NEAR(local_solar_time_h(lon - 180.0, t), 0.0, 1e-9);
}

}  // namespace
}  // namespace cv::viewer
