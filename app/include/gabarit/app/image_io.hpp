// Grayscale images and sequences on the host: PGM files, Y4M streams (Cmono
// or 4:2:0 — the luma plane is used), and directories of PGM frames. Frames
// are read one at a time; a sequence is never loaded whole.
#pragma once

#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "gabarit/app/files.hpp"
#include "gabarit/image_view.hpp"

namespace gabarit::app {

struct GrayImage {
  std::uint32_t width = 0;
  std::uint32_t height = 0;
  std::vector<std::uint8_t> pixels;  // row-major, stride == width

  GrayImage() = default;
  GrayImage(std::uint32_t w, std::uint32_t h, std::uint8_t fill = 0) : width(w), height(h), pixels(std::size_t{w} * h, fill) {}
  std::uint8_t& at(std::uint32_t x, std::uint32_t y) { return pixels[std::size_t{y} * width + x]; }
  std::uint8_t at(std::uint32_t x, std::uint32_t y) const { return pixels[std::size_t{y} * width + x]; }
  ImageView view() const { return {pixels.data(), width, height, width}; }
};

// Frames and images may be at most kMaxFrameSide pixels a side and
// kMaxFramePixels in all (64 MiB of luma): a header asking for more is
// refused before anything is allocated, and so is one asking for more than a
// regular file holds.
inline constexpr std::uint32_t kMaxFrameSide = 16384;
inline constexpr std::uint64_t kMaxFramePixels = std::uint64_t{1} << 26;

// Binary (P5) or ASCII (P2) PGM with maxval <= 255. Errors name the file.
GrayImage read_pgm(const std::string& path);
// The same from an open stream (a file, a pipe, memory); `name` for errors.
GrayImage read_pgm(std::FILE* stream, const std::string& name);
void write_pgm(const std::string& path, const GrayImage& image);

// A source of frames: next() fills `frame` and returns false at the end.
class FrameSource {
 public:
  virtual ~FrameSource() = default;
  virtual bool next(GrayImage& frame) = 0;
};

// A Y4M file or FIFO ("-": standard input), or a directory of .pgm frames
// read in name order. Y4M: 8-bit Cmono, C420 (any siting) or C444, the
// luma plane used; read sequentially, so a pipe from a camera tool works.
std::unique_ptr<FrameSource> open_frames(const std::string& path);
// A Y4M stream already open (not closed by the source); `name` for errors.
std::unique_ptr<FrameSource> open_y4m(std::FILE* stream, const std::string& name);

// Writes a Y4M stream with colourspace Cmono. The file appears (replacing
// any previous one) only when close() succeeds (files.hpp, OutputFile).
class Y4mWriter {
 public:
  Y4mWriter(const std::string& path, std::uint32_t width, std::uint32_t height, std::uint32_t fps = 30);
  void write(const GrayImage& frame);
  void close();

 private:
  OutputFile file_;
  std::uint32_t width_, height_;
};

}  // namespace gabarit::app
