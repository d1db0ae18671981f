// Tileable Perlin, Worley and their fBm blends, generated on the CPU into periodic textures.
#include "noise/noise.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <thread>

#include <glm/glm.hpp>

#include "physics/physics.hpp"

namespace cv::core {
namespace {

// An integer mixer with good avalanche (the "lowbias32" constants): every input bit changes about
// half the output bits, so neighbouring lattice cells get unrelated gradients and feature points.
std::uint32_t mix32(std::uint32_t x) {
  x ^= x >> 16;
  x *= 0x7feb352du;
  x ^= x >> 15;
  x *= 0x846ca68bu;
  x ^= x >> 16;
  return x;
}

// The hash of a lattice cell, taken modulo the period first: that is what makes the noise tile.
std::uint32_t cell_hash(int i, int j, int k, int period, std::uint32_t seed) {
  auto wrap = [period](int v) { return static_cast<std::uint32_t>(((v % period) + period) % period); };
  return mix32(seed ^ mix32(wrap(i) + mix32(wrap(j) + mix32(wrap(k)))));
}

double unit(std::uint32_t h) { return (h >> 8) * (1.0 / 16777216.0); }  // [0, 1) from 24 bits

// Perlin's quintic fade: its first and second derivatives vanish at 0 and 1, so the noise's
// gradient is continuous across cell faces (and so across the tile's seam).
double fade(double t) { return t * t * t * (t * (t * 6.0 - 15.0) + 10.0); }

// The twelve cube-edge gradients of improved Perlin noise.
double grad_dot(std::uint32_t h, double x, double y, double z) {
  switch (h % 12u) {
    case 0: return x + y;
    case 1: return -x + y;
    case 2: return x - y;
    case 3: return -x - y;
    case 4: return x + z;
    case 5: return -x + z;
    case 6: return x - z;
    case 7: return -x - z;
    case 8: return y + z;
    case 9: return -y + z;
    case 10: return y - z;
    default: return -y - z;
  }
}

// Perlin gradient noise at p (lattice cells), with hash(i, j, k) giving each lattice point's
// gradient: periodic when the hash is.
template <class Hash>
double perlin_with(const glm::dvec3& p, Hash hash) {
  const int i = static_cast<int>(std::floor(p.x)), j = static_cast<int>(std::floor(p.y)), k = static_cast<int>(std::floor(p.z));
  const double x = p.x - i, y = p.y - j, z = p.z - k;
  auto g = [&](int a, int b, int c) { return grad_dot(hash(i + a, j + b, k + c), x - a, y - b, z - c); };
  const double u = fade(x), v = fade(y), w = fade(z);
  auto lerp = [](double a, double b, double t) { return a + t * (b - a); };
  return lerp(lerp(lerp(g(0, 0, 0), g(1, 0, 0), u), lerp(g(0, 1, 0), g(1, 1, 0), u), v),
              lerp(lerp(g(0, 0, 1), g(1, 0, 1), u), lerp(g(0, 1, 1), g(1, 1, 1), u), v), w);
}

// Worley F1 (distance to the nearest feature point, in cells) at p, one feature point per cell
// placed by hash(cell): the nearest one lies in the 3 x 3 x 3 cells around p.
template <class Hash>
double worley_with(const glm::dvec3& p, Hash hash) {
  const glm::dvec3 cell = glm::floor(p);
  double best = 1e300;
  for (int c = -1; c <= 1; ++c)
    for (int b = -1; b <= 1; ++b)
      for (int a = -1; a <= 1; ++a) {
        const glm::dvec3 q = cell + glm::dvec3(a, b, c);
        std::uint32_t h = hash(int(q.x), int(q.y), int(q.z));
        glm::dvec3 feature;
        for (int d = 0; d < 3; ++d) {
          h = mix32(h + 0x9e3779b9u);
          feature[d] = q[d] + unit(h);
        }
        const glm::dvec3 e = feature - p;
        best = std::min(best, glm::dot(e, e));
      }
  return std::sqrt(best);
}

// The hashes of one period^3 lattice, computed once: generation reads them instead of rehashing
// the same few thousand cells millions of times. Same values as cell_hash.
struct Lattice {
  int period;
  std::vector<std::uint32_t> h;
  Lattice(int period_, std::uint32_t seed) : period(period_), h(static_cast<std::size_t>(period_) * period_ * period_) {
    for (int k = 0; k < period; ++k)
      for (int j = 0; j < period; ++j)
        for (int i = 0; i < period; ++i) h[(static_cast<std::size_t>(k) * period + j) * period + i] = cell_hash(i, j, k, period, seed);
  }
  std::uint32_t operator()(int i, int j, int k) const {
    auto w = [this](int v) { return ((v % period) + period) % period; };
    return h[(static_cast<std::size_t>(w(k)) * period + w(j)) * period + w(i)];
  }
};

// Inverted-Worley fBm over tile coordinates u: three octaves from `cells` cells per tile, weights
// 0.625, 0.25, 0.125 (sum 1). Near a feature point it is 1; far from all of them, 0 (billows).
double worley_fbm(const glm::dvec3& u, const Lattice (&oct)[3]) {
  const double w[3] = {0.625, 0.25, 0.125};
  double sum = 0.0;
  for (int o = 0; o < 3; ++o) sum += w[o] * (1.0 - std::min(worley_with(u * double(oct[o].period), oct[o]), 1.0));
  return sum;
}

// Perlin fBm over tile coordinates u: three octaves from `cells` cells per tile, amplitudes halving.
double perlin_fbm(const glm::dvec3& u, const Lattice (&oct)[3]) {
  double sum = 0.0, amp = 1.0, norm = 0.0;
  for (int o = 0; o < 3; ++o, amp *= 0.5) {
    sum += amp * perlin_with(u * double(oct[o].period), oct[o]);
    norm += amp;
  }
  return sum / norm;
}

// The lattices of three octaves from `cells` cells per tile, each octave with its own seed.
struct Octaves {
  Lattice o[3];
  Octaves(int cells, std::uint32_t seed)
      : o{Lattice(cells, seed), Lattice(cells * 2, seed + 101u), Lattice(cells * 4, seed + 202u)} {}
};

// Fills n^3 values of fn(tile coordinates) over slabs of k in parallel.
template <class Fn>
std::vector<double> fill(int n, unsigned threads, Fn fn) {
  std::vector<double> out(static_cast<std::size_t>(n) * n * n);
  auto slab = [&](int k0, int k1) {
    for (int k = k0; k < k1; ++k)
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i)
          out[(static_cast<std::size_t>(k) * n + j) * n + i] = fn(glm::dvec3(i, j, k) / double(n));
  };
  const int t = static_cast<int>(std::clamp(threads, 1u, static_cast<unsigned>(n)));
  std::vector<std::thread> pool;
  for (int s = 1; s < t; ++s) pool.emplace_back(slab, n * s / t, n * (s + 1) / t);
  slab(0, n / t);
  for (auto& th : pool) th.join();
  return out;
}

// Stretches values onto [0, 1] by their own extremes (a tiling-preserving affine map).
void normalise(std::vector<double>& v) {
  const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
  const double a = *lo, span = *hi - *lo > 0.0 ? *hi - *lo : 1.0;
  for (double& x : v) x = (x - a) / span;
}

NoiseTexture to_texture(int n, const std::vector<double>& v) {
  NoiseTexture t;
  t.n = n;
  t.texels.resize(v.size());
  // The clamp only absorbs rounding: the values are in [0, 1] by construction.
  for (std::size_t i = 0; i < v.size(); ++i) t.texels[i] = static_cast<float>(std::clamp(v[i], 0.0, 1.0));
  return t;
}

}  // namespace

