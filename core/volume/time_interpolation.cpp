// Interpolation of the medium between forecast steps: nearest, linear, and semi-Lagrangian advection.
#include "volume/time_interpolation.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <stdexcept>

#include "io/input_file.hpp"
#include "io/parallel.hpp"

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
    if (!(x >= 0.0 && x < double(nx))) {  // fmod leaves such an x as it is, and costs
      x = std::fmod(x, double(nx));
      if (x < 0.0) x += nx;
    }
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
  // sample() of each field into out[], the corners found once.
  void sample_all(const std::vector<const std::vector<float>*>& fields, double x, double y, double z, double* out) const {
    const std::size_t nf = fields.size();
    for (std::size_t f = 0; f < nf; ++f) out[f] = 0.0;
    corners(x, y, z, [&](std::size_t n, double w) {
      for (std::size_t f = 0; f < nf; ++f) out[f] += w * (*fields[f])[n];
    });
  }
};

// Both steps' winds as grid cells per second along (longitude, latitude, altitude), read from the
// steps' own fields: u / ((R + z) cos(lat) dlon), v / ((R + z) dlat), w / dz, the factors per level
// and row (no array the size of the grid: a global grid's six were 2.3 GB). No data, non-finite
// values and a step without a wind count as calm.
struct Winds {
  IndexSampler s{};
  const float *u0 = nullptr, *v0 = nullptr, *w0 = nullptr, *u1 = nullptr, *v1 = nullptr, *w1 = nullptr;
  std::vector<double> sx;  // per level and row (k * ny + j): cells per (m/s) along longitude
  std::vector<double> sy;  // per level
  double sz = 0.0;
  // Per row: a cell of longitude in cells of latitude, cos(lat) dlon / dlat (1 without latitudes), so
  // a sub-step's length is measured on the ground, not in index space where a polar row's cells
  // are a hundred times shorter than the equator's.
  std::vector<double> x_in_y_cells;
  double max_cells_per_s[3] = {0.0, 0.0, 0.0};  // over both steps' nodes, per axis

  static double ok(float v) { return std::isfinite(v) ? double(v) : 0.0; }
  // The time blend of a wind component at node n: (1 - t) of the earlier step and t of the later.
  static double blend(const float* a, const float* b, std::size_t n, double t) {
    return (a ? (1.0 - t) * ok(a[n]) : 0.0) + (b ? t * ok(b[n]) : 0.0);
  }
  // The wind at an index-space point and a fraction t of the gap: trilinear in space, linear in
  // time. Corners of zero weight are not read.
  void at(double x, double y, double z, double t, double& vx, double& vy, double& vz) const {
    int i0, i1, j0, j1, k0, k1;
    double tx, ty, tz;
    s.axis_x(x, i0, i1, tx);
    IndexSampler::axis_clamped(y, s.ny, j0, j1, ty);
    IndexSampler::axis_clamped(z, s.nz, k0, k1, tz);
    vx = vy = vz = 0.0;
    const int js[2] = {j0, j1}, ks[2] = {k0, k1};
    const double wy[2] = {1.0 - ty, ty}, wz[2] = {1.0 - tz, tz};
    for (int b = 0; b < 2; ++b)
      for (int a = 0; a < 2; ++a) {
        const double w = wy[a] * wz[b];
        if (w == 0.0) continue;
        const std::size_t kj = std::size_t(ks[b]) * std::size_t(s.ny) + std::size_t(js[a]);
        const std::size_t n0 = kj * std::size_t(s.nx) + std::size_t(i0), n1 = kj * std::size_t(s.nx) + std::size_t(i1);
        const double ax = tx == 1.0 ? 0.0 : 1.0 - tx, bx = tx;
        if (u0 || u1) vx += w * sx[kj] * (ax * blend(u0, u1, n0, t) + (bx == 0.0 ? 0.0 : bx * blend(u0, u1, n1, t)));
        if (v0 || v1) vy += w * sy[std::size_t(ks[b])] * (ax * blend(v0, v1, n0, t) + (bx == 0.0 ? 0.0 : bx * blend(v0, v1, n1, t)));
        if (w0 || w1) vz += w * sz * (ax * blend(w0, w1, n0, t) + (bx == 0.0 ? 0.0 : bx * blend(w0, w1, n1, t)));
      }
  }
};

