#include "gabarit/app/image_io.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>

#include "gabarit/app/error.hpp"

namespace gabarit::app {
namespace {

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};
using File = std::unique_ptr<std::FILE, FileCloser>;

File open_or_throw(const std::string& path, const char* mode) {
  File f(std::fopen(path.c_str(), mode));
  if (!f) throw Error(path + ": cannot open: " + std::strerror(errno));
  return f;
}

// Reads one whitespace-separated PNM header token, skipping # comments.
std::string pnm_token(std::FILE* f, const std::string& path) {
  std::string token;
  int c;
  while ((c = std::fgetc(f)) != EOF) {
    if (c == '#') {
      while ((c = std::fgetc(f)) != EOF && c != '\n') {}
      continue;
    }
    if (std::isspace(c)) {
      if (!token.empty()) return token;
      continue;
    }
    token.push_back(static_cast<char>(c));
    if (token.size() > 16) throw Error(path + ": malformed PGM header");
  }
  if (token.empty()) throw Error(path + ": truncated PGM header");
  return token;
}

std::uint32_t parse_dimension(const std::string& token, const std::string& path, const char* field,
                              std::uint32_t max) {
  char* end = nullptr;
  errno = 0;
  const unsigned long v = std::strtoul(token.c_str(), &end, 10);
  if (token.empty() || *end != '\0' || token[0] == '-' || token[0] == '+' || errno != 0 || v == 0 || v > max) {
    throw Error(path + ": bad " + field + " '" + token + "' (1.." + std::to_string(max) + ")");
  }
  return static_cast<std::uint32_t>(v);
}

// Bytes left in a regular file from the current position; -1 when the
// stream is not one (a pipe, a terminal, memory): its size is not known.
long long bytes_left(std::FILE* f) {
  const int fd = ::fileno(f);
  struct stat st {};
  if (fd < 0 || ::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) return -1;
  const long at = std::ftell(f);
  return at < 0 ? -1 : static_cast<long long>(st.st_size) - at;
}

void check_frame_size(std::uint32_t width, std::uint32_t height, const std::string& path) {
  if (std::uint64_t{width} * height > kMaxFramePixels) {
    throw Error(path + ": " + std::to_string(width) + "x" + std::to_string(height) + " is more than the " +
                std::to_string(kMaxFramePixels) + " pixels a frame may have");
  }
}

class Y4mSource final : public FrameSource {
 public:
  // Reads from `file`, which it closes when `owned`.
  Y4mSource(std::FILE* file, bool owned, std::string path) : path_(std::move(path)), file_(file), owned_(owned) {
    std::string header;
    int c;
    while ((c = std::fgetc(file_)) != EOF && c != '\n') {
      header.push_back(static_cast<char>(c));
      if (header.size() > 4096) throw Error(path_ + ": Y4M header line too long");
    }
    if (header.rfind("YUV4MPEG2", 0) != 0) throw Error(path_ + ": not a Y4M file (no YUV4MPEG2 signature)");
    if (c == EOF) throw Error(path_ + ": truncated Y4M header (no end of line)");
    if (!header.empty() && header.back() == '\r') {
      throw Error(path_ + ": the Y4M header line ends with a carriage return (a CRLF line ending); Y4M lines end with LF alone");
    }
    std::string colour = "420jpeg";  // the Y4M default
    bool seen_w = false, seen_h = false, seen_c = false;
    std::size_t pos = 9;
    while (pos < header.size()) {
      while (pos < header.size() && header[pos] == ' ') ++pos;
      std::size_t end = header.find(' ', pos);
      if (end == std::string::npos) end = header.size();
      const std::string tag = header.substr(pos, end - pos);
      pos = end;
      if (tag.empty()) continue;
      const auto once = [&](bool& seen) {
        if (seen) throw Error(path_ + ": Y4M header gives " + tag.substr(0, 1) + " twice");
        seen = true;
      };
      if (tag[0] == 'W') once(seen_w), width_ = parse_dimension(tag.substr(1), path_, "Y4M width", kMaxFrameSide);
      if (tag[0] == 'H') once(seen_h), height_ = parse_dimension(tag.substr(1), path_, "Y4M height", kMaxFrameSide);
      if (tag[0] == 'C') once(seen_c), colour = tag.substr(1);
    }
    if (width_ == 0 || height_ == 0) throw Error(path_ + ": Y4M header has no W/H");
    check_frame_size(width_, height_, path_);
    const std::size_t luma = std::size_t{width_} * height_;
    const std::size_t half_w = (width_ + 1) / 2, half_h = (height_ + 1) / 2;
    // 8-bit planar layouts only: the luma plane first, then the chroma skipped.
    if (colour == "mono") {
      chroma_ = 0;
    } else if (colour == "420" || colour == "420jpeg" || colour == "420paldv" || colour == "420mpeg2") {
      chroma_ = 2 * half_w * half_h;
    } else if (colour == "444") {
      chroma_ = 2 * luma;
    } else {
      throw Error(path_ + ": Y4M colourspace C" + colour +
                  " not supported (8-bit only: Cmono, C420, C420jpeg, C420paldv, C420mpeg2, C444)");
    }
  }
  ~Y4mSource() override {
    if (owned_) std::fclose(file_);
  }
  Y4mSource(const Y4mSource&) = delete;
  Y4mSource& operator=(const Y4mSource&) = delete;

