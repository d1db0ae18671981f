// The data a scene names (see scene_source.hpp).
#include "scene_source.hpp"

#include <cstdio>

#include "importer.hpp"
#include "scene/scene_json.hpp"
#include "volume/volume_io.hpp"

namespace cv::importers {

core::CloudVolume load_scene_volume(const core::Scene& scene, std::size_t cache_steps) {
  const core::DataSource& d = scene.data;
  const bool cvvol = d.path.size() >= 6 && d.path.compare(d.path.size() - 6, 6, ".cvvol") == 0;
  if (cvvol) {
    if (d.region_deg || d.levels_hpa || d.horizontal_stride != 1 || d.dz_m != 0.0) {
      throw core::SceneError(d.path +
                             ": found a region, levels, stride or dz for a .cvvol volume, expected them only for NetCDF input "
                             "(a volume is subset when it is imported)");
    }
    // diagnose_cloud applies only where a file has no cloud field; a volume always has its cloud.
    return core::read_cvvol(d.path, cache_steps);
  }
  ImportOptions o;
  if (d.region_deg) o.region = Region{(*d.region_deg)[0], (*d.region_deg)[1], (*d.region_deg)[2], (*d.region_deg)[3]};
  if (d.levels_hpa) o.level_min_hpa = (*d.levels_hpa)[0], o.level_max_hpa = (*d.levels_hpa)[1];
  o.horizontal_stride = d.horizontal_stride;
  o.dz_m = d.dz_m;
  o.diagnose_cloud = d.diagnose_cloud;
  o.rh_critical = d.rh_critical;
  o.cache_steps = cache_steps;
  return import_file(d.path, o);
}

void print_diagnosed_cloud_note(const core::CloudVolume& volume, const char* command) {
  for (const auto& w : volume.report.warnings) {
    if (w.rfind("DIAGNOSED CLOUD", 0) == 0) std::fprintf(stderr, "%s: %s\n", command, w.c_str());
  }
}

}  // namespace cv::importers
