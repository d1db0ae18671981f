// Ray/sphere and ray/shell intersection in the float32 camera-relative form against a long double
// reference: camera altitudes 0.1 m to 4e8 m, rays from nadir to zenith and within a few ulps of
// tangency, cameras below, inside and above the shell.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "physics/physics.hpp"

namespace {
using namespace cv::physics;
using ld = long double;

constexpr float kR0 = 6371000.0f;
constexpr float kBase = 1000.0f, kTop = 20000.0f;  // a cloud shell from 1 km to 20 km

struct Hit {
  bool hit = false;
  ld t0 = 0, t1 = 0;
};

// The reference: the same geometric ray (the float inputs, read exactly) in 64-bit-significand
// arithmetic, with the cancellation-free near root.
Hit reference(ld r0, ld h, ld mu, ld hs) {
  const ld r = r0 + h;
  const ld b = r * mu;
  const ld c = (h - hs) * (2 * r0 + h + hs);
  const ld disc = b * b - c;
  if (disc < 0) return {};
  const ld sq = std::sqrt(disc);
  const ld q = -(b + (b >= 0 ? sq : -sq));
  if (q == 0) return {true, 0, 0};
  const ld ta = q, tb = c / q;
  return {true, std::min(ta, tb), std::max(ta, tb)};
}

ld tolerance(ld t) { return 0.01L + 1e-6L * std::abs(t); }

std::vector<float> altitudes() {
  return {0.1f, 1.0f, 10.0f, 100.0f, 999.0f, 1000.0f, 5000.0f, 19999.0f, 25000.0f, 1e5f, 1e6f, 3.6e7f, 4e8f};
}

// Ray cosines: nadir to zenith on a grid, plus every sphere's tangent cosine and 8 ulps either side.
std::vector<float> cosines(float h) {
  std::vector<float> mus;
  for (int i = 0; i <= 720; ++i) mus.push_back(static_cast<float>(-std::cos(3.14159265358979323846L * i / 720)));
  for (float hs : {0.0f, kBase, kTop}) {
    if (h <= hs) continue;
    const ld r = static_cast<ld>(kR0) + h, rs = static_cast<ld>(kR0) + hs;
    float mu = static_cast<float>(-std::sqrt(1 - (rs / r) * (rs / r)));
    for (int k = 0; k < 8; ++k) mu = std::nextafter(mu, -1.0f);
    for (int k = 0; k <= 16; ++k, mu = std::nextafter(mu, 1.0f)) mus.push_back(mu);
  }
  return mus;
}

TEST(Intersect, CameraRelativeSphereAgainstReference) {
  long n = 0;
  ld worst = 0;  // error / tolerance
  for (float h : altitudes()) {
    for (float hs : {0.0f, kBase, kTop}) {
      for (float mu : cosines(h)) {
        const Hit ref = reference(kR0, h, mu, hs);
        float t0 = 0, t1 = 0;
        const bool hit = f32::ray_sphere_rel(kR0, h, mu, hs, t0, t1);
        ASSERT_EQ(hit, ref.hit) << "h=" << h << " hs=" << hs << " mu=" << mu;
        ++n;
        if (!hit) continue;
        ASSERT_TRUE(std::isfinite(t0) && std::isfinite(t1));
        worst = std::max({worst, std::abs(t0 - ref.t0) / tolerance(ref.t0), std::abs(t1 - ref.t1) / tolerance(ref.t1)});
        EXPECT_LE(std::abs(t0 - ref.t0), tolerance(ref.t0)) << "h=" << h << " hs=" << hs << " mu=" << mu;
        EXPECT_LE(std::abs(t1 - ref.t1), tolerance(ref.t1)) << "h=" << h << " hs=" << hs << " mu=" << mu;
      }
    }
  }
  std::printf("%ld rays; worst distance error is %.3f of the tolerance (1 cm + 1e-6 relative)\n", n,
              static_cast<double>(worst));
}

TEST(Intersect, SineFormAgainstReference) {
  // A caller's mu = d . up and nu = |d x up| are each accurate where they are the smaller. The
  // reference is the geometry the accurate one stands for: mu's near the horizontal, nu's (with
  // mu's sign) near the vertical, where mu rounds toward +-1.
  ld worst = 0;
  long n = 0;
  for (float h : altitudes()) {
    for (float hs : {0.0f, kBase, kTop}) {
      for (float mu : cosines(h)) {
        const float nu = static_cast<float>(std::sqrt((1 - static_cast<ld>(mu)) * (1 + static_cast<ld>(mu))));
        const bool vertical = std::abs(mu) >= nu;
        const ld mu_ref = vertical ? (mu < 0 ? -1 : 1) * std::sqrt(std::max(0.0L, 1 - static_cast<ld>(nu) * nu)) : mu;
        const Hit ref = reference(kR0, h, mu_ref, hs);
        float t0 = 0, t1 = 0;
        const bool hit = f32::ray_sphere_rel_nu(kR0, h, mu, nu, hs, t0, t1);
        ASSERT_EQ(hit, ref.hit) << "h=" << h << " hs=" << hs << " mu=" << mu;
        ++n;
        if (!hit) continue;
        worst = std::max({worst, std::abs(t0 - ref.t0) / tolerance(ref.t0), std::abs(t1 - ref.t1) / tolerance(ref.t1)});
      }
    }
  }
  EXPECT_LE(worst, 1.0);
  std::printf("sine form: %ld rays, worst distance error %.3f of the tolerance\n", n, static_cast<double>(worst));
}

TEST(Intersect, TangentAndMissingRaysAreClassifiedRight) {
  // From 4e8 m the Earth spans +-0.9 degrees: a horizontal ray misses, the nadir ray hits.
  float t0, t1;
  EXPECT_FALSE(f32::ray_sphere_rel(kR0, 4e8f, 0.0f, kTop, t0, t1));
  EXPECT_TRUE(f32::ray_sphere_rel(kR0, 4e8f, -1.0f, kTop, t0, t1));
  EXPECT_NEAR(t0, 4e8f - kTop, tolerance(4e8L));
  // Within ulps of tangency both outcomes occur, and each agrees with the reference (checked in
  // the sweep above); here we make sure the sweep really straddles tangency at every altitude.
  for (float h : {0.1f, 100.0f, 25000.0f, 4e8f}) {
    int hits = 0, misses = 0;
    const ld r = static_cast<ld>(kR0) + h;
    float mu = static_cast<float>(-std::sqrt(1 - (kR0 / r) * (kR0 / r)));
    for (int k = 0; k < 8; ++k) mu = std::nextafter(mu, -1.0f);
    for (int k = 0; k <= 16; ++k, mu = std::nextafter(mu, 1.0f)) {
      (f32::ray_sphere_rel(kR0, h, mu, 0.0f, t0, t1) ? hits : misses)++;
    }
    EXPECT_GT(hits, 0) << "h=" << h;
    EXPECT_GT(misses, 0) << "h=" << h;
  }
  // A ray exactly tangent from a point on the sphere: one touching point at t = 0.
  EXPECT_TRUE(f32::ray_sphere_rel(kR0, kBase, 0.0f, kBase, t0, t1));
  EXPECT_EQ(t0, 0.0f);
  EXPECT_EQ(t1, 0.0f);
}

TEST(Intersect, NaiveFloatFormLosesWhatTheRelativeFormKeeps) {
  // The brief's example: c = |o|^2 - R^2 in float32 at a few metres altitude is mostly rounding.
  const float h = 2.0f;
  const float o = kR0 + h;
  const float c_naive = o * o - kR0 * kR0;
  const double c_true = double(h) * (2.0 * kR0 + h);
  EXPECT_GT(std::abs(c_naive - c_true) / c_true, 0.01);
  float t0, t1;
  ASSERT_TRUE(f32::ray_sphere_rel(kR0, h, -1.0f, 0.0f, t0, t1));
  EXPECT_NEAR(t0, 2.0f, 1e-6f);
}

struct Segs {
  int n = 0;
  ld s[4] = {0, 0, 0, 0};
};

// Merges segments that touch (tangency may split one segment at a point).
Segs merged(Segs x, ld tol) {
  if (x.n == 2 && x.s[2] - x.s[1] <= tol) return {1, {x.s[0], x.s[3], 0, 0}};
  return x;
}

Segs reference_shell(ld h, ld mu) {
  const Hit o = reference(kR0, h, mu, kTop);
  if (!o.hit || o.t1 < 0) return {};
  const Hit i = reference(kR0, h, mu, kBase);
  const ld start = std::max(o.t0, 0.0L);
  if (!i.hit || i.t1 < 0) return {1, {start, o.t1, 0, 0}};
  if (i.t0 > start) return {2, {start, i.t0, std::max(i.t1, 0.0L), o.t1}};
  return {1, {std::max(i.t1, 0.0L), o.t1, 0, 0}};
}

TEST(Intersect, ShellSegmentsBelowInsideAndAboveTheShell) {
  ld worst = 0;
  int two = 0;
  for (float h : altitudes()) {
    for (float mu : cosines(h)) {
      Segs ref = reference_shell(h, mu);
      glm::vec4 seg;
      Segs got;
      got.n = f32::ray_shell_rel(kR0, h, mu, kBase, kTop, seg);
      for (int k = 0; k < 4; ++k) got.s[k] = seg[k];
      const ld tol = tolerance(ref.n ? ref.s[2 * ref.n - 1] : 0);
      ref = merged(ref, tol);
      got = merged(got, tol);
      ASSERT_EQ(got.n, ref.n) << "h=" << h << " mu=" << mu;
      two += ref.n == 2;
      for (int k = 0; k < 2 * ref.n; ++k) {
        worst = std::max(worst, std::abs(got.s[k] - ref.s[k]) / tolerance(ref.s[k]));
        EXPECT_LE(std::abs(got.s[k] - ref.s[k]), tolerance(ref.s[k])) << "h=" << h << " mu=" << mu << " k=" << k;
      }
    }
  }
  EXPECT_GT(two, 0);  // the sweep includes rays that dip into the shell and leave it again
  std::printf("shell segments: worst error %.3f of the tolerance\n", static_cast<double>(worst));
}

TEST(Intersect, ShellFromBelowInsideAndAbove) {
  glm::vec4 seg;
  // Below the base, looking up: one segment from base to top.
  ASSERT_EQ(f32::ray_shell_rel(kR0, 10.0f, 1.0f, kBase, kTop, seg), 1);
  EXPECT_NEAR(seg.x, kBase - 10.0f, 1e-3f);
  EXPECT_NEAR(seg.y, kTop - 10.0f, 1e-3f);
  // Inside, looking down: from the camera to the base, and again where the ray, passing through
  // the Earth (the shell knows nothing of the ground; the renderer clips at it), leaves far side.
  ASSERT_EQ(f32::ray_shell_rel(kR0, 5000.0f, -1.0f, kBase, kTop, seg), 2);
  EXPECT_EQ(seg.x, 0.0f);
  EXPECT_NEAR(seg.y, 4000.0f, 1e-3f);
  EXPECT_NEAR(seg.z, 2 * kR0 + 5000.0f + kBase, 1.0f);
  EXPECT_NEAR(seg.w, 2 * kR0 + 5000.0f + kTop, 1.0f);
  // Above, looking down: top to base (and the far side of the Earth again).
  ASSERT_EQ(f32::ray_shell_rel(kR0, 4e8f, -1.0f, kBase, kTop, seg), 2);
  EXPECT_NEAR(seg.x, 4e8f - kTop, 1e-6f * 4e8f);
  EXPECT_NEAR(seg.y, 4e8f - kBase, 1e-6f * 4e8f);
  // Above, looking away: nothing.
  EXPECT_EQ(f32::ray_shell_rel(kR0, 4e8f, 1.0f, kBase, kTop, seg), 0);
}

TEST(Intersect, GeneralVectorFormAgainstReference) {
  // The general form, in double, for rays from anywhere (no camera-relative inputs).
  f64::uint rng = 3u;
  for (int i = 0; i < 20000; ++i) {
    const glm::dvec3 o = glm::dvec3(f64::rng_next(rng) - 0.5, f64::rng_next(rng) - 0.5, f64::rng_next(rng) - 0.5) * 3e7;
    const glm::dvec3 d = glm::normalize(glm::dvec3(f64::rng_next(rng) - 0.5, f64::rng_next(rng) - 0.5, f64::rng_next(rng) - 0.5));
    const double r = 6.4e6;
    double t0, t1;
    const bool hit = f64::ray_sphere(o, d, r, t0, t1);
    const ld lo = std::sqrt(static_cast<ld>(o.x) * o.x + static_cast<ld>(o.y) * o.y + static_cast<ld>(o.z) * o.z);
    const ld mu = (static_cast<ld>(o.x) * d.x + static_cast<ld>(o.y) * d.y + static_cast<ld>(o.z) * d.z) / lo;
    const Hit ref = reference(r, lo - r, mu, 0);
    // Rays passing within a millimetre of the sphere's rim are ill-posed for double inputs.
    const ld perigee = lo * std::sqrt(std::max(0.0L, 1 - mu * mu));
    if (std::abs(perigee - r) < 1e-3L) continue;
    ASSERT_EQ(hit, ref.hit);
    if (!hit) continue;
    EXPECT_LE(std::abs(t0 - ref.t0), 1e-6L + 1e-9L * std::abs(ref.t0));
    EXPECT_LE(std::abs(t1 - ref.t1), 1e-6L + 1e-9L * std::abs(ref.t1));
  }
}

}  // namespace