double perlin_periodic(const glm::dvec3& p, int period, std::uint32_t seed) {
  return perlin_with(p, [&](int i, int j, int k) { return cell_hash(i, j, k, period, seed); });
}

double worley_periodic(const glm::dvec3& p, int period, std::uint32_t seed) {
  return worley_with(p, [&](int i, int j, int k) { return cell_hash(i, j, k, period, seed); });
}

double NoiseTexture::sample(const glm::dvec3& t) const {
  namespace p64 = cv::physics::f64;
  int i0[3], i1[3];
  double w[3];
  for (int d = 0; d < 3; ++d) p64::noise_texel_pair(t[d], n, i0[d], i1[d], w[d]);
  // The same order of interpolation as fetch_noise in shaders/kernel/march.glsl: x, then y, then z.
  auto mx = [](double a, double b, double s) { return a * (1.0 - s) + b * s; };
  const double c00 = mx(at(i0[0], i0[1], i0[2]), at(i1[0], i0[1], i0[2]), w[0]);
  const double c10 = mx(at(i0[0], i1[1], i0[2]), at(i1[0], i1[1], i0[2]), w[0]);
  const double c01 = mx(at(i0[0], i0[1], i1[2]), at(i1[0], i0[1], i1[2]), w[0]);
  const double c11 = mx(at(i0[0], i1[1], i1[2]), at(i1[0], i1[1], i1[2]), w[0]);
  return mx(mx(c00, c10, w[1]), mx(c01, c11, w[1]), w[2]);
}

