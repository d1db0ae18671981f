// Light between the two-stream's columns: 3-D against independent-column diffusion of the scaled problem.
#include "kernel/ms_lateral.hpp"

#include <algorithm>
#include <cmath>

#include "io/parallel.hpp"

namespace cv::core {
namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr std::size_t kNone = static_cast<std::size_t>(-1);

struct Layout {
  int nx = 0, ny = 0, nz = 0;
  bool wrap = false;
  std::size_t layer = 0;
  std::size_t at(int i, int j, int k) const {
    return static_cast<std::size_t>(k) * layer + static_cast<std::size_t>(j) * static_cast<std::size_t>(nx) +
           static_cast<std::size_t>(i);
  }
};

// One column's tridiagonal system over levels k0..k1 (diagonal `diag`, -wz[k] between nodes k and
// k + 1; no coupling leaves the range), solved by Thomas's algorithm (the matrix is diagonally
// dominant: no pivoting).
void solve_column(const Layout& L, std::size_t col, int k0, int k1, const std::vector<double>& diag,
                  const std::vector<float>& wz, const double* rhs, double* x, std::vector<double>& scratch) {
  scratch.resize(static_cast<std::size_t>(L.nz));
  double prev_c = 0.0, prev_x = 0.0;
  for (int k = k0; k <= k1; ++k) {
    const std::size_t a = static_cast<std::size_t>(k) * L.layer + col;
    const double lower = k > k0 ? double(wz[a - L.layer]) : 0.0;
    const double den = diag[a] - lower * prev_c;
    const double c = den > 0.0 && k < k1 ? double(wz[a]) / den : 0.0;
    const double xv = den > 0.0 ? (rhs[a] + lower * prev_x) / den : 0.0;
    scratch[static_cast<std::size_t>(k)] = c;
    x[a] = xv;
    prev_c = c;
    prev_x = xv;
  }
  for (int k = k1 - 1; k >= k0; --k) {
    const std::size_t a = static_cast<std::size_t>(k) * L.layer + col;
    x[a] += scratch[static_cast<std::size_t>(k)] * x[a + L.layer];
  }
}

// A column holding cloud and its levels from the lowest cloudy node to the highest: the solve
// works on these alone (every other node is clear, and stays 0).
struct Span {
  std::size_t col;
  int k0, k1;
};
}  // namespace

