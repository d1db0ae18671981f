// The atmosphere (shaders/common/atmosphere.glsl) against closed forms and a brute-force integral:
// vertical optical depths of the exponential layers and the ozone tent, the horizon against the
// zenith, sunset reddening, the sun below the horizon, and no NaN or Inf from 0 m to 4e8 m.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "physics/physics.hpp"

namespace {
using namespace cv::physics;
constexpr double kR0 = 6371000.0;
constexpr double kTop = 60000.0;
constexpr double kPi = 3.14159265358979323846;

// Integral of the ozone tent (1 at 25 km, 0 at 10 and 40 km) from h0 to the top, in metres.
double ozone_column_m(double h0) {
  auto cdf = [](double h) {  // integral from 0 to h
    if (h <= 10000.0) return 0.0;
    if (h <= 25000.0) return 0.5 * (h - 10000.0) * (h - 10000.0) / 15000.0;
    if (h <= 40000.0) return 15000.0 - 0.5 * (40000.0 - h) * (40000.0 - h) / 15000.0;
    return 15000.0;
  };
  return cdf(kTop) - cdf(h0);
}

// Vertical optical depth from h0 to the top, in closed form: beta H (exp(-h0/H) - exp(-top/H)) for
// the exponential layers, beta_O times the tent's column for ozone.
glm::dvec3 vertical_depth(double h0) {
  const glm::dvec3 beta_r = f64::rayleigh_scattering_per_m();
  const double hr = 8000.0, hm = 1200.0;
  return beta_r * hr * (std::exp(-h0 / hr) - std::exp(-kTop / hr)) +
         glm::dvec3(4.40e-6 * hm * (std::exp(-h0 / hm) - std::exp(-kTop / hm))) + f64::ozone_absorption_per_m() * ozone_column_m(h0);
}

TEST(Atmosphere, ConstantsAreThePublishedOnes) {
  const glm::dvec3 r = f64::rayleigh_scattering_per_m(), o = f64::ozone_absorption_per_m();
  EXPECT_DOUBLE_EQ(r.x, 5.802e-6);
  EXPECT_DOUBLE_EQ(r.z, 33.1e-6);
  EXPECT_DOUBLE_EQ(o.y, 1.881e-6);
  EXPECT_DOUBLE_EQ(f64::CV_MIE_SCATTERING_PER_M, 3.996e-6);
  // Sea-level vertical Rayleigh optical depth beta H: 0.265 in blue, 0.046 in red.
  EXPECT_NEAR(r.z * 8000.0, 0.2648, 1e-4);
}

TEST(Atmosphere, VerticalOpticalDepthMatchesTheClosedForm) {
  // Worst relative error over starting altitudes (0 to 33 km) and channels, per step count: the
  // march converges toward the closed form (the ozone tent's kinks limit it to about second order).
  double worst[4] = {0, 0, 0, 0};
  const int steps[4] = {8, 16, 64, 256};
  for (double h0 : {0.0, 1000.0, 10000.0, 20000.0, 25000.0, 33000.0}) {
    const glm::dvec3 ref = vertical_depth(h0);
    for (int k = 0; k < 4; ++k) {
      const glm::dvec3 tau = f64::atmo_optical_depth(kR0, h0, 1.0, 0.0, kTop - h0, steps[k]);
      for (int c = 0; c < 3; ++c) worst[k] = std::max(worst[k], std::abs(tau[c] - ref[c]) / ref[c]);
    }
  }
  for (int k = 0; k < 4; ++k) std::printf("vertical optical depth, %3d steps: worst relative error %.2e\n", steps[k], worst[k]);
  EXPECT_LT(worst[1], 1e-2);  // 16 steps, the renderer's sky default: within 1 % (the ozone tent's kinks above 20 km)
  EXPECT_LT(worst[3], 5e-5);
  EXPECT_LT(worst[3], worst[1] / 10.0);
}

TEST(Atmosphere, OzoneColumnIsTheTentsArea) {
  // Above 40 km only the thin exponential tails are left; the whole tent is 15 km of peak density.
  const glm::dvec3 from_ground = vertical_depth(0.0), above = vertical_depth(40000.0);
  EXPECT_NEAR(ozone_column_m(0.0), 15000.0, 1e-9);
  // Green is ozone's strongest band (Chappuis): its column is 15 km x 1.881e-6 = 0.0282.
  const glm::dvec3 tau0 = f64::atmo_optical_depth(kR0, 0.0, 1.0, 0.0, kTop, 256);
  const glm::dvec3 tau40 = f64::atmo_optical_depth(kR0, 40000.0, 1.0, 0.0, kTop - 40000.0, 256);
  const double rayleigh_mie_green = 13.558e-6 * 8000.0 * (1.0 - std::exp(-kTop / 8000.0)) + 4.40e-6 * 1200.0;
  EXPECT_NEAR(tau0.y - rayleigh_mie_green, 15000.0 * 1.881e-6, 2e-5);
  EXPECT_NEAR(tau40.y, above.y, 1e-5 * above.y);  // the march's own error at 256 steps
  EXPECT_LT(above.y, 0.01 * from_ground.y);
}

// The optical depth along a slanted ray by brute force: 200 000 uniform steps in long double, the
// altitude from the law of cosines.
glm::dvec3 brute_force_depth(double h0, double mu) {
  const long double r = kR0 + h0, rt = kR0 + kTop;
  const long double b = r * mu, c = r * r - rt * rt;
  const long double t1 = -b + std::sqrt(b * b - c);
  const int n = 200000;
  long double tau[3] = {0, 0, 0};
  for (int i = 0; i < n; ++i) {
    const long double t = (i + 0.5L) * t1 / n;
    const long double h = std::sqrt(r * r + 2 * r * mu * t + t * t) - kR0;
    const glm::dvec3 e = f64::atmo_extinction_per_m(f64::atmo_density(static_cast<double>(h)));
    for (int k = 0; k < 3; ++k) tau[k] += e[k] * (t1 / n);
  }
  return glm::dvec3(static_cast<double>(tau[0]), static_cast<double>(tau[1]), static_cast<double>(tau[2]));
}

TEST(Atmosphere, HorizonAgainstZenith) {
  // The horizontal path at sea level holds about sqrt(pi R / (2 H)) = 35 times the vertical
  // Rayleigh mass (Chapman); the 16-step march is held against brute force.
  const glm::dvec3 zen = f64::atmo_transmittance(kR0, 0.0, 1.0, 0.0, 16);
  const glm::dvec3 hor = f64::atmo_transmittance(kR0, 0.0, 0.0, 1.0, 16);
  const glm::dvec3 hor_ref = brute_force_depth(0.0, 0.0), zen_ref = vertical_depth(0.0);
  double worst = 0.0;
  for (int c = 0; c < 3; ++c) {
    worst = std::max({worst, std::abs(-std::log(zen[c]) - zen_ref[c]) / zen_ref[c], std::abs(-std::log(hor[c]) - hor_ref[c]) / hor_ref[c]});
  }
  const double ratio_blue = -std::log(hor.z) / -std::log(zen.z);
  std::printf("sea level, blue: zenith T %.4f, horizon T %.3g, optical depth ratio %.1f\n", zen.z, hor.z, ratio_blue);
  EXPECT_GT(ratio_blue, 25.0);
  EXPECT_LT(ratio_blue, 40.0);
  // Slanted rays at 1 km against brute force, 16 steps.
  for (double mu : {0.5, 0.1, 0.02, -0.005}) {
    const double nu = std::sqrt(1.0 - mu * mu);
    const glm::dvec3 t = f64::atmo_transmittance(kR0, 1000.0, mu, nu, 16), ref = brute_force_depth(1000.0, mu);
    for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(-std::log(t[c]) - ref[c]) / ref[c]);
  }
  // A 16-step march keeps slanted optical depths within 1 % of brute force.
  std::printf("16-step optical depths against brute force, zenith to below the horizon: worst relative %.2e\n", worst);
  EXPECT_LT(worst, 1e-2);
}