ErosionNoise make_erosion_noise(int low_n, int high_n, std::uint32_t seed, unsigned threads) {
  if (threads == 0) threads = std::max(1u, std::thread::hardware_concurrency());
  // Base frequency: 4 cells per tile, so the three octaves (4, 8, 16 cells) keep at least two
  // texels per cell at 32 texels.
  constexpr int kCells = 4;
  const Octaves perlin_oct(kCells, seed), worley_oct(kCells, seed + 1000u), high_oct(kCells, seed + 2000u);
  std::vector<double> perlin = fill(low_n, threads, [&](const glm::dvec3& u) { return perlin_fbm(u, perlin_oct.o); });
  std::vector<double> worley = fill(low_n, threads, [&](const glm::dvec3& u) { return worley_fbm(u, worley_oct.o); });
  normalise(perlin);
  normalise(worley);
  // Perlin-Worley: remap(perlin, worley - 1, 1, 0, 1) = (perlin - worley + 1) / (2 - worley).
  // It is perlin where worley = 1 and lifts perlin toward 1 where worley is small, so the Perlin
  // pattern gets Worley's rounded billows; for perlin, worley in [0, 1] it stays in [0, 1].
  // Its lower end is above 0 (perlin = 0 and worley = 1 rarely meet), so it is stretched again to
  // use the whole range: the erosion threshold then spans [0, amount].
  for (std::size_t i = 0; i < perlin.size(); ++i) perlin[i] = (perlin[i] - worley[i] + 1.0) / (2.0 - worley[i]);
  normalise(perlin);
  std::vector<double> high = fill(high_n, threads, [&](const glm::dvec3& u) { return worley_fbm(u, high_oct.o); });
  normalise(high);
  return {to_texture(low_n, perlin), to_texture(high_n, high), {}};
}

