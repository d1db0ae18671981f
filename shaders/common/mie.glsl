// The approximate Mie phase function for cloud droplets of Jendersie & d'Eon (2023): a blend
// (1 - w_D) HG(g_HG) + w_D Draine(g_D, alpha) with the four parameters fitted over droplet
// diameter d. The fit has four branches; it is not continuous in its parameters at 1.5 um (alpha
// jumps from 250 to 9.3) although the mean cosine is (tests/physics/mie_test.cpp measures both).

// Droplet diameter range the fit covers, in micrometres; inputs are clamped into it.
const real CV_MIE_MIN_DIAMETER_UM = real(0.01);
const real CV_MIE_MAX_DIAMETER_UM = real(50.0);

// The fitted parameters. c_hg = 1 - g_HG is kept apart: for d above ~20 um g_HG passes 0.995 and
// the HG peak, which scales as 1/c_hg^2, would lose three digits in float32 if c_hg came from g_HG.
struct MieParams {
  real g_hg;
  real c_hg;
  real g_d;
  real alpha;
  real w_d;
};

CV_FN MieParams mie_make(real g_hg, real c_hg, real g_d, real alpha, real w_d) {
  MieParams p;
  p.g_hg = g_hg;
  p.c_hg = c_hg;
  p.g_d = g_d;
  p.alpha = alpha;
  p.w_d = w_d;
  return p;
}

// Parameters for droplet diameter d_um (micrometres).
CV_FN MieParams mie_params(real d_um) {
  real d = clamp(d_um, CV_MIE_MIN_DIAMETER_UM, CV_MIE_MAX_DIAMETER_UM);
  if (d <= real(0.1)) {
    real g = real(13.8) * d * d;
    return mie_make(g, real(1) - g, real(1.1456) * d * sin(real(9.29044) * d), real(250.0),
                    real(0.252977) - real(312.983) * pow(d, real(4.3)));
  }
  if (d < real(1.5)) {
    real l = log(d);
    real inner = (l - real(0.238604)) * (l + real(1.00667)) / (real(0.507522) - real(0.15677) * l);
    real g = real(0.862) - real(0.143) * l * l;
    return mie_make(g, real(1) - g,
                    real(0.379685) * cos(real(1.19692) * cos(inner) + real(1.37932) * l + real(0.0625835)) +
                        real(0.344213),
                    real(250.0),
                    real(0.146209) * cos(real(3.38707) * l + real(2.11193)) + real(0.316072) +
                        real(0.0778917) * l);
  }
  if (d < real(5.0)) {
    real l = log(d);
    real ll = log(l);
    real g = real(0.0604931) * ll + real(0.940256);
    return mie_make(g, real(1) - g, real(0.500411) - real(0.081287) / (real(-2) * l + tan(l) + real(1.27551)),
                    real(7.30354) * l + real(6.31675),
                    real(0.026914) * (l - cos(real(5.68947) * (ll - real(0.0292149)))) + real(0.376475));
  }
  // g_HG = exp(-x), so 1 - g_HG = x E(x) with the cancellation-free segment factor E.
  real x = real(0.0990567) / (d - real(1.67154));
  return mie_make(exp(-x), x * segment_factor(x), exp(real(-2.20679) / (d + real(3.91029)) - real(0.428934)),
                  exp(real(3.62489) - real(8.29288) / (d + real(5.52825))),
                  exp(real(-0.599085) / (d - real(0.641583)) - real(0.665888)));
}

// The blend itself, with p = mie_params(d).
CV_FN real phase_mie(real mu, MieParams p) {
  return (real(1) - p.w_d) * phase_hg_c(mu, p.g_hg, p.c_hg) + p.w_d * phase_draine(mu, p.g_d, p.alpha);
}

CV_FN real mie_mean_cosine(MieParams p) {
  return (real(1) - p.w_d) * p.g_hg + p.w_d * draine_mean_cosine(p.g_d, p.alpha);
}

// The same lobes with both asymmetries scaled by s in [0, 1] (multiple-scattering octaves).
CV_FN MieParams mie_scale_g(MieParams p, real s) {
  MieParams q = p;
  q.g_hg = s * p.g_hg;
  q.c_hg = s == real(1) ? p.c_hg : real(1) - abs(q.g_hg);
  q.g_d = s * p.g_d;
  return q;
}
