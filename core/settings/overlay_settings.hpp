// The overlays a scene draws (coastlines, graticule, isosurfaces) and their parameters, typed by
// one table (overlay_settings.def): scene files, `render --overlay` and the viewer read it.
// Plain data: building and drawing the overlays is app/overlays' and app/render's.
#pragma once

#include <map>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

namespace cv::core {

enum class OverlayParamKind { Number, Text, Rgb };

struct OverlayParamRow {
  const char* overlay = nullptr;  // the overlay's type name
  const char* key = nullptr;      // the parameter's key in its scene entry
  OverlayParamKind kind = OverlayParamKind::Number;
  double number = 0.0;            // default (Number)
  const char* text = "";          // default (Text; Rgb as "r,g,b")
  double lo = 0.0, hi = 0.0;      // accepted range (Number; each component of Rgb)
  const char* unit = "";
  const char* doc = "";
};

// Every row, in the .def's order.
const std::vector<OverlayParamRow>& overlay_param_rows();
// The overlay type names, in the table's order.
const std::vector<std::string>& overlay_types();
bool is_overlay_type(const std::string& type);
// The row of (type, key), or nullptr.
const OverlayParamRow* overlay_param(const std::string& type, const std::string& key);

// One overlay of a scene: its type and every parameter of its rows, typed.
struct OverlaySpec {
  std::string type;
  bool enabled = true;  // the viewer's toggle; a scene file entry is always on
  std::map<std::string, double> numbers;
  std::map<std::string, std::string> texts;
  std::map<std::string, glm::dvec3> colors;
  bool operator==(const OverlaySpec&) const = default;

  double number(const std::string& key) const;
  const std::string& text(const std::string& key) const;
  glm::dvec3 color(const std::string& key) const;
};

// An overlay of `type` with every parameter at its default; std::invalid_argument for an unknown type.
OverlaySpec default_overlay(const std::string& type);

// What the overlay types are, for messages: "one of coastlines, graticule, isosurface, wind".
std::string overlay_types_expected();
// What a parameter accepts, for messages: "a number 0.5..90 (degrees)", "[r, g, b], each 0..1000".
std::string overlay_param_expected(const OverlayParamRow& row);

// Sets a parameter from text (the CLI's key=value; an Rgb as r,g,b or r/g/b); throws
// std::invalid_argument with "found X, expected Y" for an unknown key or a bad value.
void set_overlay_param(OverlaySpec& spec, const std::string& key, const std::string& value);

// `render --overlay NAME[:key=value,...]`: throws std::invalid_argument with one line naming what
// was wrong ("--overlay graticule:step_deg=0: found 0, expected a number 0.5..90 (degrees)").
OverlaySpec parse_overlay_flag(const std::string& arg);

}  // namespace cv::core