Winds winds_of(const VolumeGrid& g, const StepWinds& a, const StepWinds& b) {
  Winds c;
  c.s = {g.lon_deg.count, g.lat_deg.count, g.alt_m.count, g.wraps_lon()};
  const std::size_t n = g.points();
  const auto field = [&](const std::vector<float>& f) { return f.size() == n && n ? f.data() : nullptr; };
  if (a.horizontal()) c.u0 = field(a.u), c.v0 = field(a.v);
  if (b.horizontal()) c.u1 = field(b.u), c.v1 = field(b.v);
  c.w0 = field(a.w), c.w1 = field(b.w);
  const int nx = g.lon_deg.count, ny = g.lat_deg.count, nz = g.alt_m.count;
  const double dlon = std::abs(g.lon_deg.step) * kRadPerDeg, dlat = std::abs(g.lat_deg.step) * kRadPerDeg;
  const double dz = std::abs(g.alt_m.step);
  c.sx.assign(std::size_t(nz) * std::size_t(ny), 0.0);
  c.sy.assign(std::size_t(nz), 0.0);
  for (int k = 0; k < nz; ++k) {
    const double r = g.earth_radius_m + g.alt_m.at(k);
    for (int j = 0; j < ny; ++j) {
      // Near a pole the meridians converge: bounded so a polar row's zonal speed stays finite.
      const double coslat = std::max(std::cos(g.lat_deg.at(j) * kRadPerDeg), 1e-3);
      if (nx > 1 && dlon > 0) c.sx[std::size_t(k) * std::size_t(ny) + std::size_t(j)] = 1.0 / (r * coslat * dlon) * (g.lon_deg.step < 0 ? -1.0 : 1.0);
    }
    if (ny > 1 && dlat > 0) c.sy[std::size_t(k)] = 1.0 / (r * dlat) * (g.lat_deg.step < 0 ? -1.0 : 1.0);
  }
  if (nz > 1 && dz > 0) c.sz = 1.0 / dz;
  c.x_in_y_cells.assign(std::size_t(ny), 1.0);
  if (ny > 1 && dlat > 0 && dlon > 0) {
    for (int j = 0; j < ny; ++j) c.x_in_y_cells[std::size_t(j)] = std::max(std::cos(g.lat_deg.at(j) * kRadPerDeg), 1e-3) * dlon / dlat;
  }
  // The largest speed per axis, for the report's Courant number and the reach of a trajectory.
  const std::size_t plane = std::size_t(nx) * std::size_t(ny);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j) {
      const std::size_t kj = std::size_t(k) * std::size_t(ny) + std::size_t(j);
      double mu = 0.0, mv = 0.0, mw = 0.0;
      for (std::size_t i = 0; i < std::size_t(nx); ++i) {
        const std::size_t p = std::size_t(k) * plane + std::size_t(j) * std::size_t(nx) + i;
        for (const float* f : {c.u0, c.u1}) if (f) mu = std::max(mu, std::abs(Winds::ok(f[p])));
        for (const float* f : {c.v0, c.v1}) if (f) mv = std::max(mv, std::abs(Winds::ok(f[p])));
        for (const float* f : {c.w0, c.w1}) if (f) mw = std::max(mw, std::abs(Winds::ok(f[p])));
      }
      c.max_cells_per_s[0] = std::max(c.max_cells_per_s[0], mu * std::abs(c.sx[kj]));
      c.max_cells_per_s[1] = std::max(c.max_cells_per_s[1], mv * std::abs(c.sy[std::size_t(k)]));
      c.max_cells_per_s[2] = std::max(c.max_cells_per_s[2], mw * c.sz);
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

// Rows of nodes (level k, latitude row j) within `reach` rows and levels of a row where any field
// holds a value other than 0: only these can carry anything, since no trajectory moves further
// in the span. Per k * ny + j.
std::vector<char> rows_within_reach(const VolumeGrid& g, const std::vector<const std::vector<float>*>& fields, int reach_j, int reach_k) {
  const int nx = g.lon_deg.count, ny = g.lat_deg.count, nz = g.alt_m.count;
  const std::size_t rows = std::size_t(ny) * std::size_t(nz);
  // Prefix sums over (k, j) of the rows that hold anything (NaN counts as something).
  std::vector<std::uint32_t> sum((std::size_t(nz) + 1) * (std::size_t(ny) + 1), 0);
  const auto S = [&](int k, int j) -> std::uint32_t& { return sum[std::size_t(k) * std::size_t(ny + 1) + std::size_t(j)]; };
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j) {
      bool any = false;
      for (const std::vector<float>* f : fields) {
        const float* row = f->data() + (std::size_t(k) * std::size_t(ny) + std::size_t(j)) * std::size_t(nx);
        for (int i = 0; i < nx && !any; ++i) any = row[i] != 0.0f;
        if (any) break;
      }
      S(k + 1, j + 1) = S(k, j + 1) + S(k + 1, j) - S(k, j) + (any ? 1u : 0u);
    }
  std::vector<char> live(rows, 0);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j) {
      const int k0 = std::max(0, k - reach_k), k1 = std::min(nz, k + reach_k + 1);
      const int j0 = std::max(0, j - reach_j), j1 = std::min(ny, j + reach_j + 1);
      live[std::size_t(k) * std::size_t(ny) + std::size_t(j)] = S(k1, j1) + S(k0, j0) - S(k0, j1) - S(k1, j0) > 0;
    }
  return live;
}

