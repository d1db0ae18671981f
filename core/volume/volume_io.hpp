// Writing a CloudVolume: the documented .cvvol format (docs/importers.md) and VTK XML image data
// (.vti, one file per time step) that ParaView opens. Every file is written atomically.
#pragma once

#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>

#include "io/input_file.hpp"
#include "io/output_file.hpp"
#include "volume/cloud_volume.hpp"

namespace cv::core {

// How the 3-D fields are stored. Float16: IEEE half precision, extinction in 1/km (so values down
// to 6.1e-8 /m stay normal), the others in their SI units: relative error at most 2^-11 (4.9e-4)
// for normal values, absolute at most 3e-11 /m for extinction below that, 2.4e-4 for a fraction,
// 0.125 K for temperature and 0.031 m/s for winds up to 128 m/s; NaN stays NaN. Maps stay float32.
enum class CvvolEncoding { Float32, Float16 };

// Writes every time step (loading each in turn); progress(step, count) is called before each.
// Written atomically (io/output_file.hpp): alone, or as a member of `group`, committed with it.
void write_cvvol(const std::string& path, CloudVolume& volume,
                 const std::function<void(std::size_t, std::size_t)>& progress = {},
                 CvvolEncoding encoding = CvvolEncoding::Float32);
void write_cvvol(OutputGroup& group, const std::string& path, CloudVolume& volume,
                 const std::function<void(std::size_t, std::size_t)>& progress = {},
                 CvvolEncoding encoding = CvvolEncoding::Float32);

// IEEE 754 binary16 conversions (round to nearest even; NaN kept; overflow to infinity).
std::uint16_t float_to_half(float f);
float half_to_float(std::uint16_t h);
// out[i] = float_to_half(in[i] * scale) for i < n, bit for bit; with the processor's F16C
// instructions where it has them (eight at a time), else value by value.
void floats_to_halves(const float* in, float scale, std::uint16_t* out, std::size_t n);
// out[i] = half_to_float(in[i]) * scale for i < n, bit for bit (eight at a time with F16C).
void halves_to_floats(const std::uint16_t* in, float scale, float* out, std::size_t n);
// A .cvvol that cannot be read: missing, of another kind, truncated or corrupt (bad input).
class VolumeFileError : public InputError {
 public:
  using InputError::InputError;
};

// Opens a .cvvol written by write_cvvol: grid, times and fields come from its header; time steps
// are read lazily from the file (one seek each). Throws std::runtime_error naming the file and what
// is wrong (bad magic, truncated header or payload, unknown field) as a VolumeFileError.
CloudVolume read_cvvol(const std::string& path, std::size_t cache_steps = 2);

void write_vti(const std::string& path, const VolumeGrid& grid, const TimeStepData& data,
               const std::array<bool, kFieldCount>& has_field);
void write_vti(OutputGroup& group, const std::string& path, const VolumeGrid& grid, const TimeStepData& data,
               const std::array<bool, kFieldCount>& has_field);

// What is wrong with a grid, or "" when nothing: each axis has a finite start, a finite step > 0
// and 1..1e6 points; longitudes span at most one turn, latitudes lie within -90..90, altitudes
// within -1 km..100 km, and the Earth's radius lies within 1000..100 000 km.
std::string grid_problem(const VolumeGrid& grid);

}  // namespace cv::core
