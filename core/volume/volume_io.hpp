// Writing a CloudVolume: the documented .cvvol format (docs/formats.md) and VTK XML image data
// (.vti, one file per time step) that ParaView opens. Every file is written atomically.
#pragma once

#include <functional>
#include <string>

#include "volume/cloud_volume.hpp"

namespace cv::core {

// Writes `data` to `path` through a temporary file in the same folder and a rename, so a reader
// never sees a half-written file. Throws std::runtime_error naming the path on failure.
void write_file_atomically(const std::string& path, const std::function<void(std::FILE*)>& write);

// Writes every time step (loading each in turn); progress(step, count) is called before each.
void write_cvvol(const std::string& path, CloudVolume& volume,
                 const std::function<void(std::size_t, std::size_t)>& progress = {});
void write_vti(const std::string& path, const VolumeGrid& grid, const TimeStepData& data,
               const std::array<bool, kFieldCount>& has_field);

}  // namespace cv::core
