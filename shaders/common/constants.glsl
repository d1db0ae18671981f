// Mathematical and physical constants shared by the GPU and C++ (SI units).
const real CV_PI = real(3.14159265358979323846);
const real CV_TWO_PI = real(6.28318530717958647692);
const real CV_INV_4PI = real(0.07957747154594766788);
// Mean Earth radius of the spherical-Earth model (IUGG mean radius R1 rounds to this).
const real CV_EARTH_RADIUS_M = real(6371000.0);
// Standard gravity, used to turn geopotential into height.
const real CV_G0_M_PER_S2 = real(9.80665);
