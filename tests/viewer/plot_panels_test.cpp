// The viewer's Section and Series panels (issue 17, item 5): on the sample, the figures and the
// saved PNG and CSV are those `cloudviewer section` and `cloudviewer series` write for the same
// inputs, byte for byte, and bad inputs give the command's own one-line message in the panel.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include <sys/wait.h>

#include "support/scratch_dir.hpp"
#include "importer.hpp"
#include "plots/drape.hpp"
#include "scene/framing.hpp"
#include "viewer/plot_panels.hpp"

namespace {
using namespace cv;

std::string read_all(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

// Runs the command with ARGS; its exit status, and its stderr (a bad input's one line).
int run_cli(const std::string& args, std::string& err) {
  // One file per test: ctest runs the tests of this file in parallel.
  const std::string err_path =
      cv::test_support::scratch_dir() + "/plot_panels_" + ::testing::UnitTest::GetInstance()->current_test_info()->name() + ".err";
  const std::string cmd = std::string("\"") + CV_CLOUDVIEWER + "\" " + args + " > /dev/null 2> \"" + err_path + "\"";
  const int status = std::system(cmd.c_str());
  err = read_all(err_path);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string quoted(const std::string& s) { return "\"" + s + "\""; }

TEST(PlotPanels, TheSectionIsTheSectionCommandsDownToThePngAndCsv) {
  core::CloudVolume vol = importers::import_file(CV_SAMPLE_FILE);
  viewer::SectionPanel p;
  p.inputs.field = "cloud_fraction";
  p.inputs.lat1 = 35, p.inputs.lon1 = 170, p.inputs.lat2 = 55, p.inputs.lon2 = 200;
  viewer::compute_section(p, vol, CV_SAMPLE_FILE, 1);
  ASSERT_TRUE(p.message.empty()) << p.message;
  ASSERT_TRUE(p.has_figure);
  EXPECT_EQ(p.valid, "2024-01-15T03:00:00Z");
  EXPECT_NEAR(p.figure.pixels.length_m / 1000.0, 3197.0, 1.0);  // as cli.section_sample prints
  EXPECT_EQ(p.figure.canvas.width(), 800);                       // the command's default size
  EXPECT_EQ(p.figure.canvas.height(), 400);
  int cloudy = 0;
  for (unsigned char c : p.figure.grid_rows.cloudy) cloudy += c;
  EXPECT_GT(cloudy, 0);  // the path crosses the cyclone's cloud: the comparison reads values
  EXPECT_GT(p.figure.hi, p.figure.lo);

  const std::string dir = cv::test_support::scratch_dir();
  std::string err;
  ASSERT_EQ(run_cli("section " + quoted(CV_SAMPLE_FILE) + " --from 35,170 --to 55,200 --field cloud_fraction --time 1 -o " +
                        quoted(dir + "/section_cli.png") + " --csv " + quoted(dir + "/section_cli.csv"),
                    err),
            0)
      << err;
  p.png_path = dir + "/section_panel.png", p.csv_path = dir + "/section_panel.csv";
  ASSERT_TRUE(viewer::save_section(p)) << p.message;
  EXPECT_EQ(p.message, "wrote " + p.png_path + " and " + p.csv_path);
  const std::string png = read_all(p.png_path), csv = read_all(p.csv_path);
  EXPECT_GT(png.size(), 1000u);
  // Compared as booleans: a PNG or a 20000-line CSV is no use in the log.
  EXPECT_TRUE(png == read_all(dir + "/section_cli.png")) << "the panel's PNG differs from section -o";
  EXPECT_TRUE(csv == read_all(dir + "/section_cli.csv")) << "the panel's CSV differs from section --csv";
  EXPECT_TRUE(csv == p.figure.csv);
  // A PNG path that is not a .png is refused, naming it; nothing is written.
  p.png_path = dir + "/section.jpg";
  EXPECT_FALSE(viewer::save_section(p));
  EXPECT_NE(p.message.find("section PNG"), std::string::npos) << p.message;
}

TEST(PlotPanels, BadSectionInputsGiveTheCommandsLineAndKeepTheLastFigure) {
  core::CloudVolume vol = importers::import_file(CV_SAMPLE_FILE);
  viewer::SectionPanel p;
  p.inputs.field = "temperature";
  p.inputs.lat1 = 35, p.inputs.lon1 = 170, p.inputs.lat2 = 55, p.inputs.lon2 = 200;
  viewer::compute_section(p, vol, CV_SAMPLE_FILE, 0);
  ASSERT_TRUE(p.has_figure) << p.message;
  const int version = p.version;
  const std::string csv = p.figure.csv;
  struct Bad {
    const char* field;
    double lat1, lon1, lat2, lon2;
    const char* says;  // a part of the command's line
  };
  const Bad bad[] = {{"rain", 35, 170, 55, 200, "--field: found \"rain\", expected extinction or a field the volume holds"},
                     {"temperature", 35, 170, 35, 170.1, "--from/--to: the path is "},
                     {"temperature", 35, 170, 80, 200, "--to: found 80,200, outside the data of "},
                     {"temperature", 0, 0, 55, 200, "--from: found 0,0, outside the data of "}};
  for (const Bad& b : bad) {
    viewer::SectionPanel q = p;
    q.inputs.field = b.field;
    q.inputs.lat1 = b.lat1, q.inputs.lon1 = b.lon1, q.inputs.lat2 = b.lat2, q.inputs.lon2 = b.lon2;
    viewer::compute_section(q, vol, CV_SAMPLE_FILE, 0);
    EXPECT_NE(q.message.find(b.says), std::string::npos) << q.message;
    char args[200];
    std::snprintf(args, sizeof args, " --from %.6g,%.6g --to %.6g,%.6g --field %s -o ", b.lat1, b.lon1, b.lat2, b.lon2, b.field);
    std::string err;
    EXPECT_EQ(run_cli("section " + quoted(CV_SAMPLE_FILE) + args + quoted(cv::test_support::scratch_dir() + "/bad.png"), err), 2);
    EXPECT_EQ("cloudviewer section: " + q.message + "\n", err);  // the same one line
    EXPECT_EQ(q.version, version);  // the last figure stays
    EXPECT_TRUE(q.figure.csv == csv);
  }
}

TEST(PlotPanels, TheSeriesIsTheSeriesCommandsWithAMarkerAtTheTimeShown) {
  core::CloudVolume vol = importers::import_file(CV_SAMPLE_FILE);
  viewer::SeriesPanel p;
  viewer::ProbePanel probe;
  viewer::take_probe_point(p, probe);  // no click yet
  EXPECT_NE(p.message.find("no probe yet"), std::string::npos) << p.message;
  viewer::probe_into(probe, vol, CV_SAMPLE_FILE, 0, 45.0, 185.0);
  viewer::take_probe_point(p, probe);
  EXPECT_EQ(p.lat_deg, 45.0);
  EXPECT_EQ(p.lon_deg, 185.0);
  viewer::compute_series(p, vol, CV_SAMPLE_FILE);
  ASSERT_TRUE(p.message.empty()) << p.message;
  ASSERT_EQ(p.figure.columns.size(), 6u);
  EXPECT_TRUE(p.figure.timed);
  EXPECT_DOUBLE_EQ(p.figure.hours[5], 15.0);
  // Step 1's column is the probe's column at step 1.
  viewer::probe_into(probe, vol, CV_SAMPLE_FILE, 1, 45.0, 185.0);
  EXPECT_EQ(p.figure.columns[1].cover, probe.column.cover);
  EXPECT_EQ(p.figure.columns[1].optical_depth, probe.column.optical_depth);
  EXPECT_GT(probe.column.cover, 0.0);

  const std::string dir = cv::test_support::scratch_dir();
  std::string err;
  ASSERT_EQ(run_cli("series " + quoted(CV_SAMPLE_FILE) + " --at 45,185 -o " + quoted(dir + "/series_cli.png") + " --csv " +
                        quoted(dir + "/series_cli.csv"),
                    err),
            0)
      << err;
  p.png_path = dir + "/series_panel.png", p.csv_path = dir + "/series_panel.csv";
  ASSERT_TRUE(viewer::save_series(p)) << p.message;
  EXPECT_GT(read_all(p.png_path).size(), 1000u);
  EXPECT_TRUE(read_all(p.png_path) == read_all(dir + "/series_cli.png")) << "the panel's PNG differs from series -o";
  EXPECT_EQ(read_all(p.csv_path), read_all(dir + "/series_cli.csv"));

  // The marker: on the axis where the steps' points are drawn, nothing outside it.
  EXPECT_DOUBLE_EQ(viewer::series_marker_x(p, 0.0), p.figure.left);
  EXPECT_DOUBLE_EQ(viewer::series_marker_x(p, 15.0), p.figure.right);
  EXPECT_DOUBLE_EQ(viewer::series_marker_x(p, 3.0), plots::series_x(p.figure, p.figure.hours[1]));
  EXPECT_GT(viewer::series_marker_x(p, 7.5), p.figure.left);
  EXPECT_TRUE(std::isnan(viewer::series_marker_x(p, 16.0)));
  EXPECT_TRUE(std::isnan(viewer::series_marker_x(p, -1.0)));

  // A point outside the data: the command's line, and the last series stays.
  p.lat_deg = 10.0;
  viewer::compute_series(p, vol, CV_SAMPLE_FILE);
  ASSERT_EQ(run_cli("series " + quoted(CV_SAMPLE_FILE) + " --at 10,185 -o " + quoted(dir + "/bad.png"), err), 2);
  EXPECT_EQ("cloudviewer series: " + p.message + "\n", err);
  EXPECT_EQ(p.at_lat, 45.0);
  EXPECT_EQ(p.figure.columns.size(), 6u);
}

TEST(PlotPanels, TheSectionsEndsComeFromTheLastProbeClick) {
  core::CloudVolume vol = importers::import_file(CV_SAMPLE_FILE);
  viewer::SectionPanel p;
  viewer::ProbePanel probe;
  viewer::take_probe_point(p, probe, 0);
  EXPECT_NE(p.message.find("no probe yet"), std::string::npos) << p.message;
  viewer::probe_into(probe, vol, CV_SAMPLE_FILE, 0, 40.0, 175.0);
  viewer::take_probe_point(p, probe, 0);
  viewer::probe_into(probe, vol, CV_SAMPLE_FILE, 0, 50.0, 195.0);
  viewer::take_probe_point(p, probe, 1);
  EXPECT_EQ(p.inputs.lat1, 40.0);
  EXPECT_EQ(p.inputs.lon1, 175.0);
  EXPECT_EQ(p.inputs.lat2, 50.0);
  EXPECT_EQ(p.inputs.lon2, 195.0);
  EXPECT_FALSE(viewer::save_section(p));  // nothing drawn yet
  viewer::compute_section(p, vol, CV_SAMPLE_FILE, 0);  // the default field: the march's extinction
  EXPECT_TRUE(p.has_figure) << p.message;
  EXPECT_EQ(p.figure.field.name(), "extinction");
}

TEST(PlotPanels, TheCommandLineOpensThePanelsWithTheirInputs) {
  viewer::SectionPanel sec;
  EXPECT_EQ(viewer::section_from_option(sec, "35,170,55,200.5"), "");
  EXPECT_TRUE(sec.open && sec.requested);
  EXPECT_EQ(sec.inputs.lon2, 200.5);
  EXPECT_EQ(sec.inputs.field, "extinction");  // the default
  EXPECT_EQ(viewer::section_from_option(sec, "35,170,55,200,temperature"), "");
  EXPECT_EQ(sec.inputs.field, "temperature");
  for (const char* bad : {"35,170,55", "35,170,55,x", "95,170,55,200", "35,170,55,200,a,b", ""}) {
    viewer::SectionPanel q;
    const std::string m = viewer::section_from_option(q, bad);
    EXPECT_NE(m.find("cloudviewer view: --section: found '" + std::string(bad) + "'"), std::string::npos) << m;
    EXPECT_FALSE(q.open);
  }
  viewer::SeriesPanel ser;
  EXPECT_EQ(viewer::series_from_option(ser, "-45.5,185"), "");
  EXPECT_EQ(ser.lat_deg, -45.5);
  EXPECT_TRUE(ser.open && ser.requested);
  for (const char* bad : {"45", "45,185,1", "-91,0", "a,b"}) {
    viewer::SeriesPanel q;
    EXPECT_NE(viewer::series_from_option(q, bad).find("--series: found"), std::string::npos) << bad;
  }
}

// A map draped on the globe (compare --render-maps): seen from the south, east is to the right, and
// what lies outside the grid is the globe, not the map.
TEST(Drape, FromTheSouthEastIsRightAndOnlyTheGridIsMapped) {
  core::VolumeGrid g;
  g.lon_deg = {0.0, 1.0, 21};
  g.lat_deg = {40.0, 1.0, 11};
  g.alt_m = {0.0, 1000.0, 3};
  EXPECT_EQ(plots::column_at(g, 45.0, 12.4), g.column(12, 5));
  EXPECT_EQ(plots::column_at(g, 45.0, 12.4 - 360.0), g.column(12, 5));  // longitude modulo 360
  EXPECT_FALSE(plots::column_at(g, 45.0, 30.0));
  EXPECT_FALSE(plots::column_at(g, 60.0, 10.0));
  const plots::Rgb west{0, 0, 250}, east{250, 0, 0};
  const core::Camera cam = core::auto_camera(g, 96, 54);
  plots::Canvas c(96, 54, plots::kPaper);
  plots::drape_columns(c, 0, 0, cam, g, [&](std::size_t col) { return col % 21 >= 10 ? east : west; });
  int n_east = 0, n_west = 0, globe = 0;
  for (int y = 0; y < 54; ++y) {
    int last_west = -1, first_east = 1000;
    for (int x = 0; x < 96; ++x) {
      const plots::Rgb p = c.at(x, y);
      if (p[0] > 0 && p[1] == 0 && p[2] == 0) {
        first_east = std::min(first_east, x);
        ++n_east;
      } else if (p[2] > 0 && p[0] == 0 && p[1] == 0) {
        last_west = std::max(last_west, x);
        ++n_west;
      } else if (p[1] > 0) {
        ++globe;  // kGlobe, shaded
      }
    }
    if (last_west >= 0 && first_east < 1000) {
      EXPECT_LT(last_west, first_east) << "row " << y;
    }
  }
  EXPECT_GT(n_east, 100);
  EXPECT_GT(n_west, 100);
  EXPECT_GT(globe, 0);
}

}  // namespace
