// The counters of a frame's march, as both marchers report them.
#pragma once

#include <cstdint>

namespace cv::core {

// What a frame's march did, summed over its pixels (the GPU counts with atomics).
struct MarchStats {
  std::uint64_t view_samples = 0;   // medium lookups along view rays (substeps included)
  std::uint64_t view_skipped = 0;   // view step positions jumped over in empty bricks
  std::uint64_t bricks_jumped = 0;  // jumps over empty bricks, view and sun rays
  std::uint64_t sun_samples = 0;    // medium lookups along sun rays
  std::uint64_t sun_skipped = 0;    // sun step positions jumped over or cut off by sun_march_tau_limit
  std::uint64_t rays_missed = 0;    // pixels whose ray never crossed the cloud shell
  bool sun_down = false;  // the whole cloud layer was in the Earth's shadow: no sun march or octave sum ran
  // Octave terms evaluated at sunlit samples (octave_terms in octaves.glsl, per sample once for both
  // phases), and what the classic sum would have taken there (octaves per sunlit sample): the
  // difference is what the octave gate left out.
  std::uint64_t octave_terms = 0, octave_terms_full = 0;
};

}  // namespace cv::core
