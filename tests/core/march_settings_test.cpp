// The settings table (core/settings/march_settings.def) against its consumers: image equality,
// the scene file's reader and writer, and docs/scene.md, row by row.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>

#include "scene/quality.hpp"
#include "scene/scene_json.hpp"
#include "settings/march_settings.hpp"
#include "support/march_values.hpp"

namespace {
using namespace cv::core;

TEST(MarchSettingsTable, SameImageNoticesEveryRowThatChangesTheImage) {
  const MarchSettings base;
  EXPECT_TRUE(same_image(base, base));
  for (std::size_t i = 0; i < kMarchSettingCount; ++i) {
    MarchSettings changed = base;
    std::size_t j = 0;
    for_each_march_setting_pair(changed, base, [&](const SettingRow& row, auto& v, const auto& b) {
      if (j++ == i) v = cv::test::other_value(row, b);
    });
    const SettingRow& row = kMarchSettingRows[i];
    // Only per-frame state (the accumulation's frame counter) leaves the image as it is.
    EXPECT_EQ(row.image, row.group != SettingGroup::PerFrame) << row.key;
    EXPECT_EQ(same_image(base, changed), !row.image) << "render.march." << row.key;
  }
}

TEST(MarchSettingsTable, TheWriterWritesEveryRow) {
  const std::string text = scene_to_json(Scene{});
  for (const SettingRow& row : kMarchSettingRows) {
    EXPECT_NE(text.find(std::string("\"") + row.key + "\":"), std::string::npos) << row.key;
  }
}

std::string error_of(const std::string& text) {
  try {
    scene_from_json(text, "scene.json");
  } catch (const SceneError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(MarchSettingsTable, EveryNumberOutsideItsRowsRangeIsRefusedInOneLine) {
  for (const SettingRow& row : kMarchSettingRows) {
    if (row.kind != SettingKind::Int && row.kind != SettingKind::Real) continue;
    const double above = row.hi + 1.0 + std::abs(row.hi);
    const std::string found = short_number(above);
    EXPECT_EQ(error_of(R"({"version": 1, "render": {"march": {")" + std::string(row.key) + "\": " + found + "}}}"),
              "scene.json: render.march." + std::string(row.key) + ": found " + found + ", expected " + expected_text(row));
    // Positive values below the row's floor are refused too (0 alone where zero_ok: "from the grid").
    if (row.lo > 0.0) {
      const std::string below = short_number(row.lo / 1e3);
      EXPECT_NE(error_of(R"({"version": 1, "render": {"march": {")" + std::string(row.key) + "\": " + below + "}}}"),
                "(no error)")
          << row.key << " " << below;
    }
  }
  // The view step: 0 is "from the grid", but a step so small that a ray would never end is refused.
  EXPECT_EQ(error_of(R"({"version": 1, "render": {"march": {"view_step_m": 1e-9}}})"),
            "scene.json: render.march.view_step_m: found 1e-09, expected a view step in metres 0 or 1..1e7 (0: from the grid)");
  EXPECT_EQ(error_of(R"({"version": 1, "render": {"march": {"view_step_m": 0}}})"), "(no error)");
  EXPECT_EQ(error_of(R"({"version": 1, "render": {"march": {"liquid_phase": "rayleigh"}}})"),
            "scene.json: render.march.liquid_phase: found \"rayleigh\", expected \"mie\" or \"hg\"");
  EXPECT_EQ(error_of(R"({"version": 1, "render": {"march": {"ground_albedo": [0.1, 2, 0.1]}}})"),
            "scene.json: render.march.ground_albedo: found a value of 2, expected three linear albedos 0..1 [r, g, b]");
}

// docs/scene.md's key table: the backticked keys of each row's first cell (`render.march.octave_a`,
// `octave_b`, `octave_c` document three keys) and the row's second cell (type and range).
std::map<std::string, std::string> documented_march_keys() {
  std::ifstream in(std::string(CV_SOURCE_DIR) + "/docs/scene.md");
  EXPECT_TRUE(in) << "cannot read " << CV_SOURCE_DIR << "/docs/scene.md";
  std::map<std::string, std::string> keys;
  const std::string prefix = "render.march.";
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("| `" + prefix, 0) != 0) continue;
    const auto c1 = line.find('|', 1), c2 = line.find('|', c1 + 1);
    const std::string first = line.substr(1, c1 - 1), second = line.substr(c1 + 1, c2 - c1 - 1);
    for (std::size_t p = first.find('`'); p != std::string::npos; p = first.find('`', p + 1)) {
      const auto q = first.find('`', p + 1);
      std::string key = first.substr(p + 1, q - p - 1);
      if (key.rfind(prefix, 0) == 0) key = key.substr(prefix.size());
      keys[key] = second;
      p = q;
    }
  }
  return keys;
}

TEST(MarchSettingsTable, DocsSceneMdDocumentsEveryRowWithItsRange) {
  const auto documented = documented_march_keys();
  std::set<std::string> rows;
  for (const SettingRow& row : kMarchSettingRows) {
    rows.insert(row.key);
    const auto it = documented.find(row.key);
    if (it == documented.end()) {
      ADD_FAILURE() << "docs/scene.md has no entry `render.march." << row.key << "` (" << row.doc << ")";
      continue;
    }
    const std::string& cell = it->second;
    switch (row.kind) {
      case SettingKind::Int:
      case SettingKind::Real:
      case SettingKind::Rgb01:
        EXPECT_NE(cell.find(range_text(row)), std::string::npos)
            << "docs/scene.md: render.march." << row.key << ": '" << cell << "' does not give the range " << range_text(row);
        break;
      case SettingKind::Bool: EXPECT_NE(cell.find("true/false"), std::string::npos) << row.key; break;
      case SettingKind::Choice:
        EXPECT_NE(cell.find(row.choices[0]), std::string::npos) << row.key;
        EXPECT_NE(cell.find(row.choices[1]), std::string::npos) << row.key;
        break;
      case SettingKind::Text: EXPECT_NE(cell.find("string"), std::string::npos) << row.key; break;
    }
  }
  // And no documented key that is no row (a renamed or removed setting).
  for (const auto& [key, cell] : documented) EXPECT_TRUE(rows.count(key)) << "docs/scene.md documents render.march." << key << ", which is no setting";
}

}  // namespace
