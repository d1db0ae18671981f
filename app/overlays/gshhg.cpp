// GSHHG features through the GMT library (see gshhg.hpp).
#include "overlays/gshhg.hpp"

#include <gmt.h>

#include <cstdio>
#include <filesystem>
#include <mutex>

#include "overlays/overlays.hpp"

namespace cv::overlays {
namespace {

const char* package_of(char res) {
  return res == 'f' ? "gmt-gshhg-full" : res == 'h' ? "gmt-gshhg-high" : "gmt-gshhg-low";
}

std::string file_of(GshhgFeature f, char res) {
  const char* stem = f == GshhgFeature::Shore ? "binned_GSHHS_" : f == GshhgFeature::Border ? "binned_border_" : "binned_river_";
  return std::string(stem) + res + ".nc";
}

// GMT's messages for this call, instead of its printing them to stderr.
std::mutex g_gmt_mutex;  // one session at a time: the messages go to one string
std::string* g_messages = nullptr;
int collect(FILE*, const char* message) {
  if (g_messages) *g_messages += message;
  return 0;
}

}  // namespace

std::vector<std::vector<glm::dvec2>> read_gshhg_lines(GshhgFeature feature, char res, const std::string& select, const GeoBox& box,
                                                      const std::string& dir, char* chosen) {
  const char* what = feature == GshhgFeature::Shore ? "coastlines" : feature == GshhgFeature::Border ? "borders" : "rivers";
  // The requested resolution, else the nearest installed (finer first).
  const std::string order = "clihf";
  const std::size_t fit = std::min(order.find(res), order.size() - 1);
  std::string preference(1, order[fit]);
  for (std::size_t k = fit + 1; k < order.size(); ++k) preference += order[k];
  for (std::size_t k = fit; k-- > 0;) preference += order[k];
  char use = 0;
  for (char r : preference) {
    if (std::filesystem::exists(dir + "/" + file_of(feature, r))) {
      use = r;
      break;
    }
  }
  if (!use) {
    throw OverlayError(std::string("overlays: ") + what + ": no GSHHG files (" + file_of(feature, order[fit]) + ") under " + dir +
                       ", expected the files of the Debian package " + package_of(order[fit]) + " (apt-get install " +
                       package_of(order[fit]) + " gmt-common)");
  }
  if (chosen) *chosen = use;

  std::lock_guard<std::mutex> lock(g_gmt_mutex);
  std::string messages;
  g_messages = &messages;
  struct Session {
    void* api = nullptr;
    ~Session() {
      if (api) GMT_Destroy_Session(api);
      g_messages = nullptr;
    }
  } session;
  session.api = GMT_Create_Session("cloudviewer", 2, GMT_SESSION_NOEXIT | GMT_SESSION_EXTERNAL | GMT_SESSION_COLMAJOR | GMT_SESSION_NOHISTORY, collect);
  auto fail = [&](const std::string& step) {
    std::string m = messages;
    while (!m.empty() && (m.back() == '\n' || m.back() == ' ')) m.pop_back();
    for (char& c : m) c = c == '\n' ? ' ' : c;
    return OverlayError(std::string("overlays: ") + what + ": the GMT library " + step + " failed" + (m.empty() ? "" : ": " + m) +
                        " (GMT needs the Debian packages libgmt6 and gmt-common)");
  };
  if (!session.api) throw fail("session");
  char out[GMT_VF_LEN] = {};
  if (GMT_Open_VirtualFile(session.api, GMT_IS_DATASET, GMT_IS_LINE, static_cast<unsigned>(GMT_OUT) | static_cast<unsigned>(GMT_IS_REFERENCE), nullptr, out) != GMT_NOERROR) {
    throw fail("virtual file");
  }
  char region[128];
  if (box.global) {
    std::snprintf(region, sizeof region, "-Rd");
  } else {
    std::snprintf(region, sizeof region, "-R%.6f/%.6f/%.6f/%.6f", box.lon_min, box.lon_max, box.lat_min, box.lat_max);
  }
  // Shores: level 1 (land against the sea) and level 2 (lakes), as -A0/1/2 selects.
  const std::string feature_flag = feature == GshhgFeature::Shore    ? "-W -A0/1/2"
                                   : feature == GshhgFeature::Border ? "-N" + select
                                                                     : "-I" + select;
  // -M dumps the selected features as line segments instead of drawing a map.
  const std::string args = std::string(region) + " -D" + use + " " + feature_flag + " -M --DIR_GSHHG=" + dir + " ->" + out;
  if (GMT_Call_Module(session.api, "coast", GMT_MODULE_CMD, const_cast<char*>(args.c_str())) != GMT_NOERROR) throw fail("coast module");
  auto* data = static_cast<GMT_DATASET*>(GMT_Read_VirtualFile(session.api, out));
  std::vector<std::vector<glm::dvec2>> lines;
  if (data) {
    for (std::uint64_t t = 0; t < data->n_tables; ++t) {
      for (std::uint64_t s = 0; s < data->table[t]->n_segments; ++s) {
        const GMT_DATASEGMENT* seg = data->table[t]->segment[s];
        if (seg->n_rows < 2 || seg->n_columns < 2) continue;
        // GMT gives whole bins: a regional box keeps the runs of points inside it.
        std::vector<glm::dvec2> line;
        for (std::uint64_t r = 0; r < seg->n_rows; ++r) {
          glm::dvec2 p(seg->data[0][r], seg->data[1][r]);
          if (!box.global) {
            while (p.x < box.lon_min) p.x += 360.0;
            while (p.x > box.lon_min + 360.0) p.x -= 360.0;
          }
          const bool inside = box.global || (p.x <= box.lon_max && p.y >= box.lat_min && p.y <= box.lat_max);
          if (inside) line.push_back(p);
          if ((!inside || r + 1 == seg->n_rows) && !line.empty()) {
            if (line.size() >= 2) lines.push_back(line);
            line.clear();
          }
        }
      }
    }
  }
  GMT_Close_VirtualFile(session.api, out);
  return lines;
}

}  // namespace cv::overlays