constexpr std::size_t kMostCarried = 3;  // liquid, ice and cloud fraction

// The end of the trajectory that is at index-space node (i, j, k) at `fraction` of the gap, after
// span_s seconds (negative: back to the earlier step), not yet clamped to a regional grid's edges
// (clamp_end). The midpoint rule in sub-steps of at most a
// cell at the wind where each begins, at most kMaxAdvectionSubsteps in all (the last ones share
// what is left of the span equally), so calm nodes take one sub-step however fast the wind
// elsewhere (a global grid's polar rows set the largest speed). Returns the sub-steps taken.
int trajectory(const Winds& wind, int i, int j, int k, double fraction, double span_s, double gap_s, double& x, double& y, double& z) {
  const IndexSampler& s = wind.s;
  x = i, y = j, z = k;
  double t = fraction, left_s = span_s;
  int taken = 0;
  for (;;) {
    double ax, ay, az, bx, by, bz;
    wind.at(x, y, z, t, ax, ay, az);
    const double along_x = std::abs(ax) * wind.x_in_y_cells[static_cast<std::size_t>(std::lround(std::clamp(y, 0.0, double(s.ny - 1))))];
    const double cells = std::max({along_x, std::abs(ay), std::abs(az)}) * std::abs(left_s);
    const int budget = kMaxAdvectionSubsteps - taken;
    const int m = !(cells < double(budget)) ? budget : std::max(1, static_cast<int>(std::ceil(cells)));
    const double h = left_s / m, dt = h / gap_s;
    wind.at(x + 0.5 * h * ax, y + 0.5 * h * ay, z + 0.5 * h * az, t + 0.5 * dt, bx, by, bz);
    x += h * bx, y += h * by, z += h * bz;
    // A wind beyond any scale: the parcel stays (bounded either way). Outside a regional grid the
    // winds are its edge's (the sampler clamps), so the parcel is clamped at the end only.
    if (!std::isfinite(x)) x = i;
    if (!std::isfinite(y)) y = j;
    if (!std::isfinite(z)) z = k;
    t += dt, left_s -= h, ++taken;
    if (m == 1) return taken;
  }
}

