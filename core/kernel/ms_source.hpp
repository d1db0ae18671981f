// The multiple-scattering source of the two-stream model (docs/physics.md, "Multiple scattering:
// the two-stream source"): per grid column, the delta-scaled two-stream solution of a conservative
// plane-parallel column lit by the sun, as the mean diffuse radiance I0 and its first moment I1
// (I(mu) = I0 + I1 mu, mu the cosine to the local upward vertical) at every grid node, per unit
// solar irradiance. Built once per time step and sun direction on the CPU, read by the march kernel
// (u_ms_moments, u_ms_horizontal) on the GPU and in the CPU reference alike.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "frame/albedo_map.hpp"
#include "kernel/prepared_volume.hpp"

namespace cv::core {

// One column's solution at its nodes (bottom to top, as the grid's altitudes), per unit irradiance.
struct TwoStreamColumn {
  std::vector<double> i0, i1;  // diffuse radiance moments at the nodes
  double reflected = 0.0;      // upward diffuse flux at the top / (mu0 F0): the plane albedo
  double transmitted = 0.0;    // downward diffuse plus direct flux at the bottom / (mu0 F0)
  double absorbed_ground = 0.0;  // by the ground below, / (mu0 F0)
};

// How the two-stream closes its moment equations (Meador and Weaver 1980, Table 1; conservative
// scattering, delta-scaled g'): Eddington's (gamma1 = 3 (1 - g') / 4, gamma3 = (2 - 3 g' mu0) / 4)
// or the quadrature's (gamma1 = sqrt(3) (1 - g') / 2, gamma3 = (1 - sqrt(3) g' mu0) / 2). The
// quadrature's is the default: its mean radiance I0 is nearer the delta-scaled problem's exact one
// (on a slab of optical depth 10: 7-9 % low near the top and within 4 % deeper, where Eddington's is
// 6-12 % low; docs/physics.md, "The column's closure").
enum class TwoStreamClosure { Eddington, Quadrature };

// The delta-scaled two-stream solution of one conservative column: extinction sigma_per_m and
// asymmetry g at n nodes spaced dz_m apart (bottom first), the sun at cosine mu0 > 0 to the
// vertical, a Lambertian ground of albedo ground_albedo (0..1) below the lowest node. Closed form for
// single-scattering albedo 1 (no eigenvalues, no exponential growth): stable for any optical depth.
// beam: the sun's delta-scaled beam per node (irradiance normal to the beam per unit incident,
// 0..1; sun_beam_field gives it in 3-D, so light through a sunlit side feeds the column), or null
// for the plane-parallel exp(-tau'/mu0) through the column from its top.
TwoStreamColumn two_stream_column(const double* sigma_per_m, const double* g, int n, double dz_m, double mu0,
                                  double ground_albedo, TwoStreamClosure closure = TwoStreamClosure::Quadrature,
                                  const double* beam = nullptr);

// The sun's delta-scaled beam exp(-tau') at every node (0..1), tau' the optical depth of the scaled
// extinction `scaled` (1/m, the grid's layout) toward the sun: swept down from level top_level
// (above it the beam is 1), each node's tau' the upstream point's on a level 1 to 8 above (bilinear,
// where the straight ray to the sun climbs to that level over the curved Earth; per column the hop
// whose upstream point falls nearest to nodes, so the readings smear a shadow's edge least, with at
// most 64 pieces of path per node) plus the path between (the trapezoid, each point read at its own
// height, linear between the two levels around it). A sun a little below a node's horizon still
// lights it (the ray dips first, then climbs) unless the ray meets the Earth: in the Earth's shadow
// the beam is 0. Outside a regional grid is clear air; latitude clamps at the edge rows of a grid
// whose rows reach both poles.
std::vector<float> sun_beam_field(const VolumeGrid& grid, const std::vector<float>& scaled, const glm::dvec3& to_sun, int top_level);

// The source over a prepared volume: i0 and i1 per grid node (the grid's layout), as R32F textures.
struct MsSource {
  std::vector<float> i0, i1;
  // The first moment's east and north parts, from the light between the columns (lateral_ratio);
  // empty where the columns were left independent (MsSourceKey::lateral off, or a grid beyond
  // kLateralMaxNodes).
  std::vector<float> i1e, i1n;
  // For the higher-order source (MsSourceKey::slab; empty otherwise): the optical depth (true, of
  // what the march shows) above each node in its column and below it, the extinction the column was
  // solved with, and the node's light against the homogeneous slab's with its depths over its
  // column's ground (ms_slab_two_stream): I0 - I0_slab, and that ground's albedo (0 under a sun
  // below the column's horizon).
  std::vector<float> tau_above, tau_below, sigma, slab_excess, slab_ground;
  double build_ms = 0.0;        // wall time to build it
  int lateral_iterations = -1;  // the 3-D diffusion's conjugate-gradient iterations (-1: the columns left on their own)
  std::string columns_alone;    // with -1: why the columns were left on their own (ms_columns_alone_why)
  double lateral_ms = 0.0;      // its share of build_ms
};

// The kernel's two textures of the source, two channels per node: (I0, I1 up) and (I1 east, I1
// north); the second is empty where the source has no horizontal moment. With the higher-order
// source's fields both have four: (I0, extinction, tau above, ground albedo) and (I1 east, I1
// north, tau below, I0 - I0_slab), the second then always made (its horizontal moment 0 where the
// columns stay on their own).
std::vector<float> ms_moments_texels(const MsSource& s);
// The textures' channels: 4 with the slab's fields (all of them, each node), else 2.
int ms_moments_channels(const MsSource& s);
int ms_horizontal_channels(const MsSource& s);
std::vector<float> ms_horizontal_texels(const MsSource& s);

// The largest grid whose columns exchange light (the 3-D diffusion holds about 80 bytes per node
// while it solves): beyond it each column stays on its own.
inline constexpr std::size_t kLateralMaxNodes = std::size_t(8) << 20;

// The asymmetry parameters of the medium's two phases: liquid (the approximate Mie fit's mean cosine
// at the droplet diameter, or HG's g) and ice; and the ground's albedo (0: no ground, the ray ends).
struct MsSourceKey {
  glm::dvec3 to_sun{0.0};
  double liquid_g = 0.0, ice_g = 0.0, ground_albedo = 0.0;
  // The layer mask and the hidden phases: cloud the march leaves out (medium_in) holds and passes
  // no diffuse light either, so a hidden layer does not shade the layer shown.
  MediumMask mask;
  // The globe's ground map, where the march draws one: each column's ground then takes the map's
  // albedo under it (land and water) instead of the constant ground_albedo. Told apart by its id
  // (AlbedoMap::id), else its address; the map must outlive any build from this key.
  const AlbedoMap* ground = nullptr;
  std::uint64_t ground_id = 0;
  // Light between the columns (the 3-D diffusion's ratio and horizontal flux); off, every column on
  // its own as before the fortieth session (kept for comparison).
  bool lateral = true;
  bool slab = false;  // the higher-order source: each node's optical depths above and below too
  bool operator==(const MsSourceKey& o) const {
    const bool same_ground = (ground == nullptr) == (o.ground == nullptr) &&
                             (ground_id != 0 || o.ground_id != 0 ? ground_id == o.ground_id : ground == o.ground);
    return to_sun == o.to_sun && liquid_g == o.liquid_g && ice_g == o.ice_g && ground_albedo == o.ground_albedo && mask == o.mask &&
           same_ground && lateral == o.lateral && slab == o.slab;
  }
};

// Why a build with this key on this grid leaves every column on its own (the light between the
// columns not solved), or empty where it solves it.
std::string ms_columns_alone_why(const VolumeGrid& grid, const MsSourceKey& key);

// The key of the source a march with these settings and this sun needs (ground albedo: the mean of
// the constant ground_albedo where the globe is drawn, else 0; the ground map where the globe is
// drawn from one, as the march is given it).
MsSourceKey ms_source_key(const MarchSettings& s, const glm::dvec3& to_sun, const AlbedoMap* ground = nullptr);

// The albedo a column's two-stream ground takes at (lat, lon) in degrees from a ground map: its
// land's mean over red, green and blue, and water's diffuse albedo (Fresnel's under isotropic
// light and the water body's light) by the texel's water fraction, read bilinearly as the march
// reads the map.
double column_ground_albedo(const AlbedoMap& map, double lat_deg, double lon_deg);
// The same over a column's footprint, (lat, lon) +- half of (dlat, dlon) degrees: the area's mean
// (weighted by the cosine of the latitude), from the point values on a lattice no coarser than
// the map's texels, at most 32 x 32 points; a footprint within one texel is its centre's value.
// A coarse grid's column over a coast takes the share of land and sea under it, not the side its
// centre falls on.
double column_ground_albedo(const AlbedoMap& map, double lat_deg, double lon_deg, double dlat_deg, double dlon_deg);

// Each grid column with cloud is one two_stream_column, fed by the 3-D beam of sun_beam_field
// through the medium shown (a sunlit side lights its columns as a top does); columns run on the
// machine's cores.
MsSource build_ms_source(const PreparedVolume& v, const MsSourceKey& key);

// A source built ahead for a volume (PreparedVolume::ms_prebuilt) and the key it was built for.
struct PrebuiltMsSource {
  MsSourceKey key;
  MsSource source;
  std::shared_ptr<const AlbedoMap> ground;  // the ground map key.ground points to, held while this is
};

// The source a march of v needs for `key`: v's prebuilt one where its key is the same (no work),
// else built now. `built` says which (true: built here).
std::shared_ptr<const MsSource> ms_source_for(const PreparedVolume& v, const MsSourceKey& key, bool* built = nullptr);

// The forward peak of a phase function p(mu) (normalised over the sphere, mu the cosine of the
// scattering angle) that holds the share f of its scattering, cut at the level c (1/sr): the
// integral of max(p - c, 0) over the sphere is f times that of p; g is the mean cosine of that
// peak, max(p - c, 0) / f. The two-stream march sends the light the sun's beam scatters toward the
// camera with the phase above c along the true extinction, the rest along the delta-scaled one, and
// spreads the beam's peak-scattered light by g per peak scattering (docs/physics.md, "the view
// path"). f <= 0 gives c = p's largest value (no peak), f >= 1 gives c = 0 (all peak).
struct MsPeak {
  double cut = 0.0;
  double g = 1.0;
};
MsPeak ms_peak(const std::function<double(double)>& phase, double f);
inline double ms_peak_cut(const std::function<double(double)>& phase, double f) { return ms_peak(phase, f).cut; }

// The peaks of the march's liquid and ice phases at f = g^2 (the kernel's u_ms_peak_* parameters):
// the approximate Mie fit at the droplet diameter (or HG with its mean cosine with
// liquid_phase_hg) and ice's Henyey-Greenstein. Remembers the last settings it was asked for.
struct MsBeamTable;
struct MsPeaks {
  MsPeak liquid, ice;
  double f_liquid = 0.0, f_ice = 0.0;  // the shares truncated: g^2, or the higher-order source's (ms_slab_share)
  std::shared_ptr<const MsBeamTable> beam;  // the droplets' beam phase table (ms_beam_table; none with liquid_phase_hg)
};
MsPeaks ms_peaks(const MarchSettings& s);

// The higher-order source (u_ms_slab; docs/physics.md, "The higher-order source"): whether the
// settings ask for it, and its slab tables, liquid then ice (ms_slab_table; made once per phase
// and remembered for the last settings asked).
bool ms_slab_on(const MarchSettings& s);
std::shared_ptr<const std::vector<float>> ms_slab_tables(const MarchSettings& s);

// The beam phase table (docs/physics.md, "The droplets' beam spread by the true peak kernel"). A
// phase p = smooth + s HG(spike_g) (spike_c = 1 - spike_g kept apart for precision; s = 0: no lobe
// apart) whose forward peak above the cut c holds the share f has the peak kernel
// K = max(p - c, 0) / f. Light of the delta-scaled beam has met a Poisson number k of peak
// scatterings (mean lambda), so it scatters toward the camera with the mixture over k of p convolved
// k times with K, whose Legendre coefficients are chi_l(p) exp(-lambda (1 - chi_l(K))). With
// K = a HG(spike_g) + K_r (a = s / f), the part made of the HG lobe alone, s g^l exp(-lambda (1 -
// a g^l)), is a sum of narrow HG lobes the kernel evaluates in closed form (march.glsl
// ms_beam_phase_mie); the rest is tabulated here: CV_MS_BEAM_ROWS rows of lambda by
// CV_MS_BEAM_ANGLES scattering angles (shaders/kernel/ms_beam.glsl), per sr. The smooth part must
// stay below c outside the cone about forward where p exceeds c.
struct MsBeamTable {
  std::vector<float> values;  // row-major: row (lambda) by column (angle)
  double spike_share = 0.0;   // a = spike weight / f (0: no lobe apart, the table holds the whole mixture)
  double norm_error = 0.0;    // |chi_0(K) - 1|, the quadrature's check on the cut
};
MsBeamTable ms_beam_table(const std::function<double(double)>& smooth, double spike_weight, double spike_g, double spike_c,
                          double cut, double f);

}  // namespace cv::core