LateralRatio lateral_ratio(const VolumeGrid& grid, const LateralMedium& m, double tolerance,
                           int max_iterations) {
  Layout L;
  L.nx = grid.lon_deg.count;
  L.ny = grid.lat_deg.count;
  L.nz = grid.alt_m.count;
  L.wrap = grid.wraps_lon();
  L.layer = static_cast<std::size_t>(std::max(L.nx, 0)) * static_cast<std::size_t>(std::max(L.ny, 0));
  const std::size_t n = grid.points();
  LateralRatio out;
  out.ratio.assign(n, 1.0f);
  out.east.assign(n, 0.0f);
  out.north.assign(n, 0.0f);
  if (n == 0 || m.kappa.size() != n || m.scaled.size() != n || m.gcoef.size() != n || m.beam.size() != n ||
      m.beam_dir.size() != L.layer || m.ground.size() != L.layer) {
    return out;
  }
  const double R = grid.earth_radius_m;
  const double dlon = std::abs(grid.lon_deg.step) * kPi / 180.0,
               dlat = std::abs(grid.lat_deg.step) * kPi / 180.0;
  const double hy = R * dlat, hz = std::abs(grid.alt_m.step);
  const bool has_x = L.nx > 1 && dlon > 0.0, has_y = L.ny > 1 && dlat > 0.0, has_z = L.nz > 1 && hz > 0.0;
  if (!has_z) return out;  // one level (or none apart): no column to compare with
  auto hx_at = [&](double lat_deg) { return R * std::max(std::cos(lat_deg * kPi / 180.0), 1e-3) * dlon; };
  auto cloud = [&](std::size_t a) { return m.kappa[a] > 0.0f && std::isfinite(m.kappa[a]); };
  auto beam_at = [&](std::size_t a) {
    return std::isfinite(m.beam[a]) ? std::clamp(double(m.beam[a]), 0.0, 1.0) : 0.0;
  };
  auto gcoef_at = [&](std::size_t a) {
    return std::isfinite(m.gcoef[a]) ? std::clamp(double(m.gcoef[a]), 0.0, 1.0) : 0.0;
  };
  auto scaled_at = [&](std::size_t a) {
    return std::isfinite(m.scaled[a]) ? std::max(double(m.scaled[a]), 0.0) : 0.0;
  };

  // Per column: its cloud depth H (cloudy nodes times the level step; the diffusion coefficient is
  // 1 / (3 kappa + 1 / H), so light in a thin layer spreads sideways about as far as the layer is
  // deep, single scattering's reach, and not the 1 / (3 kappa) of diffusion that grows without
  // bound as the cloud thins) and its lowest cloudy node (the ground lies under it).
  std::vector<double> depth(L.layer, 0.0);
  std::vector<int> lowest(L.layer, -1), highest(L.layer, -1);
  parallel_ranges(L.layer, 1024, [&](std::size_t cb, std::size_t ce, unsigned) {
    for (std::size_t c = cb; c < ce; ++c) {
      for (int k = L.nz - 1; k >= 0; --k) {
        if (!cloud(static_cast<std::size_t>(k) * L.layer + c)) continue;
        depth[c] += hz > 0.0 ? hz : 1.0;
        lowest[c] = k;
        if (highest[c] < 0) highest[c] = k;
      }
    }
  });
  std::vector<Span> spans;
  for (std::size_t c = 0; c < L.layer; ++c) {
    if (lowest[c] >= 0) spans.push_back({c, lowest[c], highest[c]});
  }
  // fn(col, k, a) for every node of the spans, in blocks of spans on the machine's cores; sum adds
  // term(a) over them block by block in a fixed order (the same bits whatever the thread count).
  constexpr std::size_t kSpanBlock = 256;
  const std::size_t span_blocks = (spans.size() + kSpanBlock - 1) / kSpanBlock;
  auto each_block = [&](std::size_t b, auto&& fn) {
    for (std::size_t sp = b * kSpanBlock, se = std::min(spans.size(), sp + kSpanBlock); sp < se; ++sp) {
      const Span& span = spans[sp];
      for (int k = span.k0; k <= span.k1; ++k)
        fn(span.col, k, static_cast<std::size_t>(k) * L.layer + span.col);
    }
  };
  auto each_active = [&](auto&& fn) {
    parallel_ranges(span_blocks, 1, [&](std::size_t bb, std::size_t be, unsigned) {
      for (std::size_t b = bb; b < be; ++b) each_block(b, fn);
    });
  };
  auto sum = [&](auto&& term) {
    std::vector<double> parts(span_blocks, 0.0);
    parallel_ranges(span_blocks, 1, [&](std::size_t bb, std::size_t be, unsigned) {
      for (std::size_t b = bb; b < be; ++b) {
        double part = 0.0;
        each_block(b, [&](std::size_t, int, std::size_t a) { part += term(a); });
        parts[b] = part;
      }
    });
    double total = 0.0;
    for (double v : parts) total += v;
    return total;
  };
  auto diffusion = [&](std::size_t a) { return 1.0 / (3.0 * double(m.kappa[a]) + 1.0 / depth[a % L.layer]); };
  auto beam_dir = [&](std::size_t col) {
    const glm::dvec3 d = m.beam_dir[col];
    return std::isfinite(d.x + d.y + d.z) ? d : glm::dvec3(0.0);
  };

  // The light a clear column's sunlit ground sends into a cloud's side facing it: half the side's
  // view is of that ground, so the partial current coming in is A mu0 E / 2 (s_g = 2 J_in).
  auto side_light = [&](std::size_t col) {
    if (m.ground_light.size() != L.layer) return 0.0;
    const double v = m.ground_light[col];
    return std::isfinite(v) ? std::clamp(v, 0.0, 1.0) : 0.0;
  };
  // Visits the six faces of cloudy node (i, j, k): face(axis, sign, b, area, h, beta, s_g, q) with b
  // the cloudy neighbour across it, or kNone (clear air, the grid's edge, the ground: a Marshak
  // condition with beta and s_g), the face's area, the distance between the nodes, and q the
  // beam's forward flux density out through the face (across an inner face the two nodes' mean).
  auto faces = [&](int i, int j, int k, auto&& face) {
    const std::size_t a = L.at(i, j, k);
    const std::size_t col = a % L.layer;
    const double lat = grid.lat_deg.at(j);
    const double hx = hx_at(lat);
    const glm::dvec3 om = beam_dir(col);
    const double ge = gcoef_at(a) * beam_at(a);
    auto ge_of = [&](std::size_t b) { return gcoef_at(b) * beam_at(b); };
    if (has_z) {
      const double az = hx * hy;
      if (k + 1 < L.nz && cloud(a + L.layer)) {
        face(2, 1, a + L.layer, az, hz, 0.5, 0.0, 0.5 * (ge + ge_of(a + L.layer)) * om.z);
      } else {
        face(2, 1, kNone, az, hz, 0.5, 0.0, ge * om.z);
      }
      if (k > 0 && cloud(a - L.layer)) {
        face(2, -1, a - L.layer, az, hz, 0.5, 0.0, -0.5 * (ge + ge_of(a - L.layer)) * om.z);
      } else if (k == lowest[col]) {  // the ground: a Lambertian surface lit by the beam
        const double alb = std::isfinite(m.ground[col]) ? std::clamp(m.ground[col], 0.0, 1.0) : 0.0;
        face(2, -1, kNone, az, hz, (1.0 - alb) / (2.0 * (1.0 + alb)),
             2.0 * alb * std::max(-om.z, 0.0) * beam_at(a) / (1.0 + alb), -ge * om.z);
      } else {
        face(2, -1, kNone, az, hz, 0.5, 0.0, -ge * om.z);
      }
    }
    if (has_x) {
      const double ax = hy * hz;
      const double hxc = std::max(hx, 0.1 * hy);  // rows next to a pole: the coupling stays bounded
      for (int sign : {1, -1}) {
        int ib = i + sign;
        if (ib < 0 || ib >= L.nx) ib = L.wrap ? (ib + L.nx) % L.nx : -1;
        const std::size_t b = ib >= 0 && ib != i ? L.at(ib, j, k) : kNone;
        if (b != kNone && cloud(b)) {
          face(0, sign, b, ax, hxc, 0.5, 0.0, 0.5 * sign * (ge * om.x + ge_of(b) * beam_dir(b % L.layer).x));
        } else {
          face(0, sign, kNone, ax, hxc, 0.5, b != kNone ? side_light(b % L.layer) : 0.0, sign * ge * om.x);
        }
      }
    }
    if (has_y) {
      for (int sign : {1, -1}) {
        const int jb = j + sign;
        const bool inside = jb >= 0 && jb < L.ny;
        const double ay = (inside ? hx_at(0.5 * (lat + grid.lat_deg.at(jb))) : hx) * hz;
        const std::size_t b = inside ? L.at(i, jb, k) : kNone;
        if (b != kNone && cloud(b)) {
          face(1, sign, b, ay, hy, 0.5, 0.0, 0.5 * sign * (ge * om.y + ge_of(b) * beam_dir(b % L.layer).y));
        } else {
          face(1, sign, kNone, ay, hy, 0.5, b != kNone ? side_light(b % L.layer) : 0.0, sign * ge * om.y);
        }
      }
    }
  };
  // An inner face's coupling: its area times the harmonic mean of the two diffusion coefficients
  // over the distance between the nodes (symmetric).
  auto coupling = [&](std::size_t a, std::size_t b, double area, double h) {
    const double da = diffusion(a), db = diffusion(b);
    return area * 2.0 * da * db / (da + db) / h;
  };
  // A face toward clear air, the grid's edge or the ground: the diffused part of the outward flux,
  // c (phi_a - phi_b) (c = 2 D / h, phi_b at the face), meets Marshak's condition beta phi_b - s_g
  // (beta = 1/2 and s_g = 0 for vacuum; for a Lambertian ground of albedo A, beta = (1 - A) /
  // (2 (1 + A)) and s_g = 2 A mu0 E / (1 + A)), and the beam's forward flux q leaves as it is:
  // Jn = (beta phi_a - s_g) / (1 + beta / c) + q, per unit area. (Marshak's condition on the whole
  // flux, P1's own, made phi negative in thin cloud, where the forward flux outweighs phi / 2:
  // the light scattered forward there leaves the cloud without diffusing.)
  auto boundary_terms = [&](std::size_t a, double h, double beta, double sg, double q, double& per_phi,
                            double& fixed) {
    const double c = 2.0 * diffusion(a) / h;
    const double t = 1.0 + beta / c;
    per_phi = beta / t;
    fixed = -sg / t + q;
  };

  // fn(i, j, k, a, volume) for every node, rows on the machine's cores.
  auto each_node = [&](auto&& fn) {
    parallel_ranges(static_cast<std::size_t>(L.ny), 4, [&](std::size_t jb, std::size_t je, unsigned) {
      for (std::size_t jj = jb; jj < je; ++jj) {
        const int j = static_cast<int>(jj);
        const double vol = hx_at(grid.lat_deg.at(j)) * hy * (hz > 0.0 ? hz : 1.0);
        for (int k = 0; k < L.nz; ++k) {
          for (int i = 0; i < L.nx; ++i) fn(i, j, k, L.at(i, j, k), vol);
        }
      }
    });
  };

  // Both systems, multiplied through by each node's volume: diagonal, couplings east, north and up
  // (the matrix: symmetric, diagonally dominant, positive definite), right-hand sides. Clear nodes
  // hold 1 on the diagonal and 0 on the right. Each node writes only its own row.
  std::vector<double> diag3(n, 0.0), diag1(n, 0.0);
  std::vector<float> wx(has_x ? n : 0, 0.0f), wy(has_y ? n : 0, 0.0f), wz(n, 0.0f);
  std::vector<double> rhs3(n, 0.0), rhs1(n, 0.0);
  each_node([&](int i, int j, int k, std::size_t a, double vol) {
    if (!cloud(a)) {
      diag3[a] = diag1[a] = 1.0;
      return;
    }
    double d3 = 0.0, d1 = 0.0, r3 = vol * scaled_at(a) * beam_at(a), r1 = r3;
    faces(i, j, k,
          [&](int axis, int sign, std::size_t b, double area, double h, double beta, double sg, double q) {
            const bool vertical = axis == 2;
            double dd, rr;
            if (b != kNone) {
              const float w =
                  static_cast<float>(coupling(a, b, area, h));  // the diagonal sums the stored couplings
              dd = double(w);
              rr = -area * q;
              if (sign > 0) (axis == 0 ? wx : axis == 1 ? wy : wz)[a] = w;
            } else {
              double per_phi, fixed;
              boundary_terms(a, h, beta, sg, q, per_phi, fixed);
              dd = area * per_phi;
              rr = -area * fixed;
            }
            d3 += dd, r3 += rr;
            if (vertical) d1 += dd, r1 += rr;
          });
    diag3[a] = d3;
    diag1[a] = d1;
    rhs3[a] = r3;
    rhs1[a] = r1;
  });
  auto by_columns = [&](const std::vector<double>& diag, const double* rhs, double* x) {
    parallel_ranges(spans.size(), 256, [&](std::size_t sb, std::size_t se, unsigned) {
      std::vector<double> scratch;
      for (std::size_t sp = sb; sp < se; ++sp) {
        solve_column(L, spans[sp].col, spans[sp].k0, spans[sp].k1, diag, wz, rhs, x, scratch);
      }
    });
  };
  // The independent columns.
  std::vector<double> phi1(n, 0.0);
  by_columns(diag1, rhs1.data(), phi1.data());
  std::vector<double>().swap(diag1);
  std::vector<double>().swap(rhs1);

  // y = A x for the 3-D matrix (on the spans; elsewhere both are 0).
  auto apply = [&](const std::vector<double>& x, std::vector<double>& y) {
    each_active([&](std::size_t col, int k, std::size_t a) {
      double v = diag3[a] * x[a];
      if (k + 1 < L.nz) v -= double(wz[a]) * x[a + L.layer];
      if (k > 0) v -= double(wz[a - L.layer]) * x[a - L.layer];
      const std::size_t row = static_cast<std::size_t>(L.nx);
      const std::size_t i = col % row, j = col / row;
      if (has_x) {
        const std::size_t e = i + 1 < row ? a + 1 : a + 1 - row;
        const std::size_t w = i > 0 ? a - 1 : a + row - 1;
        v -= double(wx[a]) * x[e] + double(wx[w]) * x[w];
      }
      if (has_y) {
        if (j + 1 < static_cast<std::size_t>(L.ny)) v -= double(wy[a]) * x[a + row];
        if (j > 0) v -= double(wy[a - row]) * x[a - row];
      }
      y[a] = v;
    });
  };
  // Conjugate gradients from the columns' solution, preconditioned by each column's part of the
  // 3-D matrix (block Jacobi: the vertical coupling is the strong one).
  std::vector<double> phi3 = phi1, r(n, 0.0), z(n, 0.0), p, q(n, 0.0);
  apply(phi3, q);
  each_active([&](std::size_t, int, std::size_t a) { r[a] = rhs3[a] - q[a]; });
  const double bnorm = std::sqrt(sum([&](std::size_t a) { return rhs3[a] * rhs3[a]; }));
  std::vector<double>().swap(rhs3);
  by_columns(diag3, r.data(), z.data());
  p = z;
  double rz = sum([&](std::size_t a) { return r[a] * z[a]; });
  double res = bnorm > 0.0 ? std::sqrt(sum([&](std::size_t a) { return r[a] * r[a]; })) / bnorm : 0.0;
  int it = 0;
  while (res > tolerance && it < max_iterations && rz > 0.0 && std::isfinite(rz)) {
    apply(p, q);
    const double pq = sum([&](std::size_t a) { return p[a] * q[a]; });
    if (!(pq > 0.0) || !std::isfinite(pq)) break;
    const double alpha = rz / pq;
    each_active([&](std::size_t, int, std::size_t a) {
      phi3[a] += alpha * p[a];
      r[a] -= alpha * q[a];
    });
    ++it;
    res = std::sqrt(sum([&](std::size_t a) { return r[a] * r[a]; })) / bnorm;
    by_columns(diag3, r.data(), z.data());
    const double rz_new = sum([&](std::size_t a) { return r[a] * z[a]; });
    const double beta = rz_new / rz;
    rz = rz_new;
    each_active([&](std::size_t, int, std::size_t a) { p[a] = z[a] + beta * p[a]; });
  }
  out.iterations = it;
  out.residual = res;

  // Per cloudy node: the ratio, and the 3-D solution's horizontal flux by diffusion, -D grad phi
  // (the mean of the node's two faces along each axis; the beam's own forward flux left out, see
  // the header), as the first moment over the mean radiance, 3 F / phi, at most 1 in length.
  std::vector<double> put_row(static_cast<std::size_t>(L.ny), 0.0),
      out_row(static_cast<std::size_t>(L.ny), 0.0);
  each_node([&](int i, int j, int k, std::size_t a, double vol) {
    if (!cloud(a)) return;
    const std::size_t jj = static_cast<std::size_t>(j);
    put_row[jj] += vol * scaled_at(a) * beam_at(a);
    faces(i, j, k, [&](int, int, std::size_t b, double area, double h, double beta, double sg, double qf) {
      if (b != kNone) return;
      double per_phi, fixed;
      boundary_terms(a, h, beta, sg, qf, per_phi, fixed);
      out_row[jj] += area * (per_phi * phi3[a] + fixed);
    });
    const double v3 = phi3[a], v1 = phi1[a];
    // No column light (v1 <= 0): nothing to scale, the ratio stays 1; no 3-D light: 0.
    if (v1 > 0.0 && std::isfinite(v3 / v1))
      out.ratio[a] = static_cast<float>(std::clamp(v3 / v1, 0.0, kLateralRatioMax));
    if (!(v3 > 0.0) || !std::isfinite(v3)) return;
    double flux[2] = {0.0, 0.0};
    faces(i, j, k,
          [&](int axis, int sign, std::size_t b, double area, double h, double beta, double sg, double qf) {
            if (axis == 2) return;
            double diffused;  // per unit area, out through the face
            if (b != kNone) {
              diffused = coupling(a, b, area, h) * (phi3[a] - phi3[b]) / area;
            } else {
              double per_phi, fixed;
              boundary_terms(a, h, beta, sg, qf, per_phi, fixed);
              diffused = per_phi * phi3[a] + fixed - qf;
            }
            flux[axis] += 0.5 * sign * diffused;
          });
    const double fe = 3.0 * flux[0] / v3, fn = 3.0 * flux[1] / v3;
    const double len = std::hypot(fe, fn);
    if (!std::isfinite(len)) return;
    const double keep = len > 1.0 ? 1.0 / len : 1.0;  // I0 + I1 . Omega stays >= 0
    out.east[a] = static_cast<float>(fe * keep);
    out.north[a] = static_cast<float>(fn * keep);
  });
  for (std::size_t j = 0; j < put_row.size(); ++j) out.put_in += put_row[j], out.let_out += out_row[j];
  // Clear nodes of a cloudy column (the fringe above a top or below a base, a gap between layers)
  // take the ratio and the horizontal moments of the column's nearest cloudy node: the march
  // interpolates between them and the cloud's nodes.
  parallel_ranges(L.layer, 256, [&](std::size_t cb, std::size_t ce, unsigned) {
    std::vector<int> nearest(static_cast<std::size_t>(L.nz));
    for (std::size_t c = cb; c < ce; ++c) {
      if (lowest[c] < 0) continue;
      int last = -1;
      for (int k = 0; k < L.nz; ++k) {
        if (cloud(static_cast<std::size_t>(k) * L.layer + c)) last = k;
        nearest[static_cast<std::size_t>(k)] = last;
      }
      last = -1;
      for (int k = L.nz - 1; k >= 0; --k) {
        if (cloud(static_cast<std::size_t>(k) * L.layer + c)) last = k;
        int& nk = nearest[static_cast<std::size_t>(k)];
        if (nk < 0 || (last >= 0 && last - k < k - nk)) nk = last;
      }
      for (int k = 0; k < L.nz; ++k) {
        const std::size_t a = static_cast<std::size_t>(k) * L.layer + c;
        if (cloud(a)) continue;
        const std::size_t b = static_cast<std::size_t>(nearest[static_cast<std::size_t>(k)]) * L.layer + c;
        out.ratio[a] = out.ratio[b];
        out.east[a] = out.east[b];
        out.north[a] = out.north[b];
      }
    }
  });
  return out;
}

}  // namespace cv::core