std::vector<float> detail_table(const NoiseTexture& low, const NoiseTexture& high, std::size_t samples, unsigned threads) {
  namespace p64 = cv::physics::f64;
  if (threads == 0) threads = std::max(1u, std::thread::hardware_concurrency());
  const std::size_t count = std::max<std::size_t>(samples, 1024);
  std::vector<double> v(count);
  std::vector<std::uint8_t> slice_of(count);  // the point's horizontal slice, by its height in the tile
  // The first points' tile coordinates along longitude and latitude, for the first moments.
  const std::size_t moment_count = std::min<std::size_t>(count, std::size_t(1) << 20);
  std::vector<float> tx(moment_count), ty(moment_count);
  // The kernel's noise (march.glsl detail_factor) at uniform random points of the tile, point i's
  // coordinates from a hash of i: the same points whatever the threads. A regular lattice would
  // alias with the textures' texels (a 64^3 lattice gave a mean ramp 7 % off at 5 % cover).
  std::vector<std::thread> pool;
  for (unsigned w = 0; w < threads; ++w) {
    pool.emplace_back([&, w] {
      for (std::size_t i = w; i < count; i += threads) {
        std::uint64_t h = 0x9e3779b97f4a7c15ull * (i + 1);
        auto next = [&h] {
          h += 0x9e3779b97f4a7c15ull;
          std::uint64_t z = h;
          z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
          z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
          return double((z ^ (z >> 31)) >> 11) * 0x1.0p-53;
        };
        const glm::dvec3 t(next(), next(), next());
        const glm::dvec3 th(p64::noise_high_coords(t));
        v[i] = p64::detail_noise_mix(low.sample(t), high.sample(th));
        slice_of[i] = static_cast<std::uint8_t>(std::min(CV_DETAIL_SLICES - 1, static_cast<int>(t.z * CV_DETAIL_SLICES)));
        if (i < moment_count) tx[i] = static_cast<float>(t.x), ty[i] = static_cast<float>(t.y);
      }
    });
  }
  for (std::thread& t : pool) t.join();
  // The moment points sorted by their noise (before v is sorted in place).
  std::vector<std::uint32_t> order(moment_count);
  for (std::size_t i = 0; i < moment_count; ++i) order[i] = static_cast<std::uint32_t>(i);
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return v[a] < v[b]; });
  // Each slice's values, sorted (before v is sorted in place).
  std::vector<std::vector<double>> slices(CV_DETAIL_SLICES);
  for (auto& sl : slices) sl.reserve(count / CV_DETAIL_SLICES + count / (4 * CV_DETAIL_SLICES));
  for (std::size_t i = 0; i < count; ++i) slices[slice_of[i]].push_back(v[i]);
  std::vector<double> mn(moment_count);
  std::vector<float> mx(moment_count), my(moment_count);
  for (std::size_t i = 0; i < moment_count; ++i) mn[i] = v[order[i]], mx[i] = tx[order[i]], my[i] = ty[order[i]];
  std::sort(v.begin(), v.end());
  constexpr std::size_t row = CV_DETAIL_COVERS + 1;
  std::vector<float> table(2 * row * CV_DETAIL_ROWS);
  // One set of rows (the types' threshold and ramp mean per cover) from sorted values w: the whole
  // tile's at row0 = 0, each slice's at its own rows.
  auto fill_rows = [&](const std::vector<double>& w, std::size_t row0) {
    const std::size_t n = w.size();
    if (n == 0) return;
    // Prefix sums of the sorted values: the mean of the ramp above any threshold in O(log N).
    std::vector<double> prefix(n + 1, 0.0);
    for (std::size_t i = 0; i < n; ++i) prefix[i + 1] = prefix[i] + w[i];
    auto ramp_mean = [&](double t, double s) {
      // Points in (t, t + s) contribute (n - t) / s, points from t + s up contribute 1.
      const std::size_t a = static_cast<std::size_t>(std::upper_bound(w.begin(), w.end(), t) - w.begin());
      const std::size_t b = static_cast<std::size_t>(std::lower_bound(w.begin(), w.end(), t + s) - w.begin());
      const double ramp = (prefix[b] - prefix[a] - t * double(b - a)) / s;
      return (ramp + double(n - b)) / double(n);
    };
    for (int c = 0; c <= CV_DETAIL_COVERS; ++c) {
      // The share c of the points lies above t: t is the value at rank (1 - c) N (the largest for c = 0).
      const double share = (double(c) / CV_DETAIL_COVERS) * (double(c) / CV_DETAIL_COVERS);  // denser at low cover
      const double rank = (1.0 - share) * double(n);
      const std::size_t r = std::min(n - 1, static_cast<std::size_t>(std::max(0.0, rank)));
      const double t = c == 0 ? w.back() : c == CV_DETAIL_COVERS ? w.front() - 1e-9 : w[r];
      // A slice's covers with fewer than kSliceTail of its points above the threshold take the whole
      // tile's entries: from a handful of points the slice's ramp mean m is noise, and c / m (the
      // tracking's majorant, medium_majorant) came out 40 times the tile's.
      constexpr double kSliceTail = 256.0;
      if (row0 != 0 && share * double(n) < kSliceTail) {
        for (int type = 0; type < CV_DETAIL_TYPES; ++type) {
          const std::size_t e = 2 * ((row0 + std::size_t(type)) * row + static_cast<std::size_t>(c));
          const std::size_t g = 2 * (std::size_t(type) * row + static_cast<std::size_t>(c));
          table[e] = table[g];
          table[e + 1] = table[g + 1];
        }
        continue;
      }
      for (int type = 0; type < CV_DETAIL_TYPES; ++type) {  // the same threshold, each type's ramp
        const std::size_t e = 2 * ((row0 + std::size_t(type)) * row + static_cast<std::size_t>(c));
        table[e] = static_cast<float>(t);
        table[e + 1] = static_cast<float>(ramp_mean(t, p64::detail_softness(type)));
      }
    }
  };
  fill_rows(v, 0);
  {
    std::vector<std::thread> sorters;
    for (unsigned w = 0; w < threads; ++w) {
      sorters.emplace_back([&, w] {
        for (int j = int(w); j < CV_DETAIL_SLICES; j += int(threads)) {
          std::sort(slices[std::size_t(j)].begin(), slices[std::size_t(j)].end());
          fill_rows(slices[std::size_t(j)], std::size_t(CV_DETAIL_SLICE_ROW0) + std::size_t(j) * CV_DETAIL_TYPES);
        }
      });
    }
    for (std::thread& t : sorters) t.join();
  }
  // The first moments (detail.glsl detail_first_moment): for each type, phase phi = p / PHASES and
  // cover, M = E[(fract(u - phi) - 1/2) h(n; t(c), s) / m(c)] along longitude (x) and latitude (y),
  // from the moment points sorted by n: prefix sums of g = fract(u - phi) - 1/2 and of g n give the
  // ramp's share above any threshold, as ramp_mean does.
  const std::size_t mc = moment_count;
  std::vector<std::thread> workers;
  for (unsigned w = 0; w < threads; ++w) {
    workers.emplace_back([&, w] {
      std::vector<double> pg(mc + 1), pgn(mc + 1);
      for (int job = int(w); job < 2 * CV_DETAIL_PHASES; job += int(threads)) {
        const int axis = job % 2, p = job / 2;
        const double phi = double(p) / CV_DETAIL_PHASES;
        const std::vector<float>& u = axis == 0 ? mx : my;
        pg[0] = pgn[0] = 0.0;
        for (std::size_t i = 0; i < mc; ++i) {
          double g = double(u[i]) - phi;
          g -= std::floor(g);
          g -= 0.5;
          pg[i + 1] = pg[i] + g, pgn[i + 1] = pgn[i] + g * mn[i];
        }
        for (int c = 0; c <= CV_DETAIL_COVERS; ++c) {
          const double t = table[2 * static_cast<std::size_t>(c)];  // the threshold (every type's row has it)
          const std::size_t a = static_cast<std::size_t>(std::upper_bound(mn.begin(), mn.end(), t) - mn.begin());
          for (int type = 0; type < CV_DETAIL_TYPES; ++type) {
            const double sft = p64::detail_softness(type);
            const double m = table[2 * (std::size_t(type) * row + static_cast<std::size_t>(c)) + 1];
            const std::size_t b = static_cast<std::size_t>(std::lower_bound(mn.begin(), mn.end(), t + sft) - mn.begin());
            const double sum = (pgn[b] - pgn[a] - t * (pg[b] - pg[a])) / sft + (pg[mc] - pg[b]);
            const double moment = m > 0.0 ? sum / double(mc) / m : 0.0;
            const std::size_t r = CV_DETAIL_TYPES + std::size_t(type) * CV_DETAIL_PHASES + std::size_t(p);
            table[2 * (r * row + static_cast<std::size_t>(c)) + std::size_t(axis)] = static_cast<float>(moment);
          }
        }
      }
    });
  }
  for (std::thread& t : workers) t.join();
  return table;
}

NoiseAnchor noise_anchor(const glm::dvec3& centre_ecef_m, double period_m) {
  NoiseAnchor a;
  a.ecef_m = glm::dvec3(glm::vec3(centre_ecef_m));
  const glm::dvec3 tiles = a.ecef_m / period_m;
  a.frac = tiles - glm::floor(tiles);
  return a;
}

}  // namespace cv::core
