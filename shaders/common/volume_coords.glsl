// Where a point falls in a CloudVolume's regular grid: fractional indices (longitude, latitude,
// altitude), or false when it lies outside (no data). Longitude repeats on global grids (and a
// regional grid may straddle the date line in either convention); latitude clamps at the edge rows
// of a grid that reaches the poles. The CPU sampler and the GPU raymarcher both use this.
// start, step and count are (longitude deg, latitude deg, altitude m).
CV_FN bool volume_coords(real lat_deg, real lon_deg, real alt_m, real3 start, real3 step, real3 count, bool wraps,
                         bool global_lat, CV_OUT(real3) f) {
  f = real3(real(0));
  real east = mod(lon_deg - start.x, real(360));  // degrees east of the first column, in [0, 360)
  real fx = east / step.x;
  if (wraps) {
    if (fx >= count.x) fx -= count.x;
  } else {
    if (fx > count.x - real(1) + real(1e-6)) return false;
    fx = min(fx, count.x - real(1));
  }
  real fy = (lat_deg - start.y) / step.y;
  if (fy < real(0) || fy > count.y - real(1)) {
    if (!global_lat) return false;
    fy = clamp(fy, real(0), count.y - real(1));
  }
  real fz = (alt_m - start.z) / step.z;
  if (fz < real(-1e-6) || fz > count.z - real(1) + real(1e-6)) return false;
  f = real3(fx, fy, clamp(fz, real(0), count.z - real(1)));
  return true;
}
