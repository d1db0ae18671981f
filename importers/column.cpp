// The per-column physics of the conversion.
#include "column.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#endif

#include "importer.hpp"
#include "io/cpu.hpp"
#include "volume/volume_io.hpp"

namespace cv::importers {
namespace {
constexpr double kRhoWater = 1000.0;  // kg/m3
constexpr double kRhoIce = 917.0;     // kg/m3
const double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string fmt(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.6g", v);
  return b;
}
}  // namespace

void ColumnCounts::merge(const ColumnCounts& o) {
  water_without_cf += o.water_without_cf;
  water_without_cf_significant += o.water_without_cf_significant;
  cf_without_water += o.cf_without_water;
  nonmonotonic += o.nonmonotonic;
  most_water_without_cf = std::max(most_water_without_cf, o.most_water_without_cf);
}

core::RegularAxis altitude_axis(double zmin_m, double zmax_m, double dz_m, bool fit) {
  const double span = zmax_m - zmin_m;
  // Intervals needed to reach the top; a hair of tolerance so a span that is a whole number of
  // steps (to rounding) does not get one more.
  const int intervals = std::max(1, static_cast<int>(std::ceil(span / dz_m - 1e-9)));
  const double dz = fit ? span / intervals : dz_m;
  return {zmin_m, dz, intervals + 1};
}

void RowLevels::resize(int columns, int levels) {
  nx = columns, nlev = levels;
  const std::size_t n = static_cast<std::size_t>(columns) * static_cast<std::size_t>(levels);
  for (auto* a : {&z_m, &p_pa, &t_k, &qv, &cf, &q_liquid, &q_ice, &u, &v, &w}) a->resize(n);
}

namespace {
// One node's value, linear between its level pair (q0, q1 at weight a), as the field needs: the
// in-cloud value (the grid-box mean over the interpolated fraction, from c0, c1) or the value itself.
template <bool kInCloud>
inline float interpolate_node(double a, double q0, double q1, double c0, double c1) {
  double v = q0 + a * (q1 - q0);
  if constexpr (kInCloud) {
    const double cf = c0 + a * (c1 - c0);
    if (!std::isnan(cf)) v = v > 0.0 && cf > 0.0 ? v / cf : (std::isnan(v) ? v : 0.0);
  }
  return static_cast<float>(v);
}

template <bool kInCloud>
void interpolate_run_scalar(std::size_t b, std::size_t e, const double* wt, const double* q0, const double* q1,
                            const double* c0, const double* c1, float* row) {
  for (std::size_t x = b; x < e; ++x) row[x] = interpolate_node<kInCloud>(wt[x], q0[x], q1[x], kInCloud ? c0[x] : 0.0, kInCloud ? c1[x] : 0.0);
}

#if defined(__x86_64__) && defined(__GNUC__)
// The same, four nodes at a time: the same operations in the same order (no fused multiply-add),
// so the same bits as the scalar loop; the selects replace its branches.
template <bool kInCloud>
__attribute__((target("avx"))) void interpolate_run_avx(std::size_t b, std::size_t e, const double* wt, const double* q0,
                                                        const double* q1, const double* c0, const double* c1, float* row) {
  std::size_t x = b;
  const __m256d zero = _mm256_setzero_pd();
  for (; x + 4 <= e; x += 4) {
    const __m256d a = _mm256_loadu_pd(wt + x), v0 = _mm256_loadu_pd(q0 + x);
    __m256d v = _mm256_add_pd(v0, _mm256_mul_pd(a, _mm256_sub_pd(_mm256_loadu_pd(q1 + x), v0)));
    if constexpr (kInCloud) {
      const __m256d f0 = _mm256_loadu_pd(c0 + x);
      const __m256d cf = _mm256_add_pd(f0, _mm256_mul_pd(a, _mm256_sub_pd(_mm256_loadu_pd(c1 + x), f0)));
      const __m256d both = _mm256_and_pd(_mm256_cmp_pd(v, zero, _CMP_GT_OQ), _mm256_cmp_pd(cf, zero, _CMP_GT_OQ));
      // v / cf where both are positive; else NaN stays NaN and anything else is 0.
      const __m256d other = _mm256_blendv_pd(zero, v, _mm256_cmp_pd(v, v, _CMP_UNORD_Q));
      const __m256d in_cloud = _mm256_blendv_pd(other, _mm256_div_pd(v, cf), both);
      v = _mm256_blendv_pd(in_cloud, v, _mm256_cmp_pd(cf, cf, _CMP_UNORD_Q));  // no fraction: the value as it is
    }
    _mm_storeu_ps(row + x, _mm256_cvtpd_ps(v));
  }
  interpolate_run_scalar<kInCloud>(x, e, wt, q0, q1, c0, c1, row);
}
#endif

// The grid-box-mean extinctions of a row's level samples, from the water, the air's density and
// the effective radii (NaN where the water is absent; 0 where the box's fraction is below
// kZeroCloudFraction). Written without branches, so the compiler divides several values at a time
// (three divisions per value, one at a time, were about a fifth of place_row); the same operations
// in the same order as one value at a time, so the same bits.
struct ExtinctionInputs {
  const double *p, *t, *qv, *ql, *qi, *cf;
  double r_liq_m, r_ice_um;  // r_ice_um <= 0: temperature-dependent
  double *liq, *ice;
};

[[gnu::always_inline]] inline void extinction_loop(const ExtinctionInputs& in, std::size_t n) {
  const double* __restrict p = in.p;
  const double* __restrict t = in.t;
  const double* __restrict qv = in.qv;
  const double* __restrict ql = in.ql;
  const double* __restrict qi = in.qi;
  const double* __restrict cf = in.cf;
  double* __restrict liq = in.liq;
  double* __restrict ice = in.ice;
  const double r_liq_m = in.r_liq_m, r_ice_um = in.r_ice_um;
  for (std::size_t i = 0; i < n; ++i) {
    const double rho = p[i] / (kRdJPerKgK * t[i] * (1.0 + 0.608 * qv[i]));
    const double l = ql[i], q = qi[i], c = cf[i];
    const double total = (std::isnan(l) ? 0.0 : l) + (std::isnan(q) ? 0.0 : q);
    const double keep = !std::isnan(c) && total > 0.0 && c < kZeroCloudFraction ? 0.0 : 1.0;
    const double r_ice_m = (r_ice_um > 0 ? r_ice_um : ice_effective_radius_um(t[i])) * 1e-6;
    const double vl = keep * 3.0 * rho * l / (2.0 * kRhoWater * r_liq_m);
    const double vi = keep * 3.0 * rho * q / (2.0 * kRhoIce * r_ice_m);
    liq[i] = std::isnan(l) ? kNaN : vl;
    ice[i] = std::isnan(q) ? kNaN : vi;
  }
}

void extinctions_plain(const ExtinctionInputs& in, std::size_t n) { extinction_loop(in, n); }

#if defined(__x86_64__) && defined(__GNUC__)
__attribute__((target("avx"))) void extinctions_avx(const ExtinctionInputs& in, std::size_t n) {
  const __m256d zero = _mm256_setzero_pd(), one = _mm256_set1_pd(1.0), nan = _mm256_set1_pd(kNaN);
  const __m256d rd = _mm256_set1_pd(kRdJPerKgK), c608 = _mm256_set1_pd(0.608), three = _mm256_set1_pd(3.0);
  const __m256d zero_cf = _mm256_set1_pd(kZeroCloudFraction), micro = _mm256_set1_pd(1e-6);
  const __m256d liq_den = _mm256_set1_pd(2.0 * kRhoWater * in.r_liq_m), two_rho_ice = _mm256_set1_pd(2.0 * kRhoIce);
  const __m256d r_fixed = _mm256_set1_pd(in.r_ice_um), r_lo = _mm256_set1_pd(20.0), r_hi = _mm256_set1_pd(50.0);
  const __m256d half = _mm256_set1_pd(0.5), t0 = _mm256_set1_pd(273.15);
  const bool fixed = in.r_ice_um > 0;
  std::size_t i = 0;
  for (; i + 4 <= n; i += 4) {
    const __m256d t = _mm256_loadu_pd(in.t + i), l = _mm256_loadu_pd(in.ql + i), q = _mm256_loadu_pd(in.qi + i);
    const __m256d c = _mm256_loadu_pd(in.cf + i);
    const __m256d rho = _mm256_div_pd(_mm256_loadu_pd(in.p + i),
                                      _mm256_mul_pd(_mm256_mul_pd(rd, t), _mm256_add_pd(one, _mm256_mul_pd(c608, _mm256_loadu_pd(in.qv + i)))));
    const __m256d l_nan = _mm256_cmp_pd(l, l, _CMP_UNORD_Q), q_nan = _mm256_cmp_pd(q, q, _CMP_UNORD_Q);
    const __m256d total = _mm256_add_pd(_mm256_blendv_pd(l, zero, l_nan), _mm256_blendv_pd(q, zero, q_nan));
    const __m256d drop = _mm256_andnot_pd(_mm256_cmp_pd(c, c, _CMP_UNORD_Q),
                                          _mm256_and_pd(_mm256_cmp_pd(total, zero, _CMP_GT_OQ), _mm256_cmp_pd(c, zero_cf, _CMP_LT_OQ)));
    const __m256d keep = _mm256_blendv_pd(one, zero, drop);
    __m256d r_ice = r_fixed;
    if (!fixed) {  // ice_effective_radius_um: 50 + 0.5 (T - 273.15), then clamp's two selects
      const __m256d r = _mm256_add_pd(r_hi, _mm256_mul_pd(half, _mm256_sub_pd(t, t0)));
      const __m256d above = _mm256_blendv_pd(r, r_lo, _mm256_cmp_pd(r, r_lo, _CMP_LT_OQ));
      r_ice = _mm256_blendv_pd(above, r_hi, _mm256_cmp_pd(r_hi, above, _CMP_LT_OQ));
    }
    const __m256d k3rho = _mm256_mul_pd(_mm256_mul_pd(keep, three), rho);
    const __m256d vl = _mm256_div_pd(_mm256_mul_pd(k3rho, l), liq_den);
    const __m256d vi = _mm256_div_pd(_mm256_mul_pd(k3rho, q), _mm256_mul_pd(two_rho_ice, _mm256_mul_pd(r_ice, micro)));
    _mm256_storeu_pd(in.liq + i, _mm256_blendv_pd(vl, nan, l_nan));
    _mm256_storeu_pd(in.ice + i, _mm256_blendv_pd(vi, nan, q_nan));
  }
  const ExtinctionInputs rest{in.p + i, in.t + i, in.qv + i, in.ql + i, in.qi + i, in.cf + i, in.r_liq_m, in.r_ice_um,
                              in.liq + i, in.ice + i};
  extinction_loop(rest, n - i);
}
#endif

// One layer of a row's nodes from its runs: linear interpolation between each run's level pair,
// in-cloud values (the mean over the interpolated fraction) or pressure (interpolated in its
// logarithm; qcf is then the pressure) as the field needs.
template <bool kInCloud, bool kPressure>
void interpolate_nodes(const LevelRun* run, const LevelRun* runs_end, const double* wt, const double* qf, const double* qcf,
                       std::size_t nxs, float* row) {
#if defined(__x86_64__) && defined(__GNUC__)
  const bool avx = core::cpu_has_avx();
#endif
  for (; run != runs_end; ++run) {
    const std::size_t b = static_cast<std::size_t>(run->begin), e = static_cast<std::size_t>(run->end);
    if (run->lev < 0) {  // no level pair around these nodes: no data
      std::fill(row + b, row + e, std::numeric_limits<float>::quiet_NaN());
      continue;
    }
    const std::size_t upper = static_cast<std::size_t>(run->lev) * nxs;
    const double *q1 = qf + upper, *q0 = q1 - nxs, *c1 = qcf + upper, *c0 = c1 - nxs;
    if constexpr (kPressure) {
      // qf is the pressure's logarithm, qcf the pressure: p0 exp(a ln(p1 / p0)), the exponential
      // taken in float (relative error about 1e-7, the float result's own; rounding ln p itself to
      // float would lose ten times that). exp in double cost 5 % of the import.
      for (std::size_t x = b; x < e; ++x) {
        row[x] = static_cast<float>(c0[x] * static_cast<double>(std::exp(static_cast<float>(wt[x] * (q1[x] - q0[x])))));
      }
      continue;
    }
#if defined(__x86_64__) && defined(__GNUC__)
    if (avx) {
      interpolate_run_avx<kInCloud>(b, e, wt, q0, q1, c0, c1, row);
      continue;
    }
#endif
    interpolate_run_scalar<kInCloud>(b, e, wt, q0, q1, c0, c1, row);
  }
}
}  // namespace

void place_row(const RowLevels& r, const core::VolumeGrid& grid, int x0, int y, const ConversionOptions& options,
               core::TimeStepData& out, ColumnCounts& counts, StoredStats* stored) {
  thread_local PlaceRowScratch scratch;
  place_row(r, grid, x0, y, options, out, counts, stored, scratch);
}

void place_row(const RowLevels& r, const core::VolumeGrid& grid, int x0, int y, const ConversionOptions& options,
               core::TimeStepData& out, ColumnCounts& counts, StoredStats* stored, PlaceRowScratch& scratch) {
  const int n = r.nlev, nx = r.nx, nz = grid.alt_m.count;
  const std::size_t plane = static_cast<std::size_t>(n) * static_cast<std::size_t>(nx);
  // Per level and column, level-major like `r`: the quantities the conversion makes (the two
  // extinctions, grid-box means here that become in-cloud values node by node below, and the
  // pressure's logarithm) in a per-thread buffer, reused; the rest are interpolated from `r` as
  // they are.
  constexpr int kLiq = static_cast<int>(core::Field::ExtinctionLiquid), kIce = static_cast<int>(core::Field::ExtinctionIce),
                kCf = static_cast<int>(core::Field::CloudFraction), kP = static_cast<int>(core::Field::Pressure);
  std::vector<double>& buffer = scratch.buffer;
  buffer.resize(3 * plane);
  std::array<const double*, core::kFieldCount> source{};
  source[kLiq] = buffer.data(), source[kIce] = buffer.data() + plane, source[kP] = buffer.data() + 2 * plane;
  source[kCf] = r.cf.data();
  source[static_cast<int>(core::Field::WindU)] = r.u.data();
  source[static_cast<int>(core::Field::WindV)] = r.v.data();
  source[static_cast<int>(core::Field::WindW)] = r.w.data();
  source[static_cast<int>(core::Field::Temperature)] = r.t_k.data();
  static_assert(core::kFieldCount == 8, "every field has its source above");
  double* const liq = buffer.data();
  double* const ice = buffer.data() + plane;
  double* const log_p = buffer.data() + 2 * plane;
  const double r_liq_m = options.r_eff_liquid_um * 1e-6;
  // On pressure levels every column of a level has the same pressure: its logarithm is taken once.
  double last_p = std::numeric_limits<double>::quiet_NaN(), last_log_p = kNaN;
  for (std::size_t i = 0; i < plane; ++i) {
    const double ql = r.q_liquid[i], qi = r.q_ice[i], cf = r.cf[i];
    const double total = (std::isnan(ql) ? 0.0 : ql) + (std::isnan(qi) ? 0.0 : qi);
    // A box's water counts only where its fraction says there is cloud to hold it (the
    // extinctions below leave it out by the same test).
    if (!std::isnan(cf)) {
      if (total > 0.0 && cf < kZeroCloudFraction) {
        ++counts.water_without_cf;
        if (total > kZeroWater) ++counts.water_without_cf_significant;
        counts.most_water_without_cf = std::max(counts.most_water_without_cf, total);
      }
      if (cf > 0.1 && total <= kZeroWater) ++counts.cf_without_water;
    }
    // Pressure is interpolated in its logarithm (exact in an isothermal layer), turned back below.
    const double p = r.p_pa[i];
    if (!(p == last_p)) last_p = p, last_log_p = p > 0.0 ? std::log(p) : kNaN;
    log_p[i] = last_log_p;
  }
  const ExtinctionInputs in{r.p_pa.data(), r.t_k.data(), r.qv.data(), r.q_liquid.data(), r.q_ice.data(), r.cf.data(), r_liq_m,
                            options.r_eff_ice_um, liq, ice};
#if defined(__x86_64__) && defined(__GNUC__)
  if (core::cpu_has_avx()) extinctions_avx(in, plane);
  else
#endif
    extinctions_plain(in, plane);
  for (int l = 1; l < n; ++l) {
    for (int x = 0; x < nx; ++x) {
      if (!(r.z_m[r.at(l, x)] > r.z_m[r.at(l - 1, x)])) ++counts.nonmonotonic;
    }
  }
  const bool has_cf = !out.fields[static_cast<std::size_t>(kCf)].empty() || !out.halves[static_cast<std::size_t>(kCf)].empty();
  // Linear interpolation in altitude; outside a column's levels: no data. A node within a
  // micrometre of the top level (the axis was fitted to end there) takes the top level's value.
  // First each node's level pair and weight (node-major, like the output's layers), then field by
  // field, node by node, along the row.
  std::vector<int>& node_level = scratch.node_level;
  std::vector<double>& node_weight = scratch.node_weight;
  const std::size_t nodes = static_cast<std::size_t>(nz) * static_cast<std::size_t>(nx);
  node_level.assign(nodes, -1);
  node_weight.resize(nodes);
  for (int x = 0; x < nx; ++x) {
    auto zl = [&](int l) { return r.z_m[r.at(l, x)]; };
    const double z_top = n > 0 ? zl(n - 1) : kNaN;
    int l = 1;
    for (int z = 0; z < nz; ++z) {
      double alt = grid.alt_m.at(z);
      if (alt > z_top && alt - z_top < 1e-6) alt = z_top;
      while (l < n && !(zl(l) >= alt)) ++l;
      if (l >= n) break;
      const double z0 = zl(l - 1), z1 = zl(l);
      if (!(z0 <= alt) || !(z1 > z0)) continue;
      const std::size_t k = static_cast<std::size_t>(z) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(x);
      node_level[k] = l;
      node_weight[k] = (alt - z0) / (z1 - z0);
    }
  }
  const std::size_t nxs = static_cast<std::size_t>(nx);
  // Each layer's runs of nodes between the same level pair, shared by every field.
  std::vector<LevelRun>& runs = scratch.runs;
  std::vector<std::size_t>& layer_runs = scratch.layer_runs;
  runs.clear();
  layer_runs.assign(static_cast<std::size_t>(nz) + 1, 0);
  for (int z = 0; z < nz; ++z) {
    const int* lev = node_level.data() + static_cast<std::size_t>(z) * nxs;
    for (int x = 0; x < nx;) {
      int e = x + 1;
      while (e < nx && lev[e] == lev[x]) ++e;
      runs.push_back({x, e, lev[x]});
      x = e;
    }
    layer_runs[static_cast<std::size_t>(z) + 1] = runs.size();
  }
  const double* qcf = source[kCf];
  // A field held as half floats (TimeStepData::halves): each layer row is made in floats here, in
  // cache, and stored converted, as write_cvvol would convert the float field.
  std::vector<float>& layer = scratch.layer;
  layer.resize(nxs);
  for (int f = 0; f < core::kFieldCount; ++f) {
    auto& dst = out.fields[static_cast<std::size_t>(f)];
    auto& halves = out.halves[static_cast<std::size_t>(f)];
    const bool as_half = dst.empty() && !halves.empty();
    if (dst.empty() && !as_half) continue;
    const float half_scale = core::half_field_scale(static_cast<core::Field>(f));
    const double* qf = source[static_cast<std::size_t>(f)];
    // In-cloud = grid-box mean / fraction. Water was kept only where the fraction is meaningful,
    // so where the fraction vanishes the mean does too and the ratio stays bounded by its
    // neighbours' in-cloud values.
    const bool in_cloud = (f == kLiq || f == kIce) && has_cf;
    const bool pressure = f == kP;
    core::ValueStats st;  // of the finite values stored (the caller counts the missing ones)
    for (int z = 0; z < nz; ++z) {
      const LevelRun* rb = runs.data() + layer_runs[static_cast<std::size_t>(z)];
      const LevelRun* re = runs.data() + layer_runs[static_cast<std::size_t>(z) + 1];
      const double* wt = node_weight.data() + static_cast<std::size_t>(z) * nxs;
      float* row = as_half ? layer.data() : dst.data() + grid.index(x0, y, z);
      // The three kinds of field as their own loops: no per-node test of what the field is.
      if (in_cloud) interpolate_nodes<true, false>(rb, re, wt, qf, qcf, nxs, row);
      else if (pressure) interpolate_nodes<false, true>(rb, re, wt, qf, r.p_pa.data(), nxs, row);
      else interpolate_nodes<false, false>(rb, re, wt, qf, qcf, nxs, row);
      st.add_all(row, nxs);
      if (as_half) core::floats_to_halves(row, half_scale, halves.data() + grid.index(x0, y, z), nxs);
    }
    if (stored && st.count) {
      core::ValueStats& acc = (*stored)[static_cast<std::size_t>(f)];
      acc.min = std::min(acc.min, st.min);
      acc.max = std::max(acc.max, st.max);
    }
    if (stored) (*stored)[static_cast<std::size_t>(f)].count += st.count;
  }
}

void place_column(std::span<LevelSample> levels, const core::VolumeGrid& grid, int x, int y,
                  const ConversionOptions& options, core::TimeStepData& out, ColumnCounts& counts) {
  // A row of one column.
  thread_local RowLevels r;
  const int n = static_cast<int>(levels.size());
  r.resize(1, n);
  for (int l = 0; l < n; ++l) {
    const LevelSample& s = levels[static_cast<std::size_t>(l)];
    const std::size_t i = static_cast<std::size_t>(l);
    r.z_m[i] = s.z_m, r.p_pa[i] = s.p_pa, r.t_k[i] = s.t_k, r.qv[i] = s.qv, r.cf[i] = s.cf;
    r.q_liquid[i] = s.q_liquid, r.q_ice[i] = s.q_ice, r.u[i] = s.u, r.v[i] = s.v, r.w[i] = s.w;
  }
  place_row(r, grid, x, y, options, out, counts);
}

bool in_time_range(const core::ValidTime& t, const ImportOptions& o) {
  return (o.time_from_iso.empty() || t.iso_utc >= o.time_from_iso) && (o.time_to_iso.empty() || t.iso_utc <= o.time_to_iso);
}

void report_counts(const ColumnCounts& c, int t, core::ImportReport& report) {
  report_counts(c, t, "", report);
}

void report_counts(const ColumnCounts& c, int t, const std::string& what, core::ImportReport& report) {
  const std::string at = " at time step " + std::to_string(t);
  const std::string boxes = what.empty() ? "boxes" : what;
  if (c.water_without_cf) {
    report.warn(std::to_string(c.water_without_cf) + " " + boxes + " with water (up to " + fmt(c.most_water_without_cf) +
                " kg/kg; " + std::to_string(c.water_without_cf_significant) + " above " + fmt(kZeroWater) +
                " kg/kg) but a cloud fraction below " + fmt(kZeroCloudFraction) + at +
                ": their water is left out, no cloud is invented there");
  }
  if (c.cf_without_water) {
    report.warn(std::to_string(c.cf_without_water) + " " + boxes + " with cloud fraction above 0.1 but no cloud water" + at);
  }
  if (c.nonmonotonic) report.warn(std::to_string(c.nonmonotonic) + " level pairs whose heights do not rise with the level" + at);
}

}  // namespace cv::importers
