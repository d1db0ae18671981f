// Writes the fuzzers' seed corpus from real files (never committed: generated where it runs):
//   make_seeds OUT_DIR SCENE_OR_NETCDF...
// Each NetCDF file is cropped to a few points per axis (2 time steps; staggered WRF axes one
// longer than their mass axes; text lengths kept) and written as CDF-5 (netCDF classic with
// 64-bit types) to OUT_DIR/netcdf; each crop that imports is written as a .cvvol to OUT_DIR/cvvol;
// each .json given is copied to OUT_DIR/scene, with the default scene and each crop's saved scene.
#include <netcdf.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "importer.hpp"
#include "scene/quality.hpp"
#include "scene/scene_json.hpp"
#include "volume/volume_io.hpp"

namespace fs = std::filesystem;

namespace {

void check(int status, const std::string& what) {
  if (status != NC_NOERR) throw std::runtime_error(what + ": " + nc_strerror(status));
}

std::size_t cropped(const std::string& name, std::size_t len) {
  if (name.rfind("string", 0) == 0 || name == "DateStrLen") return len;  // text lengths
  const bool stag = name.size() > 5 && name.compare(name.size() - 5, 5, "_stag") == 0;
  const std::size_t time = name == "Time" || name == "time" ? 2 : 6;
  return std::min(len, stag ? time + 1 : time);
}

// format: NC_64BIT_DATA (CDF-5) or NC_NETCDF4 (HDF5; its variables deflated, so the mutations reach
// the HDF5 filter pipeline too).
void crop(const std::string& in, const std::string& out, int format) {
  int src = -1, dst = -1;
  check(nc_open(in.c_str(), NC_NOWRITE, &src), in);
  check(nc_create(out.c_str(), NC_CLOBBER | format, &dst), out);
  int ndims = 0, nvars = 0, natts = 0, unlim = -1;
  check(nc_inq(src, &ndims, &nvars, &natts, &unlim), in);
  std::vector<std::size_t> len(static_cast<std::size_t>(ndims));
  for (int d = 0; d < ndims; ++d) {
    char name[NC_MAX_NAME + 1];
    std::size_t l = 0;
    check(nc_inq_dim(src, d, name, &l), "dim");
    len[static_cast<std::size_t>(d)] = cropped(name, l);
    int id;
    check(nc_def_dim(dst, name, len[static_cast<std::size_t>(d)], &id), "def dim");
  }
  auto copy_atts = [&](int sv, int dv, int n) {
    for (int a = 0; a < n; ++a) {
      char name[NC_MAX_NAME + 1];
      check(nc_inq_attname(src, sv, a, name), "att");
      nc_type t;
      check(nc_inq_atttype(src, sv, name, &t), "att type");
      if (t == NC_STRING) continue;  // not in CDF-5
      check(nc_copy_att(src, sv, name, dst, dv), std::string("copy att ") + name);
    }
  };
  copy_atts(NC_GLOBAL, NC_GLOBAL, natts);
  std::vector<int> keep;
  for (int v = 0; v < nvars; ++v) {
    char name[NC_MAX_NAME + 1];
    nc_type t;
    int nd = 0, na = 0, dims[NC_MAX_VAR_DIMS];
    check(nc_inq_var(src, v, name, &t, &nd, dims, &na), "var");
    if (t == NC_STRING || t > NC_STRING) continue;
    int id;
    check(nc_def_var(dst, name, t, nd, dims, &id), std::string("def var ") + name);
    if (format == NC_NETCDF4 && nd > 0) check(nc_def_var_deflate(dst, id, 1, 1, 1), std::string("deflate ") + name);
    copy_atts(v, id, na);
    keep.push_back(v);
  }
  check(nc_enddef(dst), "enddef");
  for (int v : keep) {
    int nd = 0, dims[NC_MAX_VAR_DIMS];
    nc_type t;
    check(nc_inq_varndims(src, v, &nd), "ndims");
    check(nc_inq_vardimid(src, v, dims), "dimids");
    check(nc_inq_vartype(src, v, &t), "type");
    std::vector<std::size_t> start(static_cast<std::size_t>(nd), 0), count(static_cast<std::size_t>(nd));
    std::size_t n = 1;
    for (int d = 0; d < nd; ++d) n *= count[static_cast<std::size_t>(d)] = len[static_cast<std::size_t>(dims[d])];
    std::size_t bytes = 8;
    check(nc_inq_type(src, t, nullptr, &bytes), "type size");
    std::vector<unsigned char> buf(n * bytes + 1);
    char name[NC_MAX_NAME + 1];
    nc_inq_varname(src, v, name);
    check(nc_get_vara(src, v, start.data(), count.data(), buf.data()), std::string("read ") + name);
    int dv;
    check(nc_inq_varid(dst, name, &dv), "varid");
    check(nc_put_vara(dst, dv, start.data(), count.data(), buf.data()), std::string("write ") + name);
  }
  nc_close(src);
  check(nc_close(dst), "close " + out);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: make_seeds OUT_DIR FILE.nc|SCENE.json...\n");
    return 2;
  }
  const fs::path out = argv[1];
  for (const char* sub : {"netcdf", "netcdf4", "cvvol", "scene"}) fs::create_directories(out / sub);
  int seeds = 0;
  auto save = [&](const fs::path& p, const std::string& text) {
    std::ofstream(p, std::ios::binary) << text;
    ++seeds;
  };
  cv::core::Scene base;
  cv::core::apply_quality("default", base.render);
  save(out / "scene" / "default.json", cv::core::scene_to_json(base));
  for (int i = 2; i < argc; ++i) {
    const fs::path in = argv[i];
    try {
      if (in.extension() == ".json") {
        std::ifstream f(in, std::ios::binary);
        std::ostringstream s;
        s << f.rdbuf();
        save(out / "scene" / in.filename(), s.str());
        continue;
      }
      const fs::path nc = out / "netcdf" / (in.stem().string() + ".cdf5.nc");
      crop(in.string(), nc.string(), NC_64BIT_DATA);
      ++seeds;
      crop(in.string(), (out / "netcdf4" / (in.stem().string() + ".nc4.nc")).string(), NC_NETCDF4);
      ++seeds;
      cv::core::CloudVolume v = cv::importers::import_file(nc.string());
      cv::core::write_cvvol((out / "cvvol" / (in.stem().string() + ".cvvol")).string(), v);
      ++seeds;
      cv::core::Scene s = base;
      s.data.path = nc.string();
      save(out / "scene" / (in.stem().string() + ".json"), cv::core::scene_to_json(s));
      std::printf("%s: cropped, imported %d x %d x %d\n", in.c_str(), v.grid.lon_deg.count, v.grid.lat_deg.count, v.grid.alt_m.count);
    } catch (const std::exception& e) {
      std::printf("%s: %s (kept what was written)\n", in.c_str(), e.what());
    }
  }
  std::printf("%d seeds under %s\n", seeds, out.c_str());
  return 0;
}