TEST(Atmosphere, LowSunReddensAndTheSetSunDeliversNothing) {
  // The sun's colour at 1 km: red over blue grows as the sun sinks, and below the horizon (the
  // horizon dips 1.0 degree at 1 km) the ray meets the ground.
  double last_ratio = 0.0;
  for (double elev_deg : {90.0, 45.0, 20.0, 10.0, 5.0, 2.0, 0.0, -0.8}) {
    const double e = elev_deg * kPi / 180.0;
    const glm::dvec3 t = f64::atmo_transmittance(kR0, 1000.0, std::sin(e), std::cos(e), 8);
    const double ratio = t.x / t.z;
    std::printf("sun at %5.1f deg from 1 km: T = (%.3f, %.3f, %.3g), red/blue %.3g\n", elev_deg, t.x, t.y, t.z, ratio);
    EXPECT_GT(ratio, last_ratio) << elev_deg;
    last_ratio = ratio;
  }
  EXPECT_GT(last_ratio, 100.0);
  for (double elev_deg : {-1.2, -5.0, -90.0}) {
    const double e = elev_deg * kPi / 180.0;
    const glm::dvec3 t = f64::atmo_transmittance(kR0, 1000.0, std::sin(e), std::cos(e), 8);
    EXPECT_EQ(t, glm::dvec3(0.0)) << elev_deg;
  }
}