namespace {
// Along grazing and steep rays from 0 m to 30 km up, out to 1000 km, the float altitude from
// ray_altitude stays within 2 cm plus two ulps of the result (a float at 600 km carries 6 cm) of
// the long double truth; |o + t d| - r0 in float is off by decimetres (the GPU's sun samples crossing the ramp between two grid levels read a different
// extinction, and exp(-tau) over tau ~ 20 turned that into 2 % of a pixel).
TEST(Intersect, AltitudeAlongARayKeepsItsDigits) {
  const float mus[] = {-0.3f, -0.05f, -0.004f, 0.0f, 1e-4f, 0.02f, 0.5f, 1.0f};
  const float hs[] = {0.0f, 2.5f, 2500.0f, 30000.0f};
  // Error in units of the tolerance 2 cm + 2 ulps of the true altitude.
  auto scaled = [](ld err, ld truth) { return float(std::abs(err) / (0.02L + std::ldexp(std::abs(truth), -22))); };
  float worst = 0.0f, worst_naive = 0.0f;
  for (float h : hs)
    for (float mu : mus)
      for (float t = 1000.0f; t <= 1.0e6f; t *= 1.7f) {
        const ld rh = ld(kR0) + h;
        const ld truth = std::sqrt(rh * rh + ld(t) * t + 2 * ld(t) * rh * mu) - kR0;
        if (truth < 0) continue;  // through the ground
        worst = std::max(worst, scaled(f32::ray_altitude(kR0, h, mu, t) - truth, truth));
        // The naive float form: a point at t along the ray, then its radius.
        const float nu = std::sqrt(1.0f - mu * mu);
        const float px = nu * t, pz = (kR0 + h) + mu * t;
        worst_naive = std::max(worst_naive, scaled((std::sqrt(px * px + pz * pz) - kR0) - truth, truth));
      }
  std::printf("altitude along a ray: worst %.3g of the tolerance (naive float %.3g)\n", worst, worst_naive);
  EXPECT_LT(worst, 1.0f);
  EXPECT_GT(worst_naive, 5.0f);
  // Double precision is exact to the nanometre.
  EXPECT_NEAR(f64::ray_altitude(6371000.0, 2500.0, -0.004, 4.0e5), std::sqrt(6373500.0 * 6373500.0 + 1.6e11 - 2 * 4.0e5 * 6373500.0 * 0.004) - 6371000.0, 1e-6);
}
}  // namespace