  bool next(GrayImage& frame) override {
    std::string line;
    int c;
    while ((c = std::fgetc(file_)) != EOF && c != '\n') {
      line.push_back(static_cast<char>(c));
      if (line.size() > 4096) throw Error(path_ + ": frame " + std::to_string(index_) + ": FRAME line too long");
    }
    if (c == EOF && line.empty()) return false;
    if (line != "FRAME" && line.rfind("FRAME ", 0) != 0) {
      throw Error(path_ + ": frame " + std::to_string(index_) + ": missing FRAME marker");
    }
    // A regular file too short for the frame is refused before it is allocated.
    const std::size_t luma = std::size_t{width_} * height_;
    const long long left = bytes_left(file_);
    if (left >= 0 && static_cast<unsigned long long>(left) < luma + chroma_) {
      throw Error(path_ + ": frame " + std::to_string(index_) + ": truncated (the header says " + std::to_string(width_) + "x" +
                  std::to_string(height_) + ", " + std::to_string(left) + " bytes are left)");
    }
    frame.width = width_;
    frame.height = height_;
    frame.pixels.resize(luma);
    bool whole = std::fread(frame.pixels.data(), 1, frame.pixels.size(), file_) == frame.pixels.size();
    // Skip the chroma by reading it (a pipe cannot seek).
    for (std::size_t left = chroma_; whole && left > 0;) {
      char skip[4096];
      const std::size_t n = left < sizeof skip ? left : sizeof skip;
      whole = std::fread(skip, 1, n, file_) == n;
      left -= n;
    }
    if (!whole) throw Error(path_ + ": frame " + std::to_string(index_) + ": truncated");
    ++index_;
    return true;
  }

 private:
  std::string path_;
  std::FILE* file_;
  bool owned_;
  std::uint32_t width_ = 0, height_ = 0;
  std::size_t chroma_ = 0;
  std::size_t index_ = 0;
};

class PgmDirectorySource final : public FrameSource {
 public:
  explicit PgmDirectorySource(const std::string& dir) {
    for (const auto& entry : std::filesystem::directory_iterator(dir)) {
      if (entry.is_regular_file() && entry.path().extension() == ".pgm") files_.push_back(entry.path().string());
    }
    std::sort(files_.begin(), files_.end());
    if (files_.empty()) throw Error(dir + ": no .pgm frames in directory");
  }
  bool next(GrayImage& frame) override {
    if (index_ >= files_.size()) return false;
    frame = read_pgm(files_[index_++]);
    return true;
  }

 private:
  std::vector<std::string> files_;
  std::size_t index_ = 0;
};

}  // namespace

GrayImage read_pgm(const std::string& path) {
  File f = open_or_throw(path, "rb");
  return read_pgm(f.get(), path);
}

