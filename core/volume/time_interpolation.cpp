// Interpolation of the medium between forecast steps: nearest, linear, and semi-Lagrangian advection.
#include "volume/time_interpolation.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <thread>

namespace cv::core {

const char* time_interpolation_name(TimeInterpolation m) {
  switch (m) {
    case TimeInterpolation::Auto: return "auto";
    case TimeInterpolation::Nearest: return "nearest";
    case TimeInterpolation::Linear: return "linear";
    case TimeInterpolation::Advected: return "advected";
  }
  return "auto";
}

bool parse_time_interpolation(const std::string& text, TimeInterpolation& out) {
  for (TimeInterpolation m : {TimeInterpolation::Auto, TimeInterpolation::Nearest, TimeInterpolation::Linear, TimeInterpolation::Advected}) {
    if (text == time_interpolation_name(m)) {
      out = m;
      return true;
    }
  }
  return false;
}

StepWinds step_winds(const TimeStepData& data) {
  return {data[Field::WindU], data[Field::WindV], data[Field::WindW]};
}

namespace {

constexpr double kRadPerDeg = 3.14159265358979323846 / 180.0;

// Index-space trilinear sampling with the grid's edge rules: longitude repeats on a grid that wraps,
// every other axis clamps to its edge nodes (a parcel from outside a regional grid brings the edge's
// value, the usual open boundary of a semi-Lagrangian scheme).
struct IndexSampler {
  int nx, ny, nz;
  bool wraps;

