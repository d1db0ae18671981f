// A cloud diagnosed from relative humidity, for files that have temperature and humidity but no
// cloud field (asked for with --diagnose-cloud). The scheme and its constants are in
// docs/importers.md, "Diagnosed cloud".
#pragma once

namespace cv::importers {

struct DiagnosedCloudScheme {
  double rh_critical = 0.8;              // Sundqvist's threshold relative humidity (0..1)
  double condensate_of_saturation = 0.05;  // in-cloud condensate as a share of q_sat
};

// Saturation vapour pressure (Pa) over water and over ice (IFS's Tetens forms), and the IFS
// mixed-phase weight of water: 1 at and above 0 C, 0 at and below -23 C, quadratic between.
double saturation_vapour_pressure_water_pa(double t_k);
double saturation_vapour_pressure_ice_pa(double t_k);
double liquid_share(double t_k);
// Saturation specific humidity (kg/kg) over the mixed phase at (p, T).
double saturation_specific_humidity(double p_pa, double t_k);

// Sundqvist et al. (1989): fraction = 1 - sqrt((1 - RH) / (1 - RH_c)) above RH_c, 0 below, 1 at
// and above saturation. rh is 0..1 (not %).
double sundqvist_fraction(double rh, double rh_critical);

struct DiagnosedBox {
  double cloud_fraction = 0.0;
  double q_liquid = 0.0, q_ice = 0.0;  // grid-box means, kg/kg
};
// The box's cloud from its relative humidity (0..1), pressure and temperature: the Sundqvist
// fraction, an in-cloud condensate of condensate_of_saturation x q_sat, split into liquid and ice
// by liquid_share(T).
DiagnosedBox diagnose_box(double rh, double p_pa, double t_k, const DiagnosedCloudScheme& scheme);

}  // namespace cv::importers
