// Resampling a volume on the sphere onto OpenVDB voxels in a tangent frame, and writing them.
#include "vdb/vdb_export.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <mutex>
#include <sstream>

#include <glm/glm.hpp>
#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>

#include "geo/geodesy.hpp"
#include "io/output_file.hpp"
#include "volume/grid_mean.hpp"

namespace cv::vdb {
namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

// Trilinear in index space at fractional indices (fi, fj, fk); NaN outside the grid or where a
// corner has no data.
double trilinear(const core::VolumeGrid& g, const std::vector<float>& f, double fi, double fj, double fk) {
  if (!(fi >= 0 && fj >= 0 && fk >= 0 && fi <= g.lon_deg.count - 1 && fj <= g.lat_deg.count - 1 && fk <= g.alt_m.count - 1)) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  const int i = std::min(static_cast<int>(fi), g.lon_deg.count - 2), j = std::min(static_cast<int>(fj), g.lat_deg.count - 2),
            k = std::min(static_cast<int>(fk), g.alt_m.count - 2);
  const double x = fi - i, y = fj - j, z = fk - k;
  double v = 0.0;
  for (int c = 0; c < 8; ++c) {
    const int di = c & 1, dj = (c >> 1) & 1, dk = (c >> 2) & 1;
    const double w = (di ? x : 1 - x) * (dj ? y : 1 - y) * (dk ? z : 1 - z);
    if (w == 0.0) continue;
    v += w * f[g.index(i + di, j + dj, k + dk)];
  }
  return v;
}

}  // namespace

TangentFrame tangent_frame(const core::VolumeGrid& g) {
  TangentFrame t;
  t.lat0_deg = 0.5 * (g.lat_deg.start + g.lat_deg.last());
  t.lon0_deg = 0.5 * (g.lon_deg.start + g.lon_deg.last());
  t.earth_radius_m = g.earth_radius_m;
  t.origin_ecef = geo::sphere_to_ecef({t.lat0_deg, t.lon0_deg, 0.0}, g.earth_radius_m);
  const geo::EnuFrame e = geo::sphere_enu(t.lat0_deg, t.lon0_deg);
  t.east = e.east, t.north = e.north, t.up = e.up;
  t.voxel_m = glm::dvec3(g.earth_radius_m * std::cos(t.lat0_deg * kDeg) * std::abs(g.lon_deg.step) * kDeg,
                         g.earth_radius_m * std::abs(g.lat_deg.step) * kDeg, std::abs(g.alt_m.step));
  return t;
}

VdbSummary write_vdb(core::OutputGroup& group, const std::string& path, const core::VolumeGrid& g, const core::TimeStepData& step,
                     const std::array<bool, core::kFieldCount>& has_field, const std::string& valid_utc) {
  const bool has_fraction = has_field[static_cast<int>(core::Field::CloudFraction)];
  return write_vdb(group, path, g, core::grid_mean_extinction(g, step), has_fraction ? &step[core::Field::CloudFraction] : nullptr, valid_utc);
}

