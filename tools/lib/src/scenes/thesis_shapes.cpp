#include "gabarit/host/scenes/thesis_shapes.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>

#include "gabarit/features.hpp"
#include "gabarit/app/error.hpp"
#include "gabarit/host/scenes/synth.hpp"

namespace gabarit::host {
namespace {

constexpr const char* kSkimageData = "/usr/lib/python3/dist-packages/skimage/data/";

app::GrayImage box_downscale(const app::GrayImage& in, std::uint32_t k) {
  if (k <= 1) return in;
  app::GrayImage out(in.width / k, in.height / k);
  for (std::uint32_t y = 0; y < out.height; ++y)
    for (std::uint32_t x = 0; x < out.width; ++x) {
      std::uint32_t sum = 0;
      for (std::uint32_t dy = 0; dy < k; ++dy)
        for (std::uint32_t dx = 0; dx < k; ++dx) sum += in.at(x * k + dx, y * k + dy);
      out.at(x, y) = static_cast<std::uint8_t>((sum + k * k / 2) / (k * k));
    }
  return out;
}

std::vector<Point> edges(const app::GrayImage& img, std::uint16_t threshold) {
  const ImageWindow whole{0, 0, static_cast<std::uint16_t>(img.width), static_cast<std::uint16_t>(img.height)};
  std::vector<RoiPoint> found(feature_capacity(whole.width, whole.height));
  FeatureCount count;
  if (extract_gradient_rows(img.view(), whole, threshold, found, count) != Status::kOk) throw app::Error("edge extraction failed");
  std::vector<Point> out;
  const auto cx = static_cast<std::int32_t>(img.width / 2), cy = static_cast<std::int32_t>(img.height / 2);
  for (std::uint32_t i = 0; i < count.written; ++i) out.push_back({found[i].col - cx, found[i].row - cy});
  return out;
}

}  // namespace

std::vector<Point> thesis_curve() { return random_closed_curve(194, 0x7E515); }

std::vector<Point> photo_edge_points(const app::GrayImage& photo, std::size_t target, std::uint32_t downscale) {
  const app::GrayImage img = box_downscale(photo, downscale);
  if (img.width < 8 || img.height < 8 || img.width > 4096 || img.height > 4096) throw app::Error("photograph size out of range");
  // The count falls (nearly monotonically) as the threshold rises: bisect.
  std::uint16_t lo = 1, hi = kMaxGradientMagnitude;
  while (hi - lo > 1) {
    const auto mid = static_cast<std::uint16_t>((lo + hi) / 2);
    (edges(img, mid).size() > target ? lo : hi) = mid;
  }
  auto a = edges(img, lo), b = edges(img, hi);
  const auto dist = [&](std::size_t n) { return n > target ? n - target : target - n; };
  return dist(a.size()) <= dist(b.size()) ? a : b;
}

std::string debian_photo_pgm(const std::string& name) {
  const std::string png = std::string(kSkimageData) + name + ".png";
  const auto out = std::filesystem::temp_directory_path() / ("gabarit-" + name + "-" + std::to_string(::getuid()) + ".pgm");
  std::error_code ec;
  if (std::filesystem::exists(out, ec) && std::filesystem::file_size(out, ec) > 0) return out.string();
  if (!std::filesystem::exists(png, ec)) {
    throw app::Error("the photograph " + png + " is missing (apt-get install python3-skimage)");
  }
  const std::string partial = out.string() + ".part" + std::to_string(::getpid());
  const std::string cmd = "pngtopnm '" + png + "' 2>/dev/null | ppmtopgm > '" + partial + "' 2>/dev/null";
  if (std::system(cmd.c_str()) != 0 || !std::filesystem::exists(partial, ec) || std::filesystem::file_size(partial, ec) == 0) {
    std::filesystem::remove(partial, ec);
    throw app::Error("converting " + png + " failed: needs netpbm (apt-get install netpbm)");
  }
  std::filesystem::rename(partial, out, ec);  // atomic: concurrent runs never see half a file
  return out.string();
}

std::string watch_photo_pgm() {
  if (const char* env = std::getenv("GABARIT_WATCH_PGM"); env && *env) return env;
  return debian_photo_pgm("coffee");
}

std::vector<Point> watch_shape() {
  // 600x400 photograph averaged 2x2 -> 300x200, about 2800 edge points.
  return photo_edge_points(app::read_pgm(watch_photo_pgm()), 2800, 2);
}

std::vector<Point> resolve_shape(const std::string& spec, std::size_t points, std::uint64_t seed) {
  if (spec == "random") return random_closed_curve(points, seed);
  if (spec == "curve") return thesis_curve();
  if (spec == "watch") return watch_shape();
  if (spec.rfind("photo:", 0) == 0) return photo_edge_points(app::read_pgm(spec.substr(6)), points, 1);
  return read_points_csv(spec);
}

}  // namespace gabarit::host
