// The diagnosed cloud's formulas (docs/importers.md, "Diagnosed cloud").
#include "diagnosed_cloud.hpp"

#include <algorithm>
#include <cmath>

namespace cv::importers {
namespace {
constexpr double kT0 = 273.16;     // K, IFS's triple point in the Tetens forms
constexpr double kTIce = 250.16;   // K, below this the mixed phase is all ice
constexpr double kEpsilon = 0.621981;  // R_d / R_v
}  // namespace

double saturation_vapour_pressure_water_pa(double t_k) { return 611.21 * std::exp(17.502 * (t_k - kT0) / (t_k - 32.19)); }
double saturation_vapour_pressure_ice_pa(double t_k) { return 611.21 * std::exp(22.587 * (t_k - kT0) / (t_k + 0.7)); }

double liquid_share(double t_k) {
  if (t_k >= kT0) return 1.0;
  if (t_k <= kTIce) return 0.0;
  const double x = (t_k - kTIce) / (kT0 - kTIce);
  return x * x;
}

double saturation_specific_humidity(double p_pa, double t_k) {
  const double a = liquid_share(t_k);
  const double e = a * saturation_vapour_pressure_water_pa(t_k) + (1.0 - a) * saturation_vapour_pressure_ice_pa(t_k);
  // Where e would approach p (hot, very low pressure) the formula loses meaning; cap at q = 1.
  const double denom = std::max(p_pa - (1.0 - kEpsilon) * e, kEpsilon * e);
  return kEpsilon * e / denom;
}

double sundqvist_fraction(double rh, double rh_critical) {
  if (!(rh > rh_critical)) return 0.0;
  if (rh >= 1.0) return 1.0;
  return 1.0 - std::sqrt((1.0 - rh) / (1.0 - rh_critical));
}

DiagnosedBox diagnose_box(double rh, double p_pa, double t_k, const DiagnosedCloudScheme& scheme) {
  DiagnosedBox b;
  b.cloud_fraction = sundqvist_fraction(rh, scheme.rh_critical);
  if (b.cloud_fraction <= 0.0) return b;
  const double in_cloud = scheme.condensate_of_saturation * saturation_specific_humidity(p_pa, t_k);
  const double a = liquid_share(t_k);
  b.q_liquid = b.cloud_fraction * in_cloud * a;
  b.q_ice = b.cloud_fraction * in_cloud * (1.0 - a);
  return b;
}

}  // namespace cv::importers
