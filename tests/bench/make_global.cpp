// Writes the import benchmark's input: a global 0.25-degree, 37-level, 4-step ERA5-style file
// (int16 packed, CF attributes), one (time, level) slab at a time so the writer itself stays small.
// Fields are smooth analytic patterns: the benchmark measures reading and converting, not weather.
#include <netcdf.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace {
void check(int s, const char* what) {
  if (s != NC_NOERR) {
    std::fprintf(stderr, "make_global: %s: %s\n", what, nc_strerror(s));
    std::exit(1);
  }
}
double isa_height(double p) {
  return p >= 22632.06 ? 288.15 / 0.0065 * (1 - std::pow(p / 101325.0, 287.05 * 0.0065 / 9.80665))
                       : 11000.0 + 287.05 * 216.65 / 9.80665 * std::log(22632.06 / p);
}
}  // namespace

int main(int argc, char** argv) {
  const char* usage =
      "usage: make_global OUT.nc\n"
      "writes the import benchmark's global file: 0.25 degree (1440 x 721), 37 pressure levels, 4 steps,\n"
      "8 packed int16 variables (about 2.5 GB; docs/BENCHMARKS.md)\n";
  if (argc == 2 && (std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h")) {
    std::fputs(usage, stdout);
    return 0;
  }
  if (argc != 2 || argv[1][0] == '-') {
    std::fprintf(stderr, "%s", usage);
    return 2;
  }
  const int nx = 1440, ny = 721, nz = 37, nt = 4;
  const double levels[nz] = {1, 2, 3, 5, 7, 10, 20, 30, 50, 70, 100, 125, 150, 175, 200, 225, 250, 300, 350,
                             400, 450, 500, 550, 600, 650, 700, 750, 775, 800, 825, 850, 875, 900, 925, 950, 975, 1000};
  const std::string tmp = std::string(argv[1]) + ".tmp";
  int nc, dx, dy, dz, dt;
  check(nc_create(tmp.c_str(), NC_CLOBBER | NC_64BIT_OFFSET, &nc), "create");
  check(nc_def_dim(nc, "longitude", nx, &dx), "dim");
  check(nc_def_dim(nc, "latitude", ny, &dy), "dim");
  check(nc_def_dim(nc, "level", nz, &dz), "dim");
  check(nc_def_dim(nc, "time", NC_UNLIMITED, &dt), "dim");
  int vx, vy, vz, vt;
  check(nc_def_var(nc, "longitude", NC_FLOAT, 1, &dx, &vx), "var");
  check(nc_def_var(nc, "latitude", NC_FLOAT, 1, &dy, &vy), "var");
  check(nc_def_var(nc, "level", NC_INT, 1, &dz, &vz), "var");
  check(nc_def_var(nc, "time", NC_INT, 1, &dt, &vt), "var");
  nc_put_att_text(nc, vx, "units", 12, "degrees_east");
  nc_put_att_text(nc, vy, "units", 13, "degrees_north");
  nc_put_att_text(nc, vz, "units", 9, "millibars");
  const std::string tu = "hours since 1900-01-01 00:00:00.0";
  nc_put_att_text(nc, vt, "units", tu.size(), tu.c_str());
  struct Var {
    const char* name;
    const char* units;
    double lo, hi;
    int id;
  };
  std::vector<Var> vars = {{"cc", "(0 - 1)", 0, 1, 0},       {"clwc", "kg kg**-1", 0, 1e-3, 0}, {"ciwc", "kg kg**-1", 0, 5e-4, 0},
                           {"z", "m**2 s**-2", -1000, 5e5, 0}, {"t", "K", 180, 320, 0},           {"q", "kg kg**-1", 0, 0.03, 0},
                           {"u", "m s**-1", -80, 80, 0},      {"v", "m s**-1", -80, 80, 0}};
  const int dims[4] = {dt, dz, dy, dx};
  for (auto& v : vars) {
    check(nc_def_var(nc, v.name, NC_SHORT, 4, dims, &v.id), v.name);
    nc_put_att_text(nc, v.id, "units", std::string(v.units).size(), v.units);
    const double scale = (v.hi - v.lo) / 65532.0, offset = 0.5 * (v.hi + v.lo);
    const short fill = -32767;
    nc_put_att_double(nc, v.id, "scale_factor", NC_DOUBLE, 1, &scale);
    nc_put_att_double(nc, v.id, "add_offset", NC_DOUBLE, 1, &offset);
    nc_put_att_short(nc, v.id, "_FillValue", NC_SHORT, 1, &fill);
  }
  check(nc_enddef(nc), "enddef");
  std::vector<float> lon(nx), lat(ny);
  for (int i = 0; i < nx; ++i) lon[i] = 0.25f * i;
  for (int j = 0; j < ny; ++j) lat[j] = 90.0f - 0.25f * j;
  std::vector<int> lev(levels, levels + nz);
  nc_put_var_float(nc, vx, lon.data());
  nc_put_var_float(nc, vy, lat.data());
  nc_put_var_int(nc, vz, lev.data());
  std::vector<short> slab(static_cast<std::size_t>(nx) * ny);
  for (int t = 0; t < nt; ++t) {
    const int hours = 1086432 + 6 * t;  // 2024-01-01
    const std::size_t ts = t;
    nc_put_var1_int(nc, vt, &ts, &hours);
    std::printf("make_global: time step %d/%d\n", t + 1, nt);
    std::fflush(stdout);
    for (int k = 0; k < nz; ++k) {
      const double p = levels[k] * 100.0, h = isa_height(p);
      for (const auto& v : vars) {
        const double scale = (v.hi - v.lo) / 65532.0, offset = 0.5 * (v.hi + v.lo);
        for (int j = 0; j < ny; ++j) {
          const double la = lat[j] * 3.14159265358979 / 180.0;
          for (int i = 0; i < nx; ++i) {
            const double lo = lon[i] * 3.14159265358979 / 180.0 + 0.2 * t;
            const double wave = std::sin(3 * lo) * std::cos(2 * la);
            const double cloudy = std::max(0.0, wave) * (h < 12000 ? 1.0 : 0.0);
            double x = 0;
            const std::string n = v.name;
            if (n == "cc") x = cloudy;
            else if (n == "clwc") x = h < 6000 ? 2e-4 * cloudy : 0.0;
            else if (n == "ciwc") x = h > 4000 ? 5e-5 * cloudy : 0.0;
            else if (n == "z") x = 9.80665 * (h + 100.0 * wave);
            else if (n == "t") x = (h < 11000 ? 288.15 - 0.0065 * h : 216.65) - 20 * std::sin(la) * std::sin(la);
            else if (n == "q") x = 0.01 * std::exp(-h / 2500.0) * std::cos(la) * std::cos(la);
            else if (n == "u") x = 30 * std::cos(la) + 10 * wave;
            else x = 10 * std::sin(2 * lo) * std::cos(la);
            slab[static_cast<std::size_t>(j) * nx + i] = static_cast<short>(std::lround((x - offset) / scale));
          }
        }
        const std::size_t start[4] = {ts, static_cast<std::size_t>(k), 0, 0}, count[4] = {1, 1, static_cast<std::size_t>(ny), static_cast<std::size_t>(nx)};
        check(nc_put_vara_short(nc, v.id, start, count, slab.data()), v.name);
      }
    }
  }
  check(nc_close(nc), "close");
  std::rename(tmp.c_str(), argv[1]);
  return 0;
}