TEST(Atmosphere, SkyIsBlueByDayDarkAtNightAndTheLimbIsFinite) {
  // Looking up at noon from the ground: blue dominates the single-scattered sky.
  glm::dvec3 tr;
  const double mu_s = std::cos(30.0 * kPi / 180.0);
  const glm::dvec3 zen = f64::atmo_inscatter(kR0, 0.0, 1.0, mu_s, mu_s, 0.0, kTop, 16, 8, tr);
  std::printf("zenith sky, sun at 60 deg: radiance per unit irradiance (%.4f, %.4f, %.4f)\n", zen.x, zen.y, zen.z);
  EXPECT_GT(zen.z, 1.5 * zen.y);
  EXPECT_GT(zen.y, zen.x);
  EXPECT_LT(zen.z, 0.1);
  // Night: the sun 30 degrees below the horizon lights no air in the view.
  const glm::dvec3 night = f64::atmo_inscatter(kR0, 0.0, 1.0, -0.5, -0.5, 0.0, kTop, 16, 8, tr);
  EXPECT_EQ(night, glm::dvec3(0.0));
  // Sky irradiance: 0 at night, positive and bluish by day.
  EXPECT_EQ(f64::sky_irradiance(glm::dvec3(0.0), -0.3), glm::dvec3(0.0));
  const glm::dvec3 e = f64::sky_irradiance(f64::atmo_transmittance(kR0, 0.0, mu_s, 0.5, 8), mu_s);
  EXPECT_GT(e.z, e.x);
  EXPECT_GT(e.x, 0.0);
}

