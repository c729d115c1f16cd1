// The model a table is built from: for each focus-stack depth, the integer
// feature positions relative to the reference point, plus the detector whose
// features the table expects in frames.
#pragma once

#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

#include "gabarit/table_format.hpp"

namespace gabarit::host {

struct Point {
  std::int32_t x = 0;
  std::int32_t y = 0;
  friend bool operator==(const Point&, const Point&) = default;
  friend auto operator<=>(const Point&, const Point&) = default;
};

struct DetectorSettings {
  table_format::DetectorKind kind = table_format::DetectorKind::kBinary;
  std::uint16_t threshold = 0;  // gradient magnitude threshold (gradient detectors only)
};

struct ModelStack {
  std::vector<std::vector<Point>> depths;  // depths[n] = feature points of stack image n
  float ref_x = 0;                         // reference point in model-image pixels
  float ref_y = 0;
  std::uint16_t image_width = 0;           // 0 for point models
  std::uint16_t image_height = 0;
  DetectorSettings detector;
  // The model images themselves (image_width x image_height each, one per
  // depth) when built from images; stored in the table (format 1.1) so the
  // tracker has its focus stack without being given it again.
  std::vector<std::vector<std::uint8_t>> images;
};

// Points CSV: one integer "x,y" per line relative to the reference point; an
// optional header line (the first line, with letters: "x,y"); blank lines and
// '#' comments ignored; |x|, |y| <= 16384. Errors name the file and line.
std::vector<Point> read_points_csv(const std::string& path);
std::vector<Point> read_points_csv(std::istream& in, const std::string& name);
void write_points_csv(const std::string& path, const std::vector<Point>& points);

struct ImageModelOptions {
  bool binary = false;            // non-zero pixel = feature
  bool canny = false;             // the Canny variant instead of gradient rows (same threshold rule)
  int threshold = -1;             // gradient threshold; -1 = derive from the first image
  bool has_ref = false;           // reference point given (else image centre, floor(w/2), floor(h/2))
  std::int32_t ref_x = 0, ref_y = 0;
};

// Extracts features from each PGM (a focus stack, ordered by depth) with the
// same kernel detector that runs on frames. All images must share one size.
ModelStack model_from_images(const std::vector<std::string>& paths, const ImageModelOptions& options);

// The default gradient threshold: a quarter of the image's strongest Sobel
// magnitude (at least 1). Documented in docs/tracking.md ("Detectors").
std::uint16_t default_gradient_threshold(std::uint16_t strongest_magnitude);

}  // namespace gabarit::host
