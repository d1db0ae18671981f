// OpenEXR output through the OpenEXR library, into the FILE the atomic output gives.
#include "render/exr_output.hpp"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfStandardAttributes.h>
#include <ImathBox.h>

#include <cerrno>
#include <filesystem>
#include <cstring>
#include <stdexcept>

#include "io/output_file.hpp"

namespace cv::render {
namespace {
constexpr long long kMaxExrSide = 16384;  // render's and record's largest --size

// OpenEXR's output stream over the FILE: positions count from where the stream stood when it was
// handed over (0 for the files the outputs open). Nothing here throws from tellp(): OpenEXR's
// OutputFile destructor calls it outside its own error handling (a throw there would end the
// process) and writes the line offset table there, swallowing errors; so every failure is kept in
// `failed()` and the caller checks it once the OutputFile is gone.
class FileStream : public Imf::OStream {
 public:
  explicit FileStream(std::FILE* f) : Imf::OStream("OpenEXR output"), f_(f), start_(ftello(f)) {
    if (start_ < 0) throw core::WriteError(std::string("cannot tell the output's position (") + std::strerror(errno) + ")");
  }
  void write(const char c[], int n) override {
    if (n > 0 && std::fwrite(c, 1, static_cast<std::size_t>(n), f_) != static_cast<std::size_t>(n)) {
      fail("write failed");
      throw core::WriteError(error_);
    }
  }
  uint64_t tellp() override {
    const off_t at = ftello(f_);
    if (at < start_) {
      fail("cannot tell the output's position");
      return static_cast<uint64_t>(-1);  // OpenEXR's own mark of a position it cannot use
    }
    return static_cast<uint64_t>(at - start_);
  }
  void seekp(uint64_t pos) override {
    if (fseeko(f_, start_ + static_cast<off_t>(pos), SEEK_SET) != 0) {
      fail("cannot seek in the output");
      throw core::WriteError(error_);
    }
  }
  bool failed() const { return !error_.empty(); }
  const std::string& error() const { return error_; }

 private:
  void fail(const char* what) {
    if (error_.empty()) error_ = std::string(what) + " (" + std::strerror(errno) + ")";
  }
  std::FILE* f_;
  off_t start_;
  std::string error_;
};
}  // namespace

void encode_exr(std::FILE* f, int width, int height, const std::vector<glm::vec4>& pixels, bool with_alpha) {
  if (width <= 0 || height <= 0 || pixels.size() != static_cast<std::size_t>(width) * static_cast<std::size_t>(height)) {
    throw std::invalid_argument("encode_exr: " + std::to_string(pixels.size()) + " pixels for " + std::to_string(width) + " x " +
                                std::to_string(height));
  }
  Imf::Header header(width, height);
  header.compression() = Imf::ZIP_COMPRESSION;
  for (const char* c : {"R", "G", "B"}) header.channels().insert(c, Imf::Channel(Imf::FLOAT));
  if (with_alpha) header.channels().insert("A", Imf::Channel(Imf::FLOAT));
  Imf::addComments(header, with_alpha ? "cloudviewer: R, G, B linear radiance (no background, no exposure); A = 1 - transmittance "
                                        "(premultiplied: over a plate, RGB + (1 - A) x plate; A is 1 where the globe was drawn)"
                                      : "cloudviewer: R, G, B linear radiance (no background, no exposure); no transmittance estimated");
  // The library reads the channels through strides; R, G, B straight from the pixels.
  auto* base = reinterpret_cast<char*>(const_cast<glm::vec4*>(pixels.data()));
  const std::size_t xs = sizeof(glm::vec4), ys = sizeof(glm::vec4) * static_cast<std::size_t>(width);
  Imf::FrameBuffer fb;
  fb.insert("R", Imf::Slice(Imf::FLOAT, base + 0 * sizeof(float), xs, ys));
  fb.insert("G", Imf::Slice(Imf::FLOAT, base + 1 * sizeof(float), xs, ys));
  fb.insert("B", Imf::Slice(Imf::FLOAT, base + 2 * sizeof(float), xs, ys));
  std::vector<float> alpha;
  if (with_alpha) {
    alpha.resize(pixels.size());
    for (std::size_t i = 0; i < pixels.size(); ++i) alpha[i] = 1.0f - pixels[i].a;
    fb.insert("A", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(alpha.data()), sizeof(float), sizeof(float) * static_cast<std::size_t>(width)));
  }
  FileStream out(f);
  try {
    // One thread: the frame is small beside the march, and the library's pool would outlive us.
    Imf::OutputFile file(out, header, 0);
    file.setFrameBuffer(fb);
    file.writePixels(height);
  } catch (const core::WriteError&) {
    throw;
  } catch (const std::exception& e) {
    throw core::WriteError(out.failed() ? out.error() : std::string("OpenEXR: ") + e.what());
  }
  // The destructor above wrote the line offset table and kept its errors to itself.
  if (out.failed()) throw core::WriteError(out.error());
  if (std::fflush(f) != 0 || std::ferror(f)) throw core::WriteError(std::string("write failed (") + std::strerror(errno) + ")");
}