  static void axis_clamped(double x, int n, int& i0, int& i1, double& t) {
    if (n <= 1) {
      i0 = i1 = 0, t = 0.0;
      return;
    }
    x = std::clamp(x, 0.0, double(n - 1));
    i0 = std::min(static_cast<int>(std::floor(x)), n - 2);
    i1 = i0 + 1;
    t = x - i0;
  }
  void axis_x(double x, int& i0, int& i1, double& t) const {
    if (!wraps) return axis_clamped(x, nx, i0, i1, t);
    x = std::fmod(x, double(nx));
    if (x < 0.0) x += nx;
    i0 = std::min(static_cast<int>(std::floor(x)), nx - 1);
    i1 = (i0 + 1) % nx;
    t = std::clamp(x - i0, 0.0, 1.0);
  }
  template <class F>
  void corners(double x, double y, double z, F&& visit) const {
    int i0, i1, j0, j1, k0, k1;
    double tx, ty, tz;
    axis_x(x, i0, i1, tx);
    axis_clamped(y, ny, j0, j1, ty);
    axis_clamped(z, nz, k0, k1, tz);
    const auto at = [&](int i, int j, int k) { return (std::size_t(k) * std::size_t(ny) + std::size_t(j)) * std::size_t(nx) + std::size_t(i); };
    visit(at(i0, j0, k0), (1 - tx) * (1 - ty) * (1 - tz));
    visit(at(i1, j0, k0), tx * (1 - ty) * (1 - tz));
    visit(at(i0, j1, k0), (1 - tx) * ty * (1 - tz));
    visit(at(i1, j1, k0), tx * ty * (1 - tz));
    visit(at(i0, j0, k1), (1 - tx) * (1 - ty) * tz);
    visit(at(i1, j0, k1), tx * (1 - ty) * tz);
    visit(at(i0, j1, k1), (1 - tx) * ty * tz);
    visit(at(i1, j1, k1), tx * ty * tz);
  }
  double sample(const std::vector<float>& f, double x, double y, double z) const {
    double s = 0.0;
    corners(x, y, z, [&](std::size_t n, double w) { s += w * f[n]; });
    return s;
  }
};

// A step's winds in grid cells per second along (longitude, latitude, altitude) at every node;
// no data and non-finite values count as calm.
struct CellWinds {
  std::vector<double> cx, cy, cz;
  double max_cells_per_s = 0.0;
};

CellWinds cell_winds(const VolumeGrid& g, const StepWinds& w) {
  CellWinds c;
  const std::size_t n = g.points();
  c.cx.assign(n, 0.0), c.cy.assign(n, 0.0), c.cz.assign(n, 0.0);
  const double dlon = std::abs(g.lon_deg.step) * kRadPerDeg, dlat = std::abs(g.lat_deg.step) * kRadPerDeg;
  const double dz = std::abs(g.alt_m.step);
  const auto ok = [](float v) { return std::isfinite(v) ? double(v) : 0.0; };
  for (int k = 0; k < g.alt_m.count; ++k) {
    const double r = g.earth_radius_m + g.alt_m.at(k);
    for (int j = 0; j < g.lat_deg.count; ++j) {
      // Near a pole the meridians converge: bounded so a polar row's zonal speed stays finite.
      const double coslat = std::max(std::cos(g.lat_deg.at(j) * kRadPerDeg), 1e-3);
      for (int i = 0; i < g.lon_deg.count; ++i) {
        const std::size_t p = g.index(i, j, k);
        if (w.horizontal()) {
          if (g.lon_deg.count > 1 && dlon > 0) c.cx[p] = ok(w.u[p]) / (r * coslat * dlon) * (g.lon_deg.step < 0 ? -1.0 : 1.0);
          if (g.lat_deg.count > 1 && dlat > 0) c.cy[p] = ok(w.v[p]) / (r * dlat) * (g.lat_deg.step < 0 ? -1.0 : 1.0);
        }
        if (!w.w.empty() && g.alt_m.count > 1 && dz > 0) c.cz[p] = ok(w.w[p]) / dz;
        c.max_cells_per_s = std::max({c.max_cells_per_s, std::abs(c.cx[p]), std::abs(c.cy[p]), std::abs(c.cz[p])});
      }
    }
  }
  return c;
}

double area_weighted_total(const VolumeGrid& g, const std::vector<float>& f) {
  double total = 0.0;
  for (int k = 0; k < g.alt_m.count; ++k)
    for (int j = 0; j < g.lat_deg.count; ++j) {
      const double w = std::max(std::cos(g.lat_deg.at(j) * kRadPerDeg), 0.0);
      for (int i = 0; i < g.lon_deg.count; ++i) total += w * f[g.index(i, j, k)];
    }
  return total;
}

// What the warp may not do to a carried field: raise the area-weighted total optical depth above the
// source step's, or any column's optical depth above the source's thickest column. Returns the
// global factor applied (<= 1).
double conserve(const VolumeGrid& g, const std::vector<float>& source, std::vector<float>& carried) {
  const double src = area_weighted_total(g, source), got = area_weighted_total(g, carried);
  double factor = 1.0;
  if (got > src && got > 0.0) {
    factor = src / got;
    for (float& v : carried) v = static_cast<float>(v * factor);
  }
  const int nx = g.lon_deg.count, ny = g.lat_deg.count, nz = g.alt_m.count;
  double src_max = 0.0;
  std::vector<double> col(std::size_t(nx) * std::size_t(ny), 0.0);
  for (int k = 0; k < nz; ++k)
    for (std::size_t c = 0; c < col.size(); ++c) col[c] += source[std::size_t(k) * col.size() + c];
  for (double c : col) src_max = std::max(src_max, c);
  std::fill(col.begin(), col.end(), 0.0);
  for (int k = 0; k < nz; ++k)
    for (std::size_t c = 0; c < col.size(); ++c) col[c] += carried[std::size_t(k) * col.size() + c];
  for (std::size_t c = 0; c < col.size(); ++c) {
    if (!(col[c] > src_max)) continue;
    const double f = src_max / col[c];
    for (int k = 0; k < nz; ++k) carried[std::size_t(k) * col.size() + c] = static_cast<float>(carried[std::size_t(k) * col.size() + c] * f);
  }
  return factor;
}

// Each field of `fields` carried along the same trajectories: one trajectory per node, sampled in
// every field. Levels are shared out among threads (each node is independent, so the result does
// not depend on how many).
std::vector<std::vector<float>> advect_with(const VolumeGrid& g, const std::vector<const std::vector<float>*>& fields,
                                            const CellWinds& c0, const CellWinds& c1, double gap_s, double fraction, int from,
                                            int substeps) {
  const IndexSampler s{g.lon_deg.count, g.lat_deg.count, g.alt_m.count, g.wraps_lon()};
  // The winds at a point and a fraction of the gap: trilinear in space, linear in time.
  const auto wind = [&](double x, double y, double z, double t, double& vx, double& vy, double& vz) {
    vx = vy = vz = 0.0;
    s.corners(x, y, z, [&](std::size_t n, double w) {
      vx += w * ((1 - t) * c0.cx[n] + t * c1.cx[n]);
      vy += w * ((1 - t) * c0.cy[n] + t * c1.cy[n]);
      vz += w * ((1 - t) * c0.cz[n] + t * c1.cz[n]);
    });
  };
  // From the instant back to the earlier step (from 0) or on to the later one (from 1).
  const double span = from == 0 ? -fraction : 1.0 - fraction;  // in fractions of the gap, signed
  const double dt = span / substeps;                          // per sub-step, fractions of the gap
  const double dt_s = dt * gap_s;
  std::vector<std::vector<float>> out(fields.size(), std::vector<float>(g.points(), 0.0f));
  const auto levels = [&](int k_begin, int k_end) {
    for (int k = k_begin; k < k_end; ++k)
      for (int j = 0; j < g.lat_deg.count; ++j)
        for (int i = 0; i < g.lon_deg.count; ++i) {
          double x = i, y = j, z = k, t = fraction;
          for (int n = 0; n < substeps; ++n) {  // the midpoint rule along the trajectory
            double ax, ay, az, bx, by, bz;
            wind(x, y, z, t, ax, ay, az);
            wind(x + 0.5 * dt_s * ax, y + 0.5 * dt_s * ay, z + 0.5 * dt_s * az, t + 0.5 * dt, bx, by, bz);
            x += dt_s * bx, y += dt_s * by, z += dt_s * bz;
            if (!g.wraps_lon()) x = std::clamp(x, 0.0, double(g.lon_deg.count - 1));
            y = std::clamp(y, 0.0, double(g.lat_deg.count - 1));
            z = std::clamp(z, 0.0, double(g.alt_m.count - 1));
            t += dt;
          }
          // A convex combination of non-negative values: never negative, never above the source's largest.
          for (std::size_t f = 0; f < fields.size(); ++f) {
            out[f][g.index(i, j, k)] = static_cast<float>(std::max(0.0, s.sample(*fields[f], x, y, z)));
          }
        }
  };
  const int nz = g.alt_m.count;
  const int threads = std::clamp(static_cast<int>(std::thread::hardware_concurrency()), 1, std::max(1, std::min(nz, 16)));
  if (threads <= 1 || g.points() < 65536) {
    levels(0, nz);
  } else {
    std::vector<std::thread> pool;
    for (int t = 0; t < threads; ++t) pool.emplace_back(levels, nz * t / threads, nz * (t + 1) / threads);
    for (std::thread& th : pool) th.join();
  }
  return out;
}

int substeps_for(double max_cells_per_s, double gap_s, double span) {
  const double cells = max_cells_per_s * gap_s * span;
  if (!(cells > 1.0)) return 1;
  return static_cast<int>(std::min<double>(kMaxAdvectionSubsteps, std::ceil(cells)));
}

std::vector<float> blend(const std::vector<float>& a, const std::vector<float>& b, double f) {
  if (a.empty() && b.empty()) return {};
  const std::size_t n = std::max(a.size(), b.size());
  std::vector<float> out(n);
  for (std::size_t p = 0; p < n; ++p) {
    const double va = a.empty() ? 0.0 : a[p], vb = b.empty() ? 0.0 : b[p];
    out[p] = static_cast<float>(std::max(0.0, (1.0 - f) * va + f * vb));
  }
  return out;
}

}  // namespace

std::vector<float> advect_field(const VolumeGrid& grid, const std::vector<float>& field, const StepWinds& w0,
                                const StepWinds& w1, double gap_s, double fraction, int from, int* substeps,
                                double* max_courant) {
  const CellWinds c0 = cell_winds(grid, w0), c1 = cell_winds(grid, w1);
  const double cmax = std::max(c0.max_cells_per_s, c1.max_cells_per_s);
  const int n = substeps_for(cmax, gap_s, from == 0 ? fraction : 1.0 - fraction);
  if (substeps) *substeps = n;
  if (max_courant) *max_courant = cmax * gap_s;
  return std::move(advect_with(grid, {&field}, c0, c1, gap_s, fraction, from, n)[0]);
}

GridMeanExtinction interpolate_extinction(const VolumeGrid& grid, const GridMeanExtinction& e0, const GridMeanExtinction& e1,
                                          const StepWinds& w0, const StepWinds& w1, double gap_s, double fraction,
                                          TimeInterpolation mode, TimeInterpolationReport* report) {
  const auto t0 = std::chrono::steady_clock::now();
  TimeInterpolationReport local;
  TimeInterpolationReport& r = report ? *report : local;
  r = TimeInterpolationReport{};
  fraction = std::clamp(std::isfinite(fraction) ? fraction : 0.0, 0.0, 1.0);
  const bool winds = w0.horizontal() && w1.horizontal();
  if (mode == TimeInterpolation::Auto) mode = winds ? TimeInterpolation::Advected : TimeInterpolation::Linear;
  if (mode == TimeInterpolation::Advected && !winds) {
    r.warning = "the file has no horizontal winds at both steps: advected interpolation fell back to linear";
    mode = TimeInterpolation::Linear;
  }
  r.used = mode;
  GridMeanExtinction out;
  if (mode == TimeInterpolation::Nearest || fraction == 0.0 || fraction == 1.0) {
    out = (mode == TimeInterpolation::Nearest ? fraction < 0.5 : fraction == 0.0) ? e0 : e1;
  } else if (mode == TimeInterpolation::Linear) {
    out.liquid_per_m = blend(e0.liquid_per_m, e1.liquid_per_m, fraction);
    out.ice_per_m = blend(e0.ice_per_m, e1.ice_per_m, fraction);
    if (!e0.fraction.empty() && !e1.fraction.empty()) out.fraction = blend(e0.fraction, e1.fraction, fraction);
  } else {
    const CellWinds c0 = cell_winds(grid, w0), c1 = cell_winds(grid, w1);
    const double cmax = std::max(c0.max_cells_per_s, c1.max_cells_per_s);
    r.max_courant = cmax * gap_s;
    r.vertical_wind = !w0.w.empty() && !w1.w.empty();
    const int n0 = substeps_for(cmax, gap_s, fraction), n1 = substeps_for(cmax, gap_s, 1.0 - fraction);
    r.substeps = std::max(n0, n1);
    const std::vector<float> zeros(grid.points(), 0.0f);
    const auto or_zeros = [&](const std::vector<float>& f) { return f.empty() ? &zeros : &f; };
    std::vector<std::vector<float>> from0 =
        advect_with(grid, {or_zeros(e0.liquid_per_m), or_zeros(e0.ice_per_m)}, c0, c1, gap_s, fraction, 0, n0);
    std::vector<std::vector<float>> from1 =
        advect_with(grid, {or_zeros(e1.liquid_per_m), or_zeros(e1.ice_per_m)}, c0, c1, gap_s, fraction, 1, n1);
    const std::vector<float>* src0[2] = {&e0.liquid_per_m, &e0.ice_per_m};
    const std::vector<float>* src1[2] = {&e1.liquid_per_m, &e1.ice_per_m};
    std::vector<float>* outs[2] = {&out.liquid_per_m, &out.ice_per_m};
    for (int species = 0; species < 2; ++species) {
      if (src0[species]->empty() && src1[species]->empty()) continue;  // neither step has it
      r.rescale[0][species] = conserve(grid, *or_zeros(*src0[species]), from0[species]);
      r.rescale[1][species] = conserve(grid, *or_zeros(*src1[species]), from1[species]);
      *outs[species] = blend(from0[species], from1[species], fraction);
    }
    // The cloud fraction (the modelled cloud's cover) moves with the same flow; it is a share, not
    // an amount, so it is not rescaled.
    if (!e0.fraction.empty() && !e1.fraction.empty()) {
      const std::vector<std::vector<float>> f0 = advect_with(grid, {&e0.fraction}, c0, c1, gap_s, fraction, 0, n0);
      const std::vector<std::vector<float>> f1 = advect_with(grid, {&e1.fraction}, c0, c1, gap_s, fraction, 1, n1);
      out.fraction = blend(f0[0], f1[0], fraction);
    }
  }
  r.cost_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  out.ground_m = e0.ground_m.empty() ? e1.ground_m : e0.ground_m;  // the terrain does not move
  // The columns' lapse rates (the weather textures' convective signal) linear in time in every
  // mode but the nearest step's (a column property, not carried by the flow).
  if (mode != TimeInterpolation::Nearest && fraction > 0.0 && fraction < 1.0 && e0.lapse_k_per_km.size() == e1.lapse_k_per_km.size() &&
      !e0.lapse_k_per_km.empty()) {
    out.lapse_k_per_km = blend(e0.lapse_k_per_km, e1.lapse_k_per_km, fraction);
  }
  return out;
}

AngularFlow angular_flow(const VolumeGrid& grid, const StepWinds& w0, const StepWinds& w1, double fraction, int max_nodes) {
  AngularFlow f;
  const std::size_t n = grid.points();
  if (!w0.horizontal() || !w1.horizontal() || w0.u.size() != n || w0.v.size() != n || w1.u.size() != n || w1.v.size() != n ||
      n == 0) {
    return f;
  }
  max_nodes = std::max(max_nodes, 2);
  const int nx = grid.lon_deg.count, ny = grid.lat_deg.count, nz = grid.alt_m.count;
  const auto stride = [&](int count) { return count <= max_nodes ? 1 : (count - 1 + max_nodes - 2) / (max_nodes - 1); };
  const int sx = stride(nx), sy = stride(ny);
  const int cx = (nx - 1) / sx + 1, cy = (ny - 1) / sy + 1;
  f.lon_deg = {grid.lon_deg.start, grid.lon_deg.step * sx, cx};
  f.lat_deg = {grid.lat_deg.start, grid.lat_deg.step * sy, cy};
  f.levels = nz;
  const std::size_t plane = std::size_t(cx) * std::size_t(cy);
  std::vector<double> su(plane * std::size_t(nz), 0.0), sv(su.size(), 0.0), count(su.size(), 0.0);
  const double t = std::clamp(fraction, 0.0, 1.0);
  const auto calm = [](float v) { return std::isfinite(v) ? double(v) : 0.0; };
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j) {
      // Each fine node counts towards its nearest coarse node: a box of one stride around each.
      const int cj = std::min((j + sy / 2) / sy, cy - 1);
      for (int i = 0; i < nx; ++i) {
        const int ci = std::min((i + sx / 2) / sx, cx - 1);
        const std::size_t p = grid.index(i, j, k);
        const std::size_t q = std::size_t(k) * plane + std::size_t(cj) * std::size_t(cx) + std::size_t(ci);
        su[q] += (1.0 - t) * calm(w0.u[p]) + t * calm(w1.u[p]);
        sv[q] += (1.0 - t) * calm(w0.v[p]) + t * calm(w1.v[p]);
        count[q] += 1.0;
      }
    }
  f.deg_per_s.assign(2 * su.size(), 0.0f);
  for (int k = 0; k < nz; ++k) {
    const double r = grid.earth_radius_m + grid.alt_m.at(k);
    for (int j = 0; j < cy; ++j) {
      // Near a pole the meridians converge: bounded as the advection bounds it.
      const double coslat = std::max(std::cos(f.lat_deg.at(j) * kRadPerDeg), 1e-3);
      for (int i = 0; i < cx; ++i) {
        const std::size_t q = std::size_t(k) * plane + std::size_t(j) * std::size_t(cx) + std::size_t(i);
        if (count[q] == 0.0) continue;
        f.deg_per_s[2 * q] = static_cast<float>(su[q] / count[q] / (r * coslat) / kRadPerDeg);
        f.deg_per_s[2 * q + 1] = static_cast<float>(sv[q] / count[q] / r / kRadPerDeg);
      }
    }
  }
  return f;
}

}  // namespace cv::core