// A trajectory's end as the sampler takes it: within the grid, longitude apart where it wraps.
void clamp_end(const IndexSampler& s, double& x, double& y, double& z) {
  if (!std::isfinite(x)) x = 0.0;
  if (!s.wraps) x = std::clamp(x, 0.0, double(s.nx - 1));
  y = std::isfinite(y) ? std::clamp(y, 0.0, double(s.ny - 1)) : 0.0;
  z = std::isfinite(z) ? std::clamp(z, 0.0, double(s.nz - 1)) : 0.0;
}

// The nodes of one horizontal axis where trajectories run: every stride-th and the last.
std::vector<int> lattice(int n, int stride) {
  std::vector<int> at;
  for (int i = 0; i < n; i += stride) at.push_back(i);
  if (at.back() != n - 1) at.push_back(n - 1);
  return at;
}

// Each node's place between two lattice nodes of its axis: the lower one's index and the weight of
// the upper.
struct Between {
  std::vector<int> lower;
  std::vector<double> w;
};
Between between(const std::vector<int>& at, int n) {
  Between b;
  b.lower.resize(std::size_t(n)), b.w.resize(std::size_t(n));
  std::size_t q = 0;
  for (int i = 0; i < n; ++i) {
    while (q + 2 < at.size() && at[q + 1] <= i) ++q;
    b.lower[std::size_t(i)] = static_cast<int>(q);
    b.w[std::size_t(i)] = at.size() < 2 ? 0.0 : double(i - at[q]) / double(at[q + 1] - at[q]);
  }
  return b;
}

