// Scene files: the Scene struct as versioned JSON (docs/scene.md lists every key), read strictly so
// that a typo or an out-of-range value is named instead of silently ignored.
#pragma once

#include <stdexcept>
#include <string>

#include "io/input_file.hpp"
#include "scene/scene.hpp"

namespace cv::core {

// A scene file that cannot be used. The message is one line: the file, the key path, what was
// found and what was expected, e.g.
//   scene.json: render.march.sun_steps: found "abc", expected an integer 1..1024
class SceneError : public InputError {
 public:
  using InputError::InputError;
};

// Scene files are small: larger ones, and nesting deeper than this, are refused before parsing on.
inline constexpr std::uint64_t kMaxSceneBytes = 16u << 20;
inline constexpr int kMaxSceneDepth = 32;

// Parses a scene from JSON text; `source` names it in messages (the file's path). Missing keys
// take their defaults, unknown keys and values of the wrong type or range throw SceneError. The
// data path is returned as written.
Scene scene_from_json(const std::string& text, const std::string& source = "scene");

// The scene as JSON text (every key written, so the file documents itself), ending in a newline.
std::string scene_to_json(const Scene& scene);

// Reads a scene file (a regular file only: a FIFO or device is refused, never read); a relative
// data path and a relative render.march.ground_texture are resolved against the file's folder.
Scene load_scene(const std::string& path);

// Writes a scene file atomically (a reader never sees half of it). The data path is written as it
// is in the struct. Throws std::runtime_error naming the path when it cannot be written.
void save_scene(const Scene& scene, const std::string& path);

}  // namespace cv::core