// Every function, in float and double, from the ground and from 4e8 m, sun above and below the
// horizon, nadir to zenith and around tangency: finite, transmittance within [0, 1].
TEST(Atmosphere, NoNaNOrInfFromTheGroundTo400000Km) {
  int cases = 0;
  for (double h : {0.0, 1.0, 1000.0, 59999.0, 60000.0, 4e5, 3.6e7, 4e8}) {
    for (double mu : {-1.0, -0.5, -0.02, -1e-4, 0.0, 1e-4, 0.02, 0.5, 1.0}) {
      for (double mu_s : {-1.0, -0.1, 0.0, 0.1, 1.0}) {
        const double nu = std::sqrt(1.0 - mu * mu);
        const glm::dvec3 t = f64::atmo_transmittance(kR0, h, mu, nu, 8);
        const glm::vec3 tf = f32::atmo_transmittance(6371000.0f, float(h), float(mu), float(nu), 8);
        // The whole view segment inside the air, or nothing when the ray misses it.
        double a0, a1;
        double t0 = 0.0, t1 = 0.0;
        if (f64::ray_sphere_rel_nu(kR0, h, mu, nu, kTop, a0, a1) && a1 > 0.0) t0 = std::max(a0, 0.0), t1 = a1;
        glm::dvec3 tr;
        glm::vec3 trf;
        const glm::dvec3 l = f64::atmo_inscatter(kR0, h, mu, mu_s, mu * mu_s, t0, t1, 16, 8, tr);
        const glm::vec3 lf = f32::atmo_inscatter(6371000.0f, float(h), float(mu), float(mu_s), float(mu * mu_s), float(t0),
                                                 float(t1), 16, 8, trf);
        for (int c = 0; c < 3; ++c) {
          ASSERT_TRUE(std::isfinite(t[c]) && std::isfinite(tf[c]) && std::isfinite(l[c]) && std::isfinite(lf[c]) &&
                      std::isfinite(tr[c]) && std::isfinite(trf[c]))
              << "h=" << h << " mu=" << mu << " mu_s=" << mu_s;
          ASSERT_GE(t[c], 0.0);
          ASSERT_LE(t[c], 1.0);
          ASSERT_GE(l[c], 0.0);
          ASSERT_GE(tr[c], 0.0);
          ASSERT_LE(tr[c], 1.0);
        }
        ++cases;
      }
    }
  }
  EXPECT_EQ(cases, 360);
}

TEST(Atmosphere, FloatKeepsItsDigitsAtPlanetaryScale) {
  // float32 against double for rays from 2 m, 1 km and 40 km, near the horizon and steep: the
  // camera-relative altitude keeps float within 1e-4 of double (a naive sqrt(...) - R would lose
  // half a metre of altitude, 4e-4 of the Mie density).
  double worst = 0.0;
  for (double h : {2.0, 1000.0, 40000.0}) {
    for (double mu : {0.0, 0.01, 0.1, 0.7, 1.0}) {
      const double nu = std::sqrt(1.0 - mu * mu);
      const glm::dvec3 t = f64::atmo_transmittance(kR0, h, mu, nu, 16);
      const glm::vec3 tf = f32::atmo_transmittance(6371000.0f, float(h), float(mu), float(nu), 16);
      double a0, a1;
      f64::ray_sphere_rel_nu(kR0, h, mu, nu, kTop, a0, a1);
      glm::dvec3 tr;
      glm::vec3 trf;
      const glm::dvec3 l = f64::atmo_inscatter(kR0, h, mu, 0.3, 0.3 * mu, 0.0, a1, 16, 8, tr);
      const glm::vec3 lf = f32::atmo_inscatter(6371000.0f, float(h), float(mu), 0.3f, float(0.3 * mu), 0.0f, float(a1), 16, 8, trf);
      for (int c = 0; c < 3; ++c) {
        worst = std::max(worst, std::abs(tf[c] - t[c]) / std::max(t[c], 1e-3));
        worst = std::max(worst, std::abs(lf[c] - l[c]) / l[c]);
      }
    }
  }
  std::printf("float against double, transmittance and sky radiance: worst relative %.2e\n", worst);
  EXPECT_LT(worst, 1e-4);
}

TEST(Atmosphere, AltitudeAlongARayKeepsFloatDigits) {
  // 2 m above the ground, looking 1 degree down, 100 m out: the altitude is 2 - 1.745 m = 0.255 m
  // (plus 0.8 mm of curvature); float through sqrt(r^2 + ...) - R would be off by up to 0.5 m.
  const double mu = -std::sin(kPi / 180.0);
  const double ref = f64::ray_altitude(kR0, 2.0, mu, 100.0);
  const float f = f32::ray_altitude(6371000.0f, 2.0f, float(mu), 100.0f);
  EXPECT_NEAR(ref, 2.0 + 100.0 * mu + 100.0 * 100.0 / (2.0 * kR0), 1e-6);
  EXPECT_NEAR(f, ref, 1e-4);
}

}  // namespace
