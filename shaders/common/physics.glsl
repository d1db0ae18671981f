// The physics core, written once: the GPU includes this through the shader loader, C++ through
// core/physics/physics.hpp (float and double). Files are listed in dependency order; none of them
// includes another, so C++ can instantiate the set once per precision.
#include "constants.glsl"
#include "precise.glsl"
#include "rng.glsl"
#include "frame.glsl"
#include "transmittance.glsl"
#include "phase.glsl"
#include "mie.glsl"
#include "phase_sampling.glsl"
#include "octaves.glsl"
#include "intersect.glsl"
#include "geodesy.glsl"
#include "volume_coords.glsl"
#include "erosion.glsl"
#include "atmosphere.glsl"
#include "ground.glsl"
#include "march_control.glsl"
