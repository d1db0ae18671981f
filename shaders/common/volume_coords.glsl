// Where a point falls in a CloudVolume's regular grid: fractional indices (longitude, latitude,
// altitude), or false when it lies outside (no data). Longitude repeats on global grids (and a
// regional grid may straddle the date line in either convention); latitude clamps at the edge rows
// of a grid that reaches the poles. A regional grid's sides fade out over one grid cell: the
// indices run from -1 to count (horizontally), as if the grid were bordered by nodes without
// cloud, so a ray grazing the data's edge does not flip between all and nothing on float rounding
// (volume_fetch_index reads those border nodes). The CPU sampler and the GPU raymarcher both use
// this. start, step and count are (longitude deg, latitude deg, altitude m).
CV_FN bool volume_coords(real lat_deg, real lon_deg, real alt_m, real3 start, real3 step, real3 count, bool wraps,
                         bool global_lat, CV_OUT(real3) f) {
  f = real3(real(0));
  real east = mod(lon_deg - start.x, real(360));  // degrees east of the first column, in [0, 360)
  real fx = east / step.x;
  if (wraps) {
    if (fx >= count.x) fx -= count.x;
  } else if (fx > count.x) {
    fx = (east - real(360)) / step.x;  // west of the first column: its border, or nothing
    if (fx < real(-1)) return false;
  }
  real fy = (lat_deg - start.y) / step.y;
  if (global_lat) {
    fy = clamp(fy, real(0), count.y - real(1));
  } else if (fy < real(-1) || fy > count.y) {
    return false;
  }
  real fz = (alt_m - start.z) / step.z;
  if (fz < real(-1e-6) || fz > count.z - real(1) + real(1e-6)) return false;
  f = real3(fx, fy, clamp(fz, real(0), count.z - real(1)));
  return true;
}

// The lower node and the weight of the upper one along an axis of n nodes, from a fractional index
// f that volume_coords returned: nodes -1 and n are the border (no cloud); inside, the last interval
// ends on node n - 1 with weight 1, so an edge node reads exactly.
CV_FN int volume_fetch_index(real f, int n, CV_OUT(real) w) {
  int i0 = f > real(n - 1) ? n - 1 : min(int(floor(f)), max(0, n - 2));
  w = f - real(i0);
  return i0;
}
