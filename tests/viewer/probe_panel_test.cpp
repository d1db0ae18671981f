// The viewer's probe panel (issue 17, item 4): a click is a press and release without a drag, the
// pixel clicked is where its ray meets the ground, and the column read there is the one
// `cloudviewer probe` reads, down to the CSV.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "support/scratch_dir.hpp"
#include "importer.hpp"
#include "viewer/playback.hpp"
#include "viewer/probe_panel.hpp"

namespace {
using namespace cv;
constexpr double kR0 = 6371000.0;

TEST(ProbePanel, AClickIsAPressAndReleaseWithoutADrag) {
  viewer::ClickDetector c;
  EXPECT_FALSE(c.update(false, 10, 10));
  EXPECT_FALSE(c.update(true, 10, 10));
  EXPECT_FALSE(c.update(true, 11, 12));
  EXPECT_TRUE(c.update(false, 11, 12));  // within 3 pixels: a click at the press
  EXPECT_EQ(c.x0, 10.0);
  EXPECT_FALSE(c.update(true, 50, 50));
  EXPECT_FALSE(c.update(true, 80, 50));  // a drag (it orbits)...
  EXPECT_FALSE(c.update(true, 51, 50));  // ...even when it comes back
  EXPECT_FALSE(c.update(false, 51, 50));
}

TEST(ProbePanel, ThePixelClickedIsWhereItsRayMeetsTheGround) {
  core::Camera nadir;
  nadir.lat_deg = 45.0, nadir.lon_deg = -175.0, nadir.alt_m = 1.0e6, nadir.pitch_deg = -90.0, nadir.width = 65, nadir.height = 65;
  const auto below = viewer::pixel_ground(nadir, 32.5, 32.5, kR0);  // the middle pixel looks straight down
  ASSERT_TRUE(below);
  EXPECT_NEAR(below->x, 45.0, 1e-6);
  EXPECT_NEAR(below->y, -175.0, 1e-6);
  const auto left = viewer::pixel_ground(nadir, 0.5, 32.5, kR0);  // west of it (heading north: left is west)
  ASSERT_TRUE(left);
  EXPECT_LT(std::remainder(left->y - -175.0, 360.0), -1.0);  // across the antimeridian: 177.6 E is 7.4 degrees west
  EXPECT_NEAR(left->x, 45.0, 0.5);
  // An oblique view: the middle pixel meets the ground where the view centre does.
  core::Camera oblique = nadir;
  oblique.pitch_deg = -50.0, oblique.heading_deg = 70.0;  // from 1000 km the horizon lies 30 degrees down
  const auto centre = viewer::pixel_ground(oblique, 32.5, 32.5, kR0);
  ASSERT_TRUE(centre);
  EXPECT_NEAR(centre->y, viewer::view_centre_lon_deg(oblique, kR0), 1e-6);
  // Looking up from a low camera: the sky, no column.
  core::Camera up = nadir;
  up.alt_m = 1000.0, up.pitch_deg = 30.0;
  EXPECT_FALSE(viewer::pixel_ground(up, 32.5, 0.5, kR0));
}

std::string read_all(const std::string& path) {
  std::ifstream f(path);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

TEST(ProbePanel, ReadsTheColumnTheProbeCommandReadsDownToTheCsv) {
  core::CloudVolume vol = importers::import_file(CV_SAMPLE_FILE);
  viewer::ProbePanel p;
  viewer::probe_into(p, vol, CV_SAMPLE_FILE, 1, 45.0, 185.0);
  ASSERT_TRUE(p.message.empty()) << p.message;
  EXPECT_TRUE(p.open);
  EXPECT_EQ(p.valid, "2024-01-15T03:00:00Z");
  ASSERT_FALSE(p.column.levels.empty());
  EXPECT_GT(p.column.cover, 0.0);  // the sample's cyclone has cloud there: the comparison reads values

  const std::string dir = cv::test_support::scratch_dir();
  const std::string cli_csv = dir + "/probe_cli.csv", panel_csv = dir + "/probe_panel.csv";
  const std::string cmd = std::string("\"") + CV_CLOUDVIEWER + "\" probe \"" + CV_SAMPLE_FILE + "\" --at 45,185 --time 1 --csv \"" + cli_csv +
                          "\" > /dev/null";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  p.csv_path = panel_csv;
  ASSERT_TRUE(viewer::save_probe_csv(p)) << p.message;
  EXPECT_EQ(read_all(panel_csv), read_all(cli_csv));

  // Outside the data: the message names the extent, and the last column stays.
  viewer::probe_into(p, vol, CV_SAMPLE_FILE, 1, 0.0, 0.0);
  EXPECT_NE(p.message.find("is outside the data of"), std::string::npos) << p.message;
  EXPECT_NE(p.message.find("lat 25..65, lon 160..220"), std::string::npos) << p.message;
  EXPECT_EQ(p.lat_deg, 45.0);
  // A CSV path that is not a .csv is refused, naming it.
  p.csv_path = dir + "/probe.txt";
  EXPECT_FALSE(viewer::save_probe_csv(p));
  EXPECT_NE(p.message.find("probe CSV"), std::string::npos) << p.message;
}

// With the clicked view's camera, the panel records where the light came from along the view ray,
// as `probe --camera` does: the same march kernel's record, down to the CSV's summary line.
TEST(ProbePanel, RecordsTheViewRayAsTheProbeCommandWithACamera) {
  core::CloudVolume vol = importers::import_file(CV_SAMPLE_FILE);
  core::Camera cam;
  cam.lat_deg = 40.0, cam.lon_deg = 180.0, cam.alt_m = 300000.0;
  viewer::ProbePanel p;
  viewer::probe_into(p, vol, CV_SAMPLE_FILE, 1, 45.0, 185.0, &cam, 200.0);
  ASSERT_TRUE(p.message.empty()) << p.message;
  ASSERT_TRUE(p.ray.has_value());
  EXPECT_GT(p.ray->first_cloud_m, 0.0);  // the cyclone's cloud lies on the way: the record holds values
  EXPECT_LT(p.ray->first_cloud_m, p.ray->distance_to_target_m);
  EXPECT_LT(p.ray->transmittance, 1.0);
  EXPECT_EQ(p.ray->view_step_m, 200.0);

  const std::string dir = cv::test_support::scratch_dir();
  const std::string cli_csv = dir + "/probe_ray_cli.csv", panel_csv = dir + "/probe_ray_panel.csv";
  const std::string cmd = std::string("\"") + CV_CLOUDVIEWER + "\" probe \"" + CV_SAMPLE_FILE +
                          "\" --at 45,185 --time 1 --camera 40,180,300000 --view-step 200 --csv \"" + cli_csv + "\" > /dev/null";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  p.csv_path = panel_csv;
  ASSERT_TRUE(viewer::save_probe_csv(p)) << p.message;
  const std::string panel = read_all(panel_csv);
  EXPECT_EQ(panel, read_all(cli_csv));
  EXPECT_NE(panel.find(",first_cloud_m="), std::string::npos);

  // Without a camera (a probe by coordinates), no ray is kept from the click before.
  viewer::probe_into(p, vol, CV_SAMPLE_FILE, 1, 45.0, 185.0);
  EXPECT_FALSE(p.ray.has_value());
}

}  // namespace