VdbSummary write_vdb(core::OutputGroup& group, const std::string& path, const core::VolumeGrid& g, const core::GridMeanExtinction& mean,
                     const std::vector<float>* cloud_fraction, const std::string& valid_utc) {
  static std::once_flag init;
  std::call_once(init, [] { openvdb::initialize(); });
  const auto t0 = std::chrono::steady_clock::now();
  const TangentFrame frame = tangent_frame(g);
  const std::vector<float>* fields[3] = {&mean.liquid_per_m, &mean.ice_per_m, cloud_fraction};
  const char* names[3] = {"extinction_liquid", "extinction_ice", "cloud_fraction"};
  const char* units[3] = {"1/m (grid-box mean: in-cloud extinction x cloud fraction)", "1/m (grid-box mean: in-cloud extinction x cloud fraction)",
                          "1 (fraction 0..1)"};

  // The voxels' extent: the local coordinates of the volume's boundary, bottom and top.
  glm::dvec3 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
  for (int j = 0; j < g.lat_deg.count; ++j) {
    for (int i = 0; i < g.lon_deg.count; ++i) {
      for (double alt : {g.alt_m.start, g.alt_m.last()}) {
        const glm::dvec3 d = geo::sphere_to_ecef({g.lat_deg.at(j), g.lon_deg.at(i), alt}, g.earth_radius_m) - frame.origin_ecef;
        const glm::dvec3 local(glm::dot(d, frame.east), glm::dot(d, frame.north), glm::dot(d, frame.up));
        lo = glm::min(lo, local), hi = glm::max(hi, local);
      }
    }
  }
  const glm::ivec3 first(glm::floor(lo / frame.voxel_m)), last(glm::ceil(hi / frame.voxel_m));

  openvdb::GridPtrVec grids;
  openvdb::FloatGrid::Ptr out[3];
  openvdb::FloatGrid::Accessor* acc[3] = {nullptr, nullptr, nullptr};
  std::vector<openvdb::FloatGrid::Accessor> accessors;
  accessors.reserve(3);
  const openvdb::math::Transform::Ptr xform =
      openvdb::math::Transform::createLinearTransform(openvdb::math::Mat4d(
          frame.voxel_m.x, 0.0, 0.0, 0.0, 0.0, frame.voxel_m.y, 0.0, 0.0, 0.0, 0.0, frame.voxel_m.z, 0.0, 0.0, 0.0, 0.0, 1.0));
  char frame_text[256];
  std::snprintf(frame_text, sizeof frame_text,
                "local tangent plane in metres: x east, y north, z up, origin on the sphere (radius %.0f m) at lat %.6f, lon %.6f",
                frame.earth_radius_m, frame.lat0_deg, frame.lon0_deg);
  for (int f = 0; f < 3; ++f) {
    if (!fields[f] || fields[f]->empty()) continue;
    out[f] = openvdb::FloatGrid::create(0.0f);
    out[f]->setName(names[f]);
    out[f]->setGridClass(openvdb::GRID_FOG_VOLUME);
    out[f]->setTransform(xform->copy());
    out[f]->insertMeta("units", openvdb::StringMetadata(units[f]));
    out[f]->insertMeta("frame", openvdb::StringMetadata(frame_text));
    out[f]->insertMeta("origin_lat_deg", openvdb::DoubleMetadata(frame.lat0_deg));
    out[f]->insertMeta("origin_lon_deg", openvdb::DoubleMetadata(frame.lon0_deg));
    out[f]->insertMeta("earth_radius_m", openvdb::DoubleMetadata(frame.earth_radius_m));
    out[f]->insertMeta("valid_utc", openvdb::StringMetadata(valid_utc));
    accessors.push_back(out[f]->getAccessor());
    acc[f] = &accessors.back();
  }
  VdbSummary summary;
  for (int z = first.z; z <= last.z; ++z) {
    for (int y = first.y; y <= last.y; ++y) {
      for (int x = first.x; x <= last.x; ++x) {
        const glm::dvec3 local = glm::dvec3(x, y, z) * frame.voxel_m;
        const geo::Geodetic p = geo::ecef_to_sphere(frame.to_ecef(local), g.earth_radius_m);
        // Longitude into the grid's own range (it may run past 180 across the date line).
        double lon = p.lon_deg;
        while (lon < g.lon_deg.start - 180.0) lon += 360.0;
        while (lon >= g.lon_deg.start + 180.0) lon -= 360.0;
        const double fi = (lon - g.lon_deg.start) / g.lon_deg.step, fj = (p.lat_deg - g.lat_deg.start) / g.lat_deg.step,
                     fk = (p.alt_m - g.alt_m.start) / g.alt_m.step;
        for (int f = 0; f < 3; ++f) {
          if (!acc[f]) continue;
          const double v = trilinear(g, *fields[f], fi, fj, fk);
          if (!(v > 0.0)) continue;  // outside, no data, or nothing there: inactive
          acc[f]->setValue(openvdb::Coord(x, y, z), static_cast<float>(v));
          ++summary.active_voxels[f];
        }
      }
    }
  }
  for (int f = 0; f < 3; ++f) {
    if (out[f]) grids.push_back(out[f]);
  }
  std::ostringstream bytes(std::ios::binary);
  openvdb::io::Stream(bytes).write(grids);
  const std::string data = bytes.str();
  group.write(path, [&](std::FILE* file) {
    if (std::fwrite(data.data(), 1, data.size(), file) != data.size()) throw core::WriteError("short write");
  });
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return summary;
}

}  // namespace cv::vdb