GrayImage read_pgm(std::FILE* f, const std::string& path) {
  const std::string magic = pnm_token(f, path);
  if (magic != "P5" && magic != "P2") throw Error(path + ": not a PGM file (magic '" + magic + "', want P5 or P2)");
  GrayImage image;
  image.width = parse_dimension(pnm_token(f, path), path, "PGM width", kMaxFrameSide);
  image.height = parse_dimension(pnm_token(f, path), path, "PGM height", kMaxFrameSide);
  check_frame_size(image.width, image.height, path);
  const std::uint32_t maxval = parse_dimension(pnm_token(f, path), path, "PGM maxval", 65535);
  if (maxval > 255) throw Error(path + ": 16-bit PGM (maxval " + std::to_string(maxval) + ") not supported");
  const std::size_t pixels = std::size_t{image.width} * image.height;
  // A file too short for its header's size is refused before the pixels are
  // allocated; P2 needs at least a digit and a separator per pixel.
  const long long left = bytes_left(f);
  const std::size_t least = magic == "P5" ? pixels : 2 * pixels - 1;
  if (left >= 0 && static_cast<unsigned long long>(left) < least) {
    throw Error(path + ": truncated PGM pixel data (the header says " + std::to_string(image.width) + "x" +
                std::to_string(image.height) + ")");
  }
  if (magic == "P5" && left >= 0 && static_cast<unsigned long long>(left) > pixels) {
    // The raster starts right after the one whitespace that ends maxval. A
    // comment or a line break there is a malformed header, not pixels.
    const int first = std::fgetc(f);
    if (first == '#' || first == '\n') {
      throw Error(path + ": PGM header: " + std::string(first == '#' ? "a comment" : "a second line break (CRLF?)") +
                  " after maxval; the raster must follow the single whitespace after it");
    }
    if (first != EOF) std::ungetc(first, f);
  }
  image.pixels.resize(pixels);
  if (magic == "P5") {
    if (std::fread(image.pixels.data(), 1, image.pixels.size(), f) != image.pixels.size()) {
      throw Error(path + ": truncated PGM pixel data");
    }
  } else {
    for (auto& p : image.pixels) {
      const std::string token = pnm_token(f, path);
      char* end = nullptr;
      const unsigned long v = std::strtoul(token.c_str(), &end, 10);
      if (*end != '\0' || !std::isdigit(static_cast<unsigned char>(token[0])) || v > maxval) {
        throw Error(path + ": PGM pixel '" + token + "' is not a value in 0.." + std::to_string(maxval));
      }
      p = static_cast<std::uint8_t>(v);
    }
  }
  if (maxval != 255) {
    for (auto& p : image.pixels) p = static_cast<std::uint8_t>(std::min<std::uint32_t>(255, (p * 255u + maxval / 2) / maxval));
  }
  return image;
}

void write_pgm(const std::string& path, const GrayImage& image) {
  OutputFile out(path);
  out.write("P5\n" + std::to_string(image.width) + " " + std::to_string(image.height) + "\n255\n");
  out.write(std::as_bytes(std::span(image.pixels)));
  out.commit();
}

std::unique_ptr<FrameSource> open_frames(const std::string& path) {
  if (path == "-") return std::make_unique<Y4mSource>(stdin, false, "standard input");
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) return std::make_unique<PgmDirectorySource>(path);
  File f = open_or_throw(path, "rb");
  auto source = std::make_unique<Y4mSource>(f.get(), true, path);
  f.release();  // the source closes it
  return source;
}

std::unique_ptr<FrameSource> open_y4m(std::FILE* stream, const std::string& name) {
  return std::make_unique<Y4mSource>(stream, false, name);
}

Y4mWriter::Y4mWriter(const std::string& path, std::uint32_t width, std::uint32_t height, std::uint32_t fps)
    : file_(path), width_(width), height_(height) {
  file_.write("YUV4MPEG2 W" + std::to_string(width) + " H" + std::to_string(height) + " F" + std::to_string(fps) +
              ":1 Ip A1:1 Cmono\n");
}

void Y4mWriter::write(const GrayImage& frame) {
  if (frame.width != width_ || frame.height != height_) throw Error(file_.path() + ": frame size differs from stream size");
  file_.write("FRAME\n");
  file_.write(std::as_bytes(std::span(frame.pixels)));
}

void Y4mWriter::close() { file_.commit(); }

}  // namespace gabarit::app