namespace {
// atan2_accurate against long double atan2 on a spiral of directions through all quadrants, near
// the axes and the diagonals: float within 3 ulps of the result (the rounded tan(k pi/16) costs an
// ulp where the result is half the reduction angle; Mesa's atan is 20 ulps off), double within
// 5e-16 rad.
TEST(Geodesy, Atan2AccurateIsWithinAnUlp) {
  double worst_f = 0.0, worst_d = 0.0;
  int n = 0;
  for (int i = 0; i < 200000; ++i) {
    const long double ang = -3.14159265358979323846L + 6.28318530717958647692L * (i + 0.37L) / 200000.0L;
    const long double r = 1.0L + 6.371e6L * (i % 7);
    for (long double nudge : {0.0L, 1e-9L}) {
      const long double x = r * std::cos(ang + nudge), y = r * std::sin(ang + nudge);
      const float xf = float(x), yf = float(y);
      const long double truth_f = std::atan2((long double)yf, (long double)xf);
      const float got_f = f32::atan2_accurate(yf, xf);
      const float ulp = std::nextafter(std::abs(float(truth_f)), 10.0f) - std::abs(float(truth_f));
      worst_f = std::max(worst_f, double(std::abs(got_f - truth_f) / ulp));
      const double xd = double(x), yd = double(y);
      const long double truth_d = std::atan2((long double)yd, (long double)xd);
      worst_d = std::max(worst_d, double(std::abs(f64::atan2_accurate(yd, xd) - truth_d)));
      ++n;
    }
  }
  std::printf("atan2_accurate over %d directions: float worst %.3g ulp, double worst %.3g rad\n", n, worst_f, worst_d);
  EXPECT_LE(worst_f, 3.0);
  EXPECT_LE(worst_d, 5e-16);
  EXPECT_EQ(f32::atan2_accurate(0.0f, -1.0f), 3.14159265358979323846f);
  EXPECT_EQ(f32::atan2_accurate(0.0f, 0.0f), 0.0f);
  EXPECT_EQ(f32::atan2_accurate(-1.0f, 0.0f), -1.57079632679489661923f);
}
}  // namespace
