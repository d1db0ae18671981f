// .cvvol and .vti writers.
#include "volume/volume_io.hpp"

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <unistd.h>

namespace cv::core {
namespace {

// A failure of the file itself (disk full, I/O error), as opposed to one of the data being written.
struct WriteFailure : std::runtime_error {
  using std::runtime_error::runtime_error;
};

void put(std::FILE* f, const void* p, std::size_t n) {
  if (n && std::fwrite(p, 1, n, f) != n) throw WriteFailure(std::string("write failed (") + std::strerror(errno) + ")");
}
void put(std::FILE* f, const std::string& s) { put(f, s.data(), s.size()); }

std::string axis_json(const RegularAxis& a) {
  char buf[128];
  std::snprintf(buf, sizeof buf, "{\"start\": %.17g, \"step\": %.17g, \"count\": %d}", a.start, a.step, a.count);
  return buf;
}

using MapArrays = std::array<std::pair<const char*, const std::vector<float>*>, 7>;
MapArrays map_arrays(const Maps2D& m) {
  return {{{"cloud_cover", &m.cloud_cover}, {"cloud_base_m", &m.cloud_base_m}, {"cloud_top_m", &m.cloud_top_m},
           {"optical_depth", &m.optical_depth}, {"low_cover", &m.low_cover}, {"mid_cover", &m.mid_cover},
           {"high_cover", &m.high_cover}}};
}
}  // namespace

void write_file_atomically(const std::string& path, const std::function<void(std::FILE*)>& write) {
  const std::string tmp = path + ".tmp-" + std::to_string(::getpid());
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) throw std::runtime_error(path + ": cannot create (" + std::strerror(errno) + ")");
  try {
    write(f);
    if (std::fflush(f) != 0 || ::fsync(::fileno(f)) != 0) throw WriteFailure(std::string("flush failed (") + std::strerror(errno) + ")");
  } catch (const WriteFailure& e) {
    std::fclose(f);
    std::remove(tmp.c_str());
    throw std::runtime_error(path + ": " + e.what());
  } catch (...) {
    // Anything else (bad data found while loading a step) leaves no file and keeps its own message.
    std::fclose(f);
    std::remove(tmp.c_str());
    throw;
  }
  std::fclose(f);
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::remove(tmp.c_str());
    throw std::runtime_error(path + ": cannot rename into place (" + ec.message() + ")");
  }
}

void write_cvvol(const std::string& path, CloudVolume& v, const std::function<void(std::size_t, std::size_t)>& progress) {
  std::string fields = "[", maps = "[", times = "[";
  for (int i = 0; i < kFieldCount; ++i) {
    if (v.has_field[static_cast<std::size_t>(i)]) {
      fields += std::string(fields.size() > 1 ? ", " : "") + json_quote(field_name(static_cast<Field>(i)));
    }
  }
  const Maps2D none;
  for (const auto& [name, arr] : map_arrays(none)) maps += std::string(maps.size() > 1 ? ", " : "") + json_quote(name);
  for (std::size_t t = 0; t < v.times.size(); ++t) {
    times += std::string(t ? ", " : "") + "{\"iso_utc\": " + json_quote(v.times[t].iso_utc) +
             ", \"unix_s\": " + std::to_string(v.times[t].unix_s) + "}";
  }
  const std::string header = "{\"format\": \"cvvol\", \"version\": 1,\n \"grid\": {\"lon_deg\": " + axis_json(v.grid.lon_deg) +
                             ", \"lat_deg\": " + axis_json(v.grid.lat_deg) + ", \"alt_m\": " + axis_json(v.grid.alt_m) +
                             ", \"earth_radius_m\": " + std::to_string(v.grid.earth_radius_m) + "},\n \"times\": " + times +
                             "],\n \"fields\": " + fields + "],\n \"maps\": " + maps +
                             "],\n \"layout\": \"float32 little-endian; per time step, each field (lon fastest, then lat, "
                             "then alt) then each map (lon fastest, then lat); NaN = no data\"}\n";
  write_file_atomically(path, [&](std::FILE* f) {
    put(f, "CVVOL01\n");
    const std::uint64_t len = header.size();
    put(f, &len, sizeof len);
    put(f, header);
    for (std::size_t t = 0; t < v.times.size(); ++t) {
      if (progress) progress(t, v.times.size());
      const TimeStepData& d = v.step(t);
      for (int i = 0; i < kFieldCount; ++i) {
        if (!v.has_field[static_cast<std::size_t>(i)]) continue;
        const auto& a = d.fields[static_cast<std::size_t>(i)];
        if (a.size() != v.grid.points()) throw std::runtime_error(std::string("field ") + field_name(static_cast<Field>(i)) + " has the wrong size");
        put(f, a.data(), a.size() * sizeof(float));
      }
      for (const auto& [name, arr] : map_arrays(d.maps)) put(f, arr->data(), arr->size() * sizeof(float));
    }
  });
}

void write_vti(const std::string& path, const VolumeGrid& g, const TimeStepData& d, const std::array<bool, kFieldCount>& has) {
  // Altitude in km so the box keeps a sensible aspect next to degrees in ParaView.
  char head[512];
  std::snprintf(head, sizeof head,
                "<?xml version=\"1.0\"?>\n<VTKFile type=\"ImageData\" version=\"1.0\" byte_order=\"LittleEndian\" "
                "header_type=\"UInt64\">\n<ImageData WholeExtent=\"0 %d 0 %d 0 %d\" Origin=\"%.10g %.10g %.10g\" "
                "Spacing=\"%.10g %.10g %.10g\">\n<Piece Extent=\"0 %d 0 %d 0 %d\">\n<PointData>\n",
                g.lon_deg.count - 1, g.lat_deg.count - 1, g.alt_m.count - 1, g.lon_deg.start, g.lat_deg.start,
                g.alt_m.start / 1000.0, g.lon_deg.step, g.lat_deg.step, g.alt_m.step / 1000.0, g.lon_deg.count - 1,
                g.lat_deg.count - 1, g.alt_m.count - 1);
  std::string xml = head;
  std::vector<const std::vector<float>*> arrays;
  std::uint64_t offset = 0;
  for (int i = 0; i < kFieldCount; ++i) {
    if (!has[static_cast<std::size_t>(i)]) continue;
    const auto& a = d.fields[static_cast<std::size_t>(i)];
    xml += std::string("<DataArray type=\"Float32\" Name=\"") + field_name(static_cast<Field>(i)) +
           "\" format=\"appended\" offset=\"" + std::to_string(offset) + "\"/>\n";
    arrays.push_back(&a);
    offset += sizeof(std::uint64_t) + a.size() * sizeof(float);
  }
  xml += "</PointData>\n</Piece>\n</ImageData>\n<AppendedData encoding=\"raw\">\n_";
  write_file_atomically(path, [&](std::FILE* f) {
    put(f, xml);
    for (const auto* a : arrays) {
      const std::uint64_t n = a->size() * sizeof(float);
      put(f, &n, sizeof n);
      put(f, a->data(), n);
    }
    put(f, "\n</AppendedData>\n</VTKFile>\n");
  });
}

}  // namespace cv::core
