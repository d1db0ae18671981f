// The approximate Mie phase function for cloud droplets of Jendersie & d'Eon (2023): a blend
// (1 - w_D) HG(g_HG) + w_D Draine(g_D, alpha) with the four parameters fitted over droplet
// diameter d. The fit has four branches; it is not continuous in its parameters at 1.5 um (alpha
// jumps from 250 to 9.3) although the mean cosine is (tests/physics/mie_test.cpp measures both).

// Droplet diameter range the fit covers, in micrometres; inputs are clamped into it.
const real CV_MIE_MIN_DIAMETER_UM = real(0.01);
const real CV_MIE_MAX_DIAMETER_UM = real(50.0);

// (g_HG, g_D, alpha, w_D) for droplet diameter d_um (micrometres).
CV_FN real4 mie_params(real d_um) {
  real d = clamp(d_um, CV_MIE_MIN_DIAMETER_UM, CV_MIE_MAX_DIAMETER_UM);
  if (d <= real(0.1)) {
    return real4(real(13.8) * d * d, real(1.1456) * d * sin(real(9.29044) * d), real(250.0),
                 real(0.252977) - real(312.983) * pow(d, real(4.3)));
  }
  if (d < real(1.5)) {
    real l = log(d);
    real inner = (l - real(0.238604)) * (l + real(1.00667)) / (real(0.507522) - real(0.15677) * l);
    return real4(real(0.862) - real(0.143) * l * l,
                 real(0.379685) * cos(real(1.19692) * cos(inner) + real(1.37932) * l + real(0.0625835)) +
                     real(0.344213),
                 real(250.0),
                 real(0.146209) * cos(real(3.38707) * l + real(2.11193)) + real(0.316072) +
                     real(0.0778917) * l);
  }
  if (d < real(5.0)) {
    real l = log(d);
    real ll = log(l);
    return real4(real(0.0604931) * ll + real(0.940256),
                 real(0.500411) - real(0.081287) / (real(-2) * l + tan(l) + real(1.27551)),
                 real(7.30354) * l + real(6.31675),
                 real(0.026914) * (l - cos(real(5.68947) * (ll - real(0.0292149)))) + real(0.376475));
  }
  return real4(exp(real(-0.0990567) / (d - real(1.67154))),
               exp(real(-2.20679) / (d + real(3.91029)) - real(0.428934)),
               exp(real(3.62489) - real(8.29288) / (d + real(5.52825))),
               exp(real(-0.599085) / (d - real(0.641583)) - real(0.665888)));
}

// The blend itself, with p = mie_params(d).
CV_FN real phase_mie(real mu, real4 p) {
  return (real(1) - p.w) * phase_hg(mu, p.x) + p.w * phase_draine(mu, p.y, p.z);
}

CV_FN real mie_mean_cosine(real4 p) {
  return (real(1) - p.w) * p.x + p.w * draine_mean_cosine(p.y, p.z);
}
