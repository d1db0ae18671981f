// Orthonormal frames around a unit vector (branchless construction of Duff et al. 2017, which has
// no singularity except the sign switch at n.z = 0), and directions from spherical coordinates.
CV_FN void make_frame(real3 n, CV_OUT(real3) t, CV_OUT(real3) b) {
  real s = n.z >= real(0) ? real(1) : real(-1);
  real a = real(-1) / (s + n.z);
  real c = n.x * n.y * a;
  t = real3(real(1) + s * n.x * n.x * a, s * c, -s * n.x);
  b = real3(c, s + n.y * n.y * a, -n.y);
}

// The unit vector at angle acos(mu) from axis n and azimuth phi (radians) around it.
CV_FN real3 direction_around(real3 n, real mu, real phi) {
  real3 t;
  real3 b;
  make_frame(n, t, b);
  real sin_theta = sqrt(max(real(0), (real(1) - mu) * (real(1) + mu)));
  return normalize(t * (sin_theta * cos(phi)) + b * (sin_theta * sin(phi)) + n * mu);
}
