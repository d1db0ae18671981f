// The import benchmark's baseline: reads the same variables the importer uses, one time step at a
// time, with plain netCDF-C calls into int16 buffers and no conversion.
#include <netcdf.h>

#include <chrono>
#include <cstdio>
#include <vector>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: plain_read FILE.nc\n");
    return 2;
  }
  const auto t0 = std::chrono::steady_clock::now();
  int nc;
  if (nc_open(argv[1], NC_NOWRITE, &nc) != NC_NOERR) return 1;
  int dt, dz, dy, dx;
  size_t nt, nz, ny, nx;
  nc_inq_dimid(nc, "time", &dt), nc_inq_dimlen(nc, dt, &nt);
  nc_inq_dimid(nc, "level", &dz), nc_inq_dimlen(nc, dz, &nz);
  nc_inq_dimid(nc, "latitude", &dy), nc_inq_dimlen(nc, dy, &ny);
  nc_inq_dimid(nc, "longitude", &dx), nc_inq_dimlen(nc, dx, &nx);
  std::vector<short> buf(nz * ny * nx);
  long long sum = 0;
  for (size_t t = 0; t < nt; ++t) {
    for (const char* name : {"cc", "clwc", "ciwc", "z", "t", "q", "u", "v"}) {
      int v;
      if (nc_inq_varid(nc, name, &v) != NC_NOERR) return 1;
      const size_t start[4] = {t, 0, 0, 0}, count[4] = {1, nz, ny, nx};
      if (nc_get_vara_short(nc, v, start, count, buf.data()) != NC_NOERR) return 1;
      sum += buf[buf.size() / 2];
    }
  }
  nc_close(nc);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("plain_read: %zu steps x 8 variables x %zu values in %.2f s (checksum %lld)\n", nt, nz * ny * nx, s, sum);
  return 0;
}
