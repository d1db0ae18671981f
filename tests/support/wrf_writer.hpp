// Writes small WRF files (wrfout layout) for importer tests: the projection's global attributes,
// XLAT/XLONG per mass point (per step for a moving nest), the staggered geopotential PH + PHB on
// flat levels 0, 1, 2, ... km, pressure P + PB of 950 hPa falling 100 hPa a level, T = 0 (300 K
// potential temperature), QCLOUD, and optionally CLDFRA, COSALPHA/SINALPHA and staggered U/V.
// Each test gives the fields as functions of position, so that it knows the values to expect.
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "support/nc_builder.hpp"

namespace cv::test {

struct WrfFile {
  int nx = 8, ny = 6, nz = 3, nt = 1;
  int map_proj = 3;  // 1 Lambert, 2 polar stereographic, 3 Mercator
  double truelat1 = 0.0, truelat2 = 0.0, stand_lon = 0.0, dx = 50000.0;
  // XLAT/XLONG with a Time dimension (a moving nest) rather than one 2-D grid for all steps.
  bool latlon_per_step = false;
  // (lat, lon) in degrees of mass point (i, j) at step t.
  std::function<std::pair<double, double>(int t, int i, int j)> latlon;
  // QCLOUD (kg/kg) at mass level k of point (i, j) at step t.
  std::function<double(int t, int k, int i, int j)> qcloud;
  nc_type qcloud_type = NC_DOUBLE;
  // Absent when empty.
  std::function<double(int t, int k, int i, int j)> cldfra;
  std::function<std::pair<double, double>(int i, int j)> cos_sin_alpha;
  // Staggered grid winds of constant value; absent unless winds is set.
  bool winds = false;
  double u = 10.0, v = 0.0;
};

inline void write_wrf_file(const std::string& path, const WrfFile& s) {
  NcBuilder b(path);
  const auto n = [](int v) { return static_cast<std::size_t>(v); };
  const int dt = b.dim("Time", n(s.nt)), dxd = b.dim("west_east", n(s.nx)), dyd = b.dim("south_north", n(s.ny));
  const int dzd = b.dim("bottom_top", n(s.nz)), dzs = b.dim("bottom_top_stag", n(s.nz + 1));
  int dxs = -1, dys = -1;
  if (s.winds) dxs = b.dim("west_east_stag", n(s.nx + 1)), dys = b.dim("south_north_stag", n(s.ny + 1));
  b.number(NC_GLOBAL, "MAP_PROJ", NC_INT, {static_cast<double>(s.map_proj)});
  b.number(NC_GLOBAL, "TRUELAT1", NC_FLOAT, {s.truelat1});
  b.number(NC_GLOBAL, "TRUELAT2", NC_FLOAT, {s.truelat2});
  b.number(NC_GLOBAL, "STAND_LON", NC_FLOAT, {s.stand_lon});
  b.number(NC_GLOBAL, "DX", NC_FLOAT, {s.dx});
  b.number(NC_GLOBAL, "DY", NC_FLOAT, {s.dx});
  const std::vector<int> d2 = s.latlon_per_step ? std::vector<int>{dt, dyd, dxd} : std::vector<int>{dyd, dxd};
  const int vlat = b.var("XLAT", NC_DOUBLE, d2), vlon = b.var("XLONG", NC_DOUBLE, d2);
  int vca = -1, vsa = -1, vcf = -1, vu = -1, vv = -1;
  if (s.cos_sin_alpha) vca = b.var("COSALPHA", NC_DOUBLE, d2), vsa = b.var("SINALPHA", NC_DOUBLE, d2);
  const int ph = b.var("PH", NC_FLOAT, {dt, dzs, dyd, dxd}), phb = b.var("PHB", NC_FLOAT, {dt, dzs, dyd, dxd});
  const int pp = b.var("P", NC_FLOAT, {dt, dzd, dyd, dxd}), pb = b.var("PB", NC_FLOAT, {dt, dzd, dyd, dxd});
  const int th = b.var("T", NC_FLOAT, {dt, dzd, dyd, dxd}), qc = b.var("QCLOUD", s.qcloud_type, {dt, dzd, dyd, dxd});
  if (s.winds) vu = b.var("U", NC_FLOAT, {dt, dzd, dyd, dxs}), vv = b.var("V", NC_FLOAT, {dt, dzd, dys, dxd});
  if (s.cldfra) vcf = b.var("CLDFRA", NC_FLOAT, {dt, dzd, dyd, dxd});
  const std::size_t n2 = n(s.nx) * n(s.ny);
  std::vector<double> lat, lon, ca, sa, vph, vphb, vp, vpb, vth, vqc, vcfd, wu, wv;
  for (int t = 0; t < (s.latlon_per_step ? s.nt : 1); ++t) {
    for (int j = 0; j < s.ny; ++j) {
      for (int i = 0; i < s.nx; ++i) {
        const auto [la, lo] = s.latlon(t, i, j);
        lat.push_back(la);
        lon.push_back(lo);
        if (s.cos_sin_alpha) {
          const auto [c, si] = s.cos_sin_alpha(i, j);
          ca.push_back(c);
          sa.push_back(si);
        }
      }
    }
  }
  for (int t = 0; t < s.nt; ++t) {
    for (int k = 0; k <= s.nz; ++k) vph.insert(vph.end(), n2, 0.0), vphb.insert(vphb.end(), n2, 9.81 * 1000.0 * k);
    for (int k = 0; k < s.nz; ++k) {
      vp.insert(vp.end(), n2, 0.0);
      vpb.insert(vpb.end(), n2, 95000.0 - 10000.0 * k);
      vth.insert(vth.end(), n2, 0.0);
      for (int j = 0; j < s.ny; ++j) {
        for (int i = 0; i < s.nx; ++i) {
          vqc.push_back(s.qcloud(t, k, i, j));
          if (s.cldfra) vcfd.push_back(s.cldfra(t, k, i, j));
        }
      }
      if (s.winds) wu.insert(wu.end(), n(s.nx + 1) * n(s.ny), s.u), wv.insert(wv.end(), n(s.nx) * n(s.ny + 1), s.v);
    }
  }
  b.put(vlat, lat);
  b.put(vlon, lon);
  if (s.cos_sin_alpha) b.put(vca, ca), b.put(vsa, sa);
  b.put(ph, vph);
  b.put(phb, vphb);
  b.put(pp, vp);
  b.put(pb, vpb);
  b.put(th, vth);
  b.put(qc, vqc);
  if (s.winds) b.put(vu, wu), b.put(vv, wv);
  if (s.cldfra) b.put(vcf, vcfd);
  b.close();
}

}  // namespace cv::test