ExrImage read_exr(const std::string& path, const std::vector<std::string>& names) {
  try {
    Imf::InputFile file(path.c_str(), 0);
    const Imath::Box2i dw = file.header().dataWindow();
    ExrImage img;
    const long long w = static_cast<long long>(dw.max.x) - dw.min.x + 1, h = static_cast<long long>(dw.max.y) - dw.min.y + 1;
    // A header may claim any size: refused past what render writes before anything is allocated.
    if (w < 1 || h < 1 || w > kMaxExrSide || h > kMaxExrSide) {
      throw std::runtime_error("a data window of " + std::to_string(w) + " x " + std::to_string(h) + ", expected 1.." +
                               std::to_string(kMaxExrSide) + " on each side");
    }
    img.width = static_cast<int>(w);
    img.height = static_cast<int>(h);
    for (auto it = file.header().channels().begin(); it != file.header().channels().end(); ++it) img.channels.push_back(it.name());
    const std::size_t n = static_cast<std::size_t>(img.width) * static_cast<std::size_t>(img.height);
    Imf::FrameBuffer fb;
    img.values.assign(names.size(), std::vector<float>(n));
    for (std::size_t c = 0; c < names.size(); ++c) {
      if (!file.header().channels().findChannel(names[c])) throw std::runtime_error(path + ": no channel '" + names[c] + "'");
      // Offsets so that the data window's first pixel lands at index 0.
      char* origin = reinterpret_cast<char*>(img.values[c].data()) -
                     (static_cast<std::ptrdiff_t>(dw.min.x) + static_cast<std::ptrdiff_t>(dw.min.y) * img.width) * static_cast<std::ptrdiff_t>(sizeof(float));
      fb.insert(names[c], Imf::Slice(Imf::FLOAT, origin, sizeof(float), sizeof(float) * static_cast<std::size_t>(img.width)));
    }
    file.setFrameBuffer(fb);
    file.readPixels(dw.min.y, dw.max.y);
    return img;
  } catch (const std::exception& e) {
    throw std::runtime_error(path + ": " + e.what());
  }
}

bool exr_decodes_at_size(const std::string& path, int width, int height, bool alpha) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return false;
  const std::vector<std::string> names = alpha ? std::vector<std::string>{"R", "G", "B", "A"} : std::vector<std::string>{"R", "G", "B"};
  try {
    {  // The header first: a damaged file's claimed size is never allocated.
      Imf::InputFile file(path.c_str(), 0);
      const Imath::Box2i dw = file.header().dataWindow();
      if (dw.min.x != 0 || dw.min.y != 0 || dw.max.x != width - 1 || dw.max.y != height - 1) return false;
      for (const std::string& n : names) {
        if (!file.header().channels().findChannel(n)) return false;
      }
    }
    const ExrImage img = read_exr(path, names);
    return img.width == width && img.height == height;
  } catch (const std::exception&) {
    return false;
  }
}

}  // namespace cv::render
