#include "gabarit/host/tables/model.hpp"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <sstream>

#include "gabarit/features.hpp"
#include "gabarit/app/error.hpp"
#include "gabarit/app/files.hpp"
#include "gabarit/app/image_io.hpp"

namespace gabarit::host {

std::vector<Point> read_points_csv(const std::string& path) {
  std::istringstream in(app::read_text(path));
  return read_points_csv(in, path);
}

std::vector<Point> read_points_csv(std::istream& in, const std::string& path) {
  std::vector<Point> points;
  std::string line;
  std::size_t line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line[0] == '#') continue;
    long x = 0, y = 0;
    char comma = 0, extra = 0;
    std::istringstream fields(line);
    if (!(fields >> x >> comma >> y) || comma != ',' || (fields >> extra)) {
      // A header: the first line, naming columns (letters), not a malformed point.
      const bool names = std::any_of(line.begin(), line.end(), [](unsigned char ch) { return std::isalpha(ch) != 0; });
      if (points.empty() && line_number == 1 && names) continue;
      throw app::Error(path + ":" + std::to_string(line_number) + ": expected integer 'x,y', got '" + line + "'");
    }
    if (x < -16384 || x > 16384 || y < -16384 || y > 16384) {
      throw app::Error(path + ":" + std::to_string(line_number) + ": point out of range (|x|,|y| <= 16384)");
    }
    points.push_back({static_cast<std::int32_t>(x), static_cast<std::int32_t>(y)});
  }
  if (points.empty()) throw app::Error(path + ": no points");
  return points;
}

void write_points_csv(const std::string& path, const std::vector<Point>& points) {
  std::ostringstream out;
  out << "x,y\n";
  for (const Point& p : points) out << p.x << ',' << p.y << '\n';
  app::write_file(path, out.str());
}

std::uint16_t default_gradient_threshold(std::uint16_t strongest_magnitude) {
  return static_cast<std::uint16_t>(std::max(1, strongest_magnitude / 4));
}

ModelStack model_from_images(const std::vector<std::string>& paths, const ImageModelOptions& options) {
  if (paths.empty()) throw app::Error("no model image given");
  ModelStack model;
  model.detector.kind = options.binary  ? table_format::DetectorKind::kBinary
                        : options.canny ? table_format::DetectorKind::kCanny
                                        : table_format::DetectorKind::kGradientRows;
  std::int32_t ref_x = options.ref_x, ref_y = options.ref_y;
  for (std::size_t i = 0; i < paths.size(); ++i) {
    const app::GrayImage image = app::read_pgm(paths[i]);
    if (image.width > 4096 || image.height > 4096) throw app::Error(paths[i] + ": model image larger than 4096x4096");
    if (i == 0) {
      model.image_width = static_cast<std::uint16_t>(image.width);
      model.image_height = static_cast<std::uint16_t>(image.height);
      if (!options.has_ref) {
        ref_x = static_cast<std::int32_t>(image.width / 2);
        ref_y = static_cast<std::int32_t>(image.height / 2);
      }
      if (!options.binary) {
        if (options.threshold >= 0) {
          if (options.threshold < 1 || options.threshold > kMaxGradientMagnitude) {
            throw app::Error("--threshold must be in 1.." + std::to_string(kMaxGradientMagnitude));
          }
          model.detector.threshold = static_cast<std::uint16_t>(options.threshold);
        } else {
          std::uint16_t strongest = 0;
          for (std::uint32_t y = 0; y < image.height; ++y)
            for (std::uint32_t x = 0; x < image.width; ++x)
              strongest = std::max(strongest, gradient_magnitude(image.view(), x, y));
          if (strongest == 0) throw app::Error(paths[i] + ": flat image, no edges to build a model from");
          model.detector.threshold = default_gradient_threshold(strongest);
          if (options.canny && model.detector.threshold < 2) model.detector.threshold = 2;  // its low threshold is half
        }
      }
    } else if (image.width != model.image_width || image.height != model.image_height) {
      throw app::Error(paths[i] + ": focus-stack images must all have the size of " + paths[0]);
    }
    model.images.push_back(image.pixels);
    const ImageWindow whole{0, 0, static_cast<std::uint16_t>(image.width), static_cast<std::uint16_t>(image.height)};
    std::vector<RoiPoint> found(feature_capacity(whole.width, whole.height));
    FeatureCount count;
    if (extract_features(image.view(), whole, model.detector.kind, model.detector.threshold, found, count) !=
        Status::kOk) {
      throw app::Error(paths[i] + ": feature extraction failed");
    }
    std::vector<Point> points;
    points.reserve(count.written);
    for (std::uint32_t k = 0; k < count.written; ++k) points.push_back({found[k].col - ref_x, found[k].row - ref_y});
    if (points.empty()) throw app::Error(paths[i] + ": no features found (try --binary or a lower --threshold)");
    model.depths.push_back(std::move(points));
  }
  model.ref_x = static_cast<float>(ref_x);
  model.ref_y = static_cast<float>(ref_y);
  return model;
}

}  // namespace gabarit::host
