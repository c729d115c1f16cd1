#include "gabarit/app/image_io.hpp"

#include <algorithm>
#include <cctype>
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
  const unsigned long v = std::strtoul(token.c_str(), &end, 10);
  if (token.empty() || *end != '\0' || v == 0 || v > max) {
    throw Error(path + ": bad " + field + " '" + token + "' (1.." + std::to_string(max) + ")");
  }
  return static_cast<std::uint32_t>(v);
}

constexpr std::uint32_t kMaxSide = 32768;

class Y4mSource final : public FrameSource {
 public:
  explicit Y4mSource(const std::string& path) : path_(path), file_(open_or_throw(path, "rb")) {
    std::string header;
    int c;
    while ((c = std::fgetc(file_.get())) != EOF && c != '\n') {
      header.push_back(static_cast<char>(c));
      if (header.size() > 4096) throw Error(path + ": Y4M header line too long");
    }
    if (header.rfind("YUV4MPEG2", 0) != 0) throw Error(path + ": not a Y4M file (no YUV4MPEG2 signature)");
    std::string colour = "420jpeg";  // the Y4M default
    std::size_t pos = 9;
    while (pos < header.size()) {
      while (pos < header.size() && header[pos] == ' ') ++pos;
      std::size_t end = header.find(' ', pos);
      if (end == std::string::npos) end = header.size();
      const std::string tag = header.substr(pos, end - pos);
      pos = end;
      if (tag.empty()) continue;
      if (tag[0] == 'W') width_ = parse_dimension(tag.substr(1), path, "Y4M width", kMaxSide);
      if (tag[0] == 'H') height_ = parse_dimension(tag.substr(1), path, "Y4M height", kMaxSide);
      if (tag[0] == 'C') colour = tag.substr(1);
    }
    if (width_ == 0 || height_ == 0) throw Error(path + ": Y4M header has no W/H");
    const std::size_t luma = std::size_t{width_} * height_;
    if (colour == "mono") {
      chroma_ = 0;
    } else if (colour.rfind("420", 0) == 0) {
      chroma_ = 2 * (std::size_t{(width_ + 1) / 2} * ((height_ + 1) / 2));
    } else if (colour.rfind("444", 0) == 0 && colour.find("alpha") == std::string::npos) {
      chroma_ = 2 * luma;
    } else {
      throw Error(path + ": Y4M colourspace C" + colour + " not supported (use Cmono, C420* or C444)");
    }
  }

  bool next(GrayImage& frame) override {
    std::string line;
    int c;
    while ((c = std::fgetc(file_.get())) != EOF && c != '\n') {
      line.push_back(static_cast<char>(c));
      if (line.size() > 4096) throw Error(path_ + ": frame " + std::to_string(index_) + ": FRAME line too long");
    }
    if (c == EOF && line.empty()) return false;
    if (line.rfind("FRAME", 0) != 0) throw Error(path_ + ": frame " + std::to_string(index_) + ": missing FRAME marker");
    frame.width = width_;
    frame.height = height_;
    frame.pixels.resize(std::size_t{width_} * height_);
    if (std::fread(frame.pixels.data(), 1, frame.pixels.size(), file_.get()) != frame.pixels.size() ||
        std::fseek(file_.get(), static_cast<long>(chroma_), SEEK_CUR) != 0) {
      throw Error(path_ + ": frame " + std::to_string(index_) + ": truncated");
    }
    ++index_;
    return true;
  }

 private:
  std::string path_;
  File file_;
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
  const std::string magic = pnm_token(f.get(), path);
  if (magic != "P5" && magic != "P2") throw Error(path + ": not a PGM file (magic '" + magic + "', want P5 or P2)");
  GrayImage image;
  image.width = parse_dimension(pnm_token(f.get(), path), path, "PGM width", kMaxSide);
  image.height = parse_dimension(pnm_token(f.get(), path), path, "PGM height", kMaxSide);
  const std::uint32_t maxval = parse_dimension(pnm_token(f.get(), path), path, "PGM maxval", 65535);
  if (maxval > 255) throw Error(path + ": 16-bit PGM (maxval " + std::to_string(maxval) + ") not supported");
  image.pixels.resize(std::size_t{image.width} * image.height);
  if (magic == "P5") {
    if (std::fread(image.pixels.data(), 1, image.pixels.size(), f.get()) != image.pixels.size()) {
      throw Error(path + ": truncated PGM pixel data");
    }
  } else {
    for (auto& p : image.pixels) {
      const std::uint32_t v = parse_dimension(pnm_token(f.get(), path), path, "PGM pixel", 65535) ;
      if (v > maxval) throw Error(path + ": PGM pixel above maxval");
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
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) return std::make_unique<PgmDirectorySource>(path);
  return std::make_unique<Y4mSource>(path);
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
