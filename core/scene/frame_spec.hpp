// A scene resolved against its data into what one frame needs: the camera at the output size and at
// the march size, the sun, the march settings with everything the scene left automatic filled in
// (view step from the grid, droplet diameter from the data), the accumulation and the exposure.
// `render`, the viewer and the bench all start a frame here.
#pragma once

#include <string>

#include "frame/camera.hpp"
#include "frame/sun.hpp"
#include "settings/march_settings.hpp"
#include "scene/instant.hpp"
#include "scene/scene.hpp"
#include "volume/cloud_volume.hpp"

namespace cv::core {

struct FrameSpec {
  Camera camera;        // at the output size (scene width x height)
  Camera march_camera;  // the same at the march size (render.resolution_scale)
  Sun sun;
  MarchSettings march;
  int accumulate = 1;  // jittered frames averaged (1: one frame at step middles)
  // The jitter index of the accumulation's first frame (frames jitter_base .. jitter_base +
  // accumulate - 1): a video's frame k takes k * accumulate, so each frame's seeds come from its
  // number and the pattern does not repeat from frame to frame.
  int jitter_base = 0;
  double exposure = 4.0;
  bool auto_exposure = false;  // exposure from the marched image (render::auto_exposure), not the number
  bool valid_time_known = false;  // the data's time step has a UTC valid time (else the sun is at noon over the camera)
  Instant instant;                // where the scene's time falls among the file's steps
};

// The scene's instant in `volume`: time.valid_utc when set, else time_step (TimeError otherwise,
// naming `source`, the file).
Instant scene_instant(const Scene& scene, const CloudVolume& volume, const std::string& source);

// The march size of an output of width x height at a resolution scale (clamped to 0.01..1):
// each side rounded, at least 1 pixel.
void march_size(int width, int height, double resolution_scale, int& march_w, int& march_h);

// Resolves the scene's instant in `volume` (scene_instant: TimeError when the file does not hold it). The camera
// frames the volume from the south when the scene has none; the sun follows scene.sun (from the
// valid time unless set). The ground texture stays as the scene names it (the render layer finds it).
FrameSpec resolve_frame(const Scene& scene, const CloudVolume& volume);

}  // namespace cv::core
