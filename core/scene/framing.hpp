// Where the camera goes when a scene sets none, and where the sun stands for a scene: shared by
// the `render` command and the viewer so both frame a volume and light it the same way.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "frame/sun.hpp"
#include "scene/scene.hpp"
#include "volume/cloud_volume.hpp"

namespace cv::core {

// South of the volume and high up (90 km per degree of latitude span), aimed at the centre of its
// base, 60 degree field of view: the whole domain in view with some relief from the slant.
Camera auto_camera(const VolumeGrid& grid, int width, int height);

// Seconds since 1970-01-01 UTC of "YYYY-MM-DDThh:mm[:ss[.fff]][Z]" (proleptic Gregorian, UTC; a
// fraction is dropped), or nothing when the text is not such a date-time.
std::optional<std::int64_t> parse_iso_utc(const std::string& text);

// sun.mode in scene files: "valid_time", "datetime", "manual", "local_noon" (parse: false otherwise).
const char* sun_mode_name(SunMode m);
bool parse_sun_mode(const std::string& text, SunMode& out);

// The sun a scene asks for. A LocalNoon sun stands over `fallback_lon_deg` (the camera's longitude)
// at the declination of the valid time (0 without one). `valid_time` is the data's valid time (nothing when unknown, e.g. a
// file without a time axis); then a ValidTime sun stands at noon over `fallback_lon_deg`.
// Throws std::invalid_argument when a DateTime sun has no parseable date-time.
Sun resolve_sun(const SunSpec& spec, const std::optional<std::int64_t>& valid_time_unix_s, double fallback_lon_deg);

}  // namespace cv::core