// Each field of `fields` carried along the same trajectories and sampled trilinearly at their ends
// (an empty field stays empty: carried nothing). With stride 1 every node runs its own trajectory;
// with a larger stride trajectories run on every stride-th node of longitude and latitude (and the
// last), every level, and each node between takes the bilinear blend of its four lattice nodes'
// displacements (trajectory_stride). Rows of nodes beyond the trajectories' reach of any value are
// left 0. Nodes are independent: the result does not depend on the number of threads.
// *most_substeps: the most sub-steps any trajectory took.
std::vector<std::vector<float>> advect_with(const VolumeGrid& g, const std::vector<const std::vector<float>*>& fields,
                                            const Winds& wind, double gap_s, double fraction, int from, int stride,
                                            int* most_substeps) {
  const IndexSampler& s = wind.s;
  // From the instant back to the earlier step (from 0) or on to the later one (from 1).
  const double span = from == 0 ? -fraction : 1.0 - fraction;  // in fractions of the gap, signed
  const double span_s = span * gap_s;
  if (fields.size() > kMostCarried) throw std::logic_error("advect_with: more fields than kMostCarried");
  std::vector<std::vector<float>> out(fields.size());
  std::vector<const std::vector<float>*> present;
  std::vector<std::vector<float>*> carried;
  for (std::size_t f = 0; f < fields.size(); ++f) {
    if (fields[f]->empty()) continue;
    // A global field is 190 MB of fresh pages: faulted in on every core before the zeros go in.
    reserve_exact(out[f], g.points());
    populate_pages(out[f].data(), g.points() * sizeof(float));
    out[f].assign(g.points(), 0.0f);
    present.push_back(fields[f]);
    carried.push_back(&out[f]);
  }
  if (most_substeps) *most_substeps = 0;
  if (present.empty()) return out;
  const auto reach = [&](double cells_per_s, int n) {
    const double cells = cells_per_s * std::abs(span_s);
    return !(cells < double(n)) ? n : static_cast<int>(std::ceil(cells)) + 1;
  };
  const int nx = g.lon_deg.count, ny = g.lat_deg.count, nz = g.alt_m.count;
  const std::vector<char> live = rows_within_reach(g, present, reach(wind.max_cells_per_s[1], ny), reach(wind.max_cells_per_s[2], nz));
  stride = std::max(stride, 1);
  // The lattice's displacements (x, y, z per lattice node, level by level), on levels with a live row.
  const std::vector<int> lx = lattice(nx, stride), ly = lattice(ny, stride);
  const std::size_t lnx = lx.size(), lny = ly.size();
  std::vector<char> level_live(std::size_t(nz), 0);
  for (std::size_t row = 0; row < live.size(); ++row) level_live[row / std::size_t(ny)] |= live[row];
  std::vector<float> shift;
  std::vector<int> most(worker_count(), 0);
  // Shares rows [0, n) among the machine's cores a few at a time (live rows are uneven).
  const auto shared_rows = [&](std::size_t n, const auto& body) {
    std::atomic<std::size_t> next{0};
    parallel_ranges(std::size_t(worker_count()), 1, [&](std::size_t, std::size_t, unsigned part) {
      for (;;) {
        const std::size_t r0 = next.fetch_add(8);
        if (r0 >= n) break;
        for (std::size_t row = r0; row < std::min(n, r0 + 8); ++row) body(row, most[part]);
      }
    });
  };
  if (stride > 1) {
    shift.assign(lnx * lny * std::size_t(nz) * 3, 0.0f);
    shared_rows(lny * std::size_t(nz), [&](std::size_t row, int& worst) {
      const int k = static_cast<int>(row / lny), j = ly[row % lny];
      if (!level_live[std::size_t(k)]) return;
      for (std::size_t q = 0; q < lnx; ++q) {
        double x, y, z;
        worst = std::max(worst, trajectory(wind, lx[q], j, k, fraction, span_s, gap_s, x, y, z));
        float* d = shift.data() + 3 * (row * lnx + q);
        d[0] = static_cast<float>(x - lx[q]), d[1] = static_cast<float>(y - j), d[2] = static_cast<float>(z - k);
      }
    });
  }
  const Between bx = between(lx, nx), by = between(ly, ny);
  shared_rows(live.size(), [&](std::size_t row, int& worst) {
    if (!live[row]) return;
    const int k = static_cast<int>(row / std::size_t(ny)), j = static_cast<int>(row % std::size_t(ny));
    const std::size_t J = std::size_t(by.lower[std::size_t(j)]), J1 = std::min(J + 1, lny - 1);
    const double wy = by.w[std::size_t(j)];
    for (int i = 0; i < nx; ++i) {
      double x, y, z;
      if (stride == 1) {
        worst = std::max(worst, trajectory(wind, i, j, k, fraction, span_s, gap_s, x, y, z));
        clamp_end(s, x, y, z);
      } else {
        const std::size_t I = std::size_t(bx.lower[std::size_t(i)]), I1 = std::min(I + 1, lnx - 1);
        const double wx = bx.w[std::size_t(i)];
        const std::size_t base = std::size_t(k) * lny;
        const float* a = shift.data() + 3 * ((base + J) * lnx + I);
        const float* b = shift.data() + 3 * ((base + J) * lnx + I1);
        const float* c = shift.data() + 3 * ((base + J1) * lnx + I);
        const float* d = shift.data() + 3 * ((base + J1) * lnx + I1);
        double dd[3];
        for (int e = 0; e < 3; ++e) dd[e] = (1.0 - wy) * ((1.0 - wx) * a[e] + wx * b[e]) + wy * ((1.0 - wx) * c[e] + wx * d[e]);
        x = i + dd[0], y = j + dd[1], z = k + dd[2];
        clamp_end(s, x, y, z);
      }
      // A convex combination of non-negative values: never negative, never above the source's largest.
      const std::size_t p = g.index(i, j, k);
      double v[kMostCarried];
      s.sample_all(present, x, y, z, v);
      for (std::size_t f = 0; f < present.size(); ++f) (*carried[f])[p] = static_cast<float>(std::max(0.0, v[f]));
    }
  });
  if (most_substeps) *most_substeps = *std::max_element(most.begin(), most.end());
  return out;
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

// blend(a, b, f) written over a (no fresh array: a global field is 190 MB of pages), on every core.
std::vector<float> blend_into(std::vector<float>&& a, const std::vector<float>& b, double f) {
  if (a.empty()) return blend(a, b, f);
  const std::size_t n = a.size();
  parallel_ranges(n, std::size_t(1) << 20, [&](std::size_t lo, std::size_t hi, unsigned) {
    for (std::size_t p = lo; p < hi; ++p) {
      const double va = a[p], vb = b.empty() ? 0.0 : b[p];
      a[p] = static_cast<float>(std::max(0.0, (1.0 - f) * va + f * vb));
    }
  });
  return std::move(a);
}

}  // namespace

