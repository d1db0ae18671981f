// Water on the globe (shaders/common/ground.glsl): the Fresnel reflectance against the textbook
// angle form, the Cox-Munk glint centred on the mirror direction and finite there, no NaN or Inf at
// grazing angles or with the sun down, no energy gain over the hemisphere, and open sea within the
// physical range (the sea's albedo 2-7 % under a high sun; at nadir outside the glint below 7 % in
// every channel).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "physics/physics.hpp"

namespace {
using namespace cv::physics;
constexpr double kPi = 3.14159265358979323846;

// Fresnel's equations in their angle form (Born & Wolf), for comparison: unpolarised reflectance
// of light from air onto water at incidence angle ti.
double fresnel_angles(double ti, double n) {
  if (ti < 1e-9) return std::pow((n - 1.0) / (n + 1.0), 2.0);
  const double tt = std::asin(std::sin(ti) / n);
  const double rs = std::sin(tt - ti) / std::sin(tt + ti), rp = std::tan(ti - tt) / std::tan(ti + tt);
  return 0.5 * (rs * rs + rp * rp);
}

TEST(Water, FresnelIsTheAirWaterReflectance) {
  const double n = f64::CV_WATER_N;
  EXPECT_NEAR(f64::fresnel_water(1.0), std::pow((n - 1.0) / (n + 1.0), 2.0), 1e-15);  // 0.0204
  EXPECT_NEAR(f64::fresnel_water(1.0), 0.0204, 1e-4);
  EXPECT_DOUBLE_EQ(f64::fresnel_water(0.0), 1.0);
  EXPECT_DOUBLE_EQ(f64::fresnel_water(-0.3), 1.0);  // clamped: grazing
  double worst = 0.0;
  for (int i = 0; i <= 89; ++i) {
    const double ti = i * kPi / 180.0;
    worst = std::max(worst, std::abs(f64::fresnel_water(std::cos(ti)) - fresnel_angles(ti, n)));
  }
  EXPECT_LT(worst, 1e-12);
  // At Brewster's angle (tan = n) the p-wave vanishes.
  const double tb = std::atan(n), tt = kPi / 2.0 - tb;
  const double rs = std::sin(tt - tb) / std::sin(tt + tb);
  EXPECT_NEAR(f64::fresnel_water(std::cos(tb)), 0.5 * rs * rs, 1e-12);
  // Under isotropic light a flat water surface reflects the constant the body term uses.
  double diffuse = 0.0;
  const int m = 200000;
  for (int i = 0; i < m; ++i) {
    const double mu = (i + 0.5) / m;
    diffuse += f64::fresnel_water(mu) * 2.0 * mu / m;
  }
  std::printf("water: F(0) %.5f, albedo under isotropic light %.5f (constant %.4f)\n", f64::fresnel_water(1.0), diffuse,
              f64::CV_WATER_DIFFUSE_FRESNEL);
  EXPECT_NEAR(diffuse, f64::CV_WATER_DIFFUSE_FRESNEL, 1e-4);
}

TEST(Water, CoxMunkSlopesGrowWithTheWind) {
  EXPECT_DOUBLE_EQ(f64::cox_munk_mss(0.0), 0.003);
  EXPECT_NEAR(f64::cox_munk_mss(7.0), 0.003 + 5.12e-3 * 7.0, 1e-15);
  EXPECT_DOUBLE_EQ(f64::cox_munk_mss(-3.0), 0.003);  // no negative roughness
}

TEST(Water, SmithLambdaIsTheErfcForm) {
  double worst = 0.0;
  for (double mss : {0.003, 0.0388, 0.157}) {
    for (int i = 1; i <= 1000; ++i) {
      const double mu = i / 1000.0;
      const double a = mu / std::sqrt(mss * std::max(1.0 - mu * mu, 1e-12));
      const double exact = 0.5 * (std::exp(-a * a) / (a * std::sqrt(kPi)) - std::erfc(a));
      worst = std::max(worst, std::abs(f64::smith_lambda_gauss(mu, mss) - std::max(exact, 0.0)));
    }
  }
  std::printf("Smith Lambda against the erfc form: worst absolute difference %.2e\n", worst);
  EXPECT_LT(worst, 2e-7);
}

// The glint's radiance factor toward a viewer at zenith angle tv and relative azimuth phi (0: toward
// the sun's side; pi: the mirror side), the sun at zenith angle ts.
double glint(double ts, double tv, double phi, double mss) {
  const glm::dvec3 s(std::sin(ts), 0.0, std::cos(ts)), v(std::sin(tv) * std::cos(phi), std::sin(tv) * std::sin(phi), std::cos(tv));
  return f64::sea_glint_brdf(s.z, v.z, glm::dot(s, v), mss);
}

TEST(Water, TheGlintPeaksInTheMirrorDirectionAndIsFinite) {
  for (double mss : {0.003, f64::cox_munk_mss(7.0), f64::cox_munk_mss(20.0)}) {
    for (double ts_deg : {0.0, 30.0, 60.0}) {
      const double ts = ts_deg * kPi / 180.0;
      // In the mirror direction the facets face the half vector: D is its peak 1 / (pi mss).
      const double mu = std::cos(ts), nu = std::cos(2.0 * ts) * 1.0;  // v = mirror of s: s.v = cos 2 ts
      const double f = f64::sea_glint_brdf(mu, mu, nu, mss);
      const double g = 1.0 / (1.0 + 2.0 * f64::smith_lambda_gauss(mu, mss));
      ASSERT_TRUE(std::isfinite(f));
      EXPECT_NEAR(f * 4.0 * mu * mu / (f64::fresnel_water(mu) * g), 1.0 / (kPi * mss), 1e-9 / mss) << mss << " " << ts_deg;
      // Along the principal plane the largest radiance lies at the mirror direction (overhead sun);
      // with the sun lower it moves toward the horizon (the off-specular peak: 1 / mu_v and Fresnel
      // grow there), by a few degrees on a calm or moderate sea under a high sun.
      double best = -1.0, best_tv = 0.0;
      for (int i = -890; i <= 890; ++i) {
        const double tv = std::abs(i) * 0.1 * kPi / 180.0;
        const double l = glint(ts, tv, i < 0 ? 0.0 : kPi, mss);
        ASSERT_TRUE(std::isfinite(l) && l >= 0.0);
        if (l > best) best = l, best_tv = (i < 0 ? -1.0 : 1.0) * tv;
      }
      const double off_deg = best_tv * 180.0 / kPi - ts_deg;
      std::printf("glint, mss %.4f, sun at %2.0f deg: peak %.4g /sr at %.1f deg from the mirror direction; 25 deg past it %.3g\n",
                  mss, ts_deg, best, off_deg, glint(ts, ts + 25.0 * kPi / 180.0, kPi, mss));
      EXPECT_TRUE(std::isfinite(best));
      if (ts_deg == 0.0) {
        EXPECT_NEAR(off_deg, 0.0, 0.051);
      }
      EXPECT_GE(off_deg, -0.051);
      if (ts_deg <= 30.0 && mss < 0.04) {
        EXPECT_LT(off_deg, 5.0);
      }
    }
  }
}

TEST(Water, NoNaNOrInfAtGrazingAnglesOrWithTheSunDown) {
  const double mus[] = {-1.0, -0.5, -1e-7, 0.0, 1e-30, 1e-12, 1e-7, 1e-4, 0.01, 0.3, 0.999999, 1.0};
  int cases = 0;
  for (double ms : mus) {
    for (double mv : mus) {
      for (double nu : {-1.0, -0.999999, -0.5, 0.0, 0.7, 1.0}) {
        for (double mss : {0.003, 0.0388, 0.157}) {
          const double fd = f64::sea_glint_brdf(ms, mv, nu, mss);
          const float ff = f32::sea_glint_brdf(float(ms), float(mv), float(nu), float(mss));
          const glm::dvec3 ld = f64::water_radiance(f64::CV_WATER_BODY, ms, mv, nu, mss, glm::dvec3(1.0), glm::dvec3(0.05));
          const glm::vec3 lf = f32::water_radiance(f32::CV_WATER_BODY, float(ms), float(mv), float(nu), float(mss), glm::vec3(1.0f),
                                                   glm::vec3(0.05f));
          ASSERT_TRUE(std::isfinite(fd) && fd >= 0.0 && std::isfinite(ff) && ff >= 0.0f) << ms << " " << mv << " " << nu;
          for (int k = 0; k < 3; ++k) ASSERT_TRUE(std::isfinite(ld[k]) && ld[k] >= 0.0 && std::isfinite(lf[k]) && lf[k] >= 0.0f);
          if (!(ms > 0.0) || !(mv > 0.0)) {
            EXPECT_EQ(fd, 0.0);
          }
          ++cases;
        }
      }
    }
  }
  std::printf("%d cases, all finite and >= 0 in float and double\n", cases);
}

// The water's directional albedo for the sun at cosine mu_s: the glint's integral over the view
// hemisphere (through the half vector, where the glint is narrow: dw_v = 4 (s.h) dw_h), plus the
// body's light let out over the hemisphere, per channel. With sky irradiance e_sky, its share.
struct Albedo {
  double glint = 0.0;
  glm::dvec3 total{0.0};
};
Albedo water_albedo(double mu_s, double mss) {
  const double ts = std::acos(mu_s);
  const glm::dvec3 s(std::sin(ts), 0.0, mu_s);
  Albedo a;
  const int nz = 1500, nphi = 720;
  const double zmax = 12.0 * std::sqrt(mss);  // tan of the facet angle: exp(-144) beyond
  for (int i = 0; i < nz; ++i) {
    const double z = (i + 0.5) * zmax / nz, th = std::atan(z), dth = zmax / nz / (1.0 + z * z);
    for (int j = 0; j < nphi; ++j) {
      const double ph = (j + 0.5) * 2.0 * kPi / nphi;
      const glm::dvec3 h(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
      const double sh = glm::dot(s, h);
      if (sh <= 0.0) continue;
      const glm::dvec3 v = 2.0 * sh * h - s;
      if (v.z <= 0.0) continue;
      const double f = f64::sea_glint_brdf(mu_s, v.z, glm::dot(s, v), mss);
      a.glint += f * v.z * 4.0 * sh * std::sin(th) * dth * (2.0 * kPi / nphi);
    }
  }
  // The body: water_radiance without the glint, integrated over the hemisphere (a smooth function).
  glm::dvec3 body(0.0);
  const int nm = 2000;
  for (int i = 0; i < nm; ++i) {
    const double mu_v = (i + 0.5) / nm;
    // water_radiance less its glint (and no sky light: e_sky 0) is the body's radiance.
    const double nu = -mu_s * mu_v + std::sqrt((1.0 - mu_s * mu_s) * (1.0 - mu_v * mu_v));  // any azimuth will do
    const glm::dvec3 l = f64::water_radiance(f64::CV_WATER_BODY, mu_s, mu_v, nu, mss, glm::dvec3(1.0), glm::dvec3(0.0)) -
                         glm::dvec3(mu_s * f64::sea_glint_brdf(mu_s, mu_v, nu, mss));
    body += l * (mu_v * 2.0 * kPi / nm);
  }
  a.total = a.glint + body / mu_s;
  return a;
}

TEST(Water, NoEnergyGainAndTheAlbedoOfTheSeaUnderAHighSun) {
  for (double wind : {0.0, 7.0, 20.0}) {
    const double mss = f64::cox_munk_mss(wind);
    for (double ts_deg : {0.0, 30.0, 50.0, 60.0, 70.0, 80.0, 85.0, 89.0}) {
      const double mu_s = std::cos(ts_deg * kPi / 180.0);
      const Albedo a = water_albedo(mu_s, mss);
      std::printf("wind %4.1f m/s, sun at %2.0f deg: glint albedo %.4f (flat water: F = %.4f), water %.4f %.4f %.4f\n", wind,
                  ts_deg, a.glint, f64::fresnel_water(mu_s), a.total.x, a.total.y, a.total.z);
      // The glint holds at most the largest Fresnel factor its facets see (shadowing and masking
      // take the rest at grazing sun); with the body it never reflects more than arrives.
      EXPECT_LE(a.glint, 1.0);
      for (int k = 0; k < 3; ++k) EXPECT_LE(a.total[k], 1.0);
      if (ts_deg <= 50.0) {
        // The sea's albedo under a high sun: 2-7 % (Payne 1972: about 0.03-0.06 at sun elevations
        // above 40 deg; Jin et al. 2004, 2011), Fresnel's 2 % at normal incidence plus the body's.
        for (int k = 0; k < 3; ++k) {
          EXPECT_GE(a.total[k], 0.02) << wind << " " << ts_deg;
          EXPECT_LE(a.total[k], 0.07) << wind << " " << ts_deg;
        }
      }
      if (ts_deg == 60.0) {
        EXPECT_LE((a.total.x + a.total.y + a.total.z) / 3.0, 0.07) << wind;  // Payne: ~0.06 at 30 deg elevation
      }
      // Overhead: Fresnel at normal incidence (roughness spreads it, shadowing takes a little).
      if (ts_deg == 0.0) {
        EXPECT_NEAR(a.glint, f64::fresnel_water(1.0), 2e-3);
      }
    }
  }
}

TEST(Water, OpenSeaAtNadirStaysInThePhysicalRange) {
  // Reflectance factor pi L / (E mu_s) at nadir, no air (t_sun 1, no sky light), 7 m/s.
  const double mss = f64::cox_munk_mss(7.0);
  auto nadir = [&](double ts_deg) {
    const double ts = ts_deg * kPi / 180.0;
    return f64::water_radiance(f64::CV_WATER_BODY, std::cos(ts), 1.0, std::cos(ts), mss, glm::dvec3(1.0), glm::dvec3(0.0)) * kPi /
           std::cos(ts);
  };
  // In the glint (overhead sun): Fresnel's 0.0204 over 4 mss (Cox & Munk's peak), plus the body.
  const glm::dvec3 peak = nadir(0.0);
  EXPECT_NEAR(peak.y, f64::fresnel_water(1.0) / (4.0 * mss) + f64::CV_WATER_BODY.y, 1e-9);
  std::printf("nadir, overhead sun (in the glint): %.4f %.4f %.4f\n", peak.x, peak.y, peak.z);
  // Outside the glint: the body's light and what is left of the glint, every channel below 7 %;
  // blue the brightest (clear water's own colour), red below 1 %.
  for (double ts_deg : {40.0, 50.0, 60.0}) {
    const glm::dvec3 r = nadir(ts_deg);
    std::printf("nadir, sun at %2.0f deg (outside the glint): %.4f %.4f %.4f\n", ts_deg, r.x, r.y, r.z);
    for (int k = 0; k < 3; ++k) EXPECT_LT(r[k], 0.07);
    EXPECT_GT(r.z, r.y);
    EXPECT_GT(r.y, r.x);
    EXPECT_GE(r.z, 0.015);
  }
  // The same from the overhead sun's side: a viewer 40-60 deg off nadir.
  for (double tv_deg : {40.0, 60.0}) {
    const double tv = tv_deg * kPi / 180.0;
    const glm::dvec3 r =
        f64::water_radiance(f64::CV_WATER_BODY, 1.0, std::cos(tv), std::cos(tv), mss, glm::dvec3(1.0), glm::dvec3(0.0)) * kPi;
    std::printf("overhead sun, viewed %2.0f deg off nadir: %.4f %.4f %.4f\n", tv_deg, r.x, r.y, r.z);
    for (int k = 0; k < 3; ++k) EXPECT_LT(r[k], 0.07);
  }
  // The relief image's sea colour, taken as albedo before, reflected several times more.
  const double map_sea_green = std::pow((172.0 / 255.0 + 0.055) / 1.055, 2.4);
  EXPECT_GT(map_sea_green / nadir(50.0).y, 5.0);
}

// No water: ground_radiance_water is the Lambertian ground exactly (the constant albedo, land).
TEST(Water, LandIsLambertianAsBefore) {
  const glm::dvec3 a(0.12), t(0.8, 0.7, 0.6), e(0.03, 0.04, 0.05);
  for (double mu_s : {-0.2, 0.0, 0.4, 1.0}) {
    const glm::dvec3 l = f64::ground_radiance(a, mu_s, t, e);
    EXPECT_EQ(f64::ground_radiance_water(a, 0.0, f64::CV_WATER_BODY, mu_s, 0.9, 0.3, 0.04, t, e), l);
  }
}

}  // namespace
