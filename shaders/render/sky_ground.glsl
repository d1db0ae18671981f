// The air and the ground around the clouds, for raymarch.comp (it uses that file's uniforms and
// cloud_sun_depth): the view ray's sky in-scatter in front of and behind the cloud, and the globe
// lit through the air and the clouds' shadow, as in core/reference/raymarcher.cpp.

// Linear albedo at a ground point, bilinear over texel centres exactly as the CPU reference.
vec3 ground_albedo(float lat_rad, float lon_rad) {
  if (u_ground_size.x <= 0) return u_ground_albedo;
  vec4 c = equirect_texel(lat_rad, lon_rad, u_ground_size.x, u_ground_size.y);
  int x0 = int(c.x);
  int y0 = int(c.y);
  int x1 = (x0 + 1) % u_ground_size.x;
  int y1 = min(y0 + 1, u_ground_size.y - 1);
  vec3 a = mix(texelFetch(u_ground, ivec2(x0, y0), 0).rgb, texelFetch(u_ground, ivec2(x1, y0), 0).rgb, c.z);
  vec3 b = mix(texelFetch(u_ground, ivec2(x0, y1), 0).rgb, texelFetch(u_ground, ivec2(x1, y1), 0).rgb, c.z);
  return mix(a, b, c.w);
}

// Radiance and alpha of a pixel whose view ray d carries cloud radiance cloud_l and cloud
// transmittance cloud_t, the cloud (when has_cloud) standing at p_cloud for the air:
// sky in front + T (cloud + cloud_t (sky behind + T ground)). Alpha: 0 where the globe shows,
// else the cloud's times the air's (green) transmittance, for the background behind.
vec4 sky_and_ground(vec3 d, vec3 cloud_l, float cloud_t, bool has_cloud, vec3 p_cloud) {
  float top = CV_ATMO_TOP_M;
  // The air's own frame: a camera above the atmosphere starts from where its ray enters it, on the
  // exact sphere (positions near the Earth keep their digits; see main()).
  vec3 o = u_cam_ecef;
  float h = u_cam_alt;
  vec3 up = u_cam_up;
  float mu = dot(d, up);
  float nu = length(cross(d, up));
  float a0;
  float a1;
  if (!ray_sphere_rel_nu(u_r0, h, mu, nu, top, a0, a1) || a1 < 0.0) return vec4(cloud_l, cloud_t);
  if (h > top && a0 > 0.0) {
    o = normalize(o + a0 * d) * (u_r0 + top);
    h = top;
    up = normalize(o);
    mu = dot(d, up);
    nu = length(cross(d, up));
    ray_sphere_rel_nu(u_r0, h, mu, nu, top, a0, a1);
  }
  float g0;
  float g1;
  bool hits_ground = ray_sphere_rel_nu(u_r0, h, mu, nu, 0.0, g0, g1) && g1 > 0.0;
  float t_end = hits_ground ? max(g0, 0.0) : a1;
  float t_cloud = has_cloud ? clamp(dot(p_cloud - o, d), 0.0, t_end) : t_end;
  vec3 sky_front = vec3(0.0);
  vec3 sky_back = vec3(0.0);
  vec3 tr_front = vec3(1.0);
  vec3 tr_back = vec3(1.0);
  if (kAtmosphere) {
    float mu_s = dot(u_to_sun, up);
    float nu_vs = dot(d, u_to_sun);
    sky_front = u_irradiance * atmo_inscatter(u_r0, h, mu, mu_s, nu_vs, 0.0, t_cloud, u_sky_steps, u_atmo_sun_steps, tr_front);
    if (t_end > t_cloud) {
      sky_back = u_irradiance * atmo_inscatter(u_r0, h, mu, mu_s, nu_vs, t_cloud, t_end, u_sky_steps, u_atmo_sun_steps, tr_back);
    }
  }
  vec3 ground = vec3(0.0);
  bool globe = hits_ground && kGlobe;
  if (globe) {
    vec3 pg = normalize(o + t_end * d) * u_r0;
    vec3 n = normalize(pg);
    float mu_sg = dot(u_to_sun, n);
    float nu_sg = length(cross(u_to_sun, n));
    vec3 sun_air = vec3(mu_sg > 0.0 ? 1.0 : 0.0);
    vec3 e_sky = vec3(0.0);
    if (kAtmosphere) {
      sun_air = atmo_transmittance(u_r0, 0.0, mu_sg, nu_sg, u_atmo_sun_steps);
      e_sky = sky_irradiance(sun_air, mu_sg);
    }
    // The clouds' shadow: the same sun march the cloud samples use.
    // With the whole layer in the Earth's shadow no sunlit ray crosses cloud: left out (u_sun_down).
    float shadow = mu_sg > 0.0 ? (u_sun_down ? 1.0 : transmittance(cloud_sun_depth(pg, 0.0, mu_sg, nu_sg))) : 0.0;
    vec3 ll = ecef_to_sphere(pg, u_r0);
    ground = u_irradiance * ground_radiance(ground_albedo(ll.x, ll.y), mu_sg, sun_air * shadow, e_sky);
  }
  vec3 l = sky_front + tr_front * (cloud_l + cloud_t * (sky_back + tr_back * ground));
  return vec4(l, globe ? 0.0 : cloud_t * tr_front.y * tr_back.y);
}