int trajectory_stride(const VolumeGrid& grid) {
  const double columns = double(grid.lon_deg.count) * double(grid.lat_deg.count);
  int stride = 1;
  while (columns / (double(stride) * double(stride)) > double(kMaxTrajectoryColumns)) ++stride;
  return stride;
}

std::vector<float> advect_field(const VolumeGrid& grid, const std::vector<float>& field, const StepWinds& w0,
                                const StepWinds& w1, double gap_s, double fraction, int from, int* substeps,
                                double* max_courant, int stride) {
  const Winds wind = winds_of(grid, w0, w1);
  if (max_courant) *max_courant = std::max({wind.max_cells_per_s[0], wind.max_cells_per_s[1], wind.max_cells_per_s[2]}) * gap_s;
  std::vector<std::vector<float>> out = advect_with(grid, {&field}, wind, gap_s, fraction, from, stride > 0 ? stride : trajectory_stride(grid), substeps);
  if (out[0].empty()) out[0].assign(field.size(), 0.0f);
  return std::move(out[0]);
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
    const Winds wind = winds_of(grid, w0, w1);
    r.max_courant = std::max({wind.max_cells_per_s[0], wind.max_cells_per_s[1], wind.max_cells_per_s[2]}) * gap_s;
    r.vertical_wind = !w0.w.empty() && !w1.w.empty();
    // Each neighbour's liquid, ice and cloud fraction along one set of trajectories. The fraction
    // (the modelled cloud's cover) moves with the same flow; it is a share, not an amount, so it is
    // not rescaled. A species neither step has stays empty; one step's missing species is 0.
    const std::vector<float> none;
    const bool fractions = !e0.fraction.empty() && !e1.fraction.empty();
    int n0 = 0, n1 = 0;
    r.stride = trajectory_stride(grid);
    std::vector<std::vector<float>> from0 = advect_with(
        grid, {&e0.liquid_per_m, &e0.ice_per_m, fractions ? &e0.fraction : &none}, wind, gap_s, fraction, 0, r.stride, &n0);
    std::vector<std::vector<float>> from1 = advect_with(
        grid, {&e1.liquid_per_m, &e1.ice_per_m, fractions ? &e1.fraction : &none}, wind, gap_s, fraction, 1, r.stride, &n1);
    r.substeps = std::max(n0, n1);
    const std::vector<float>* src0[2] = {&e0.liquid_per_m, &e0.ice_per_m};
    const std::vector<float>* src1[2] = {&e1.liquid_per_m, &e1.ice_per_m};
    std::vector<float>* outs[2] = {&out.liquid_per_m, &out.ice_per_m};
    for (int species = 0; species < 2; ++species) {
      if (src0[species]->empty() && src1[species]->empty()) continue;  // neither step has it
      if (!from0[species].empty()) r.rescale[0][species] = conserve(grid, *src0[species], from0[species]);
      if (!from1[species].empty()) r.rescale[1][species] = conserve(grid, *src1[species], from1[species]);
      *outs[species] = blend_into(std::move(from0[species]), from1[species], fraction);
    }
    if (fractions) out.fraction = blend_into(std::move(from0[2]), from1[2], fraction);
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
