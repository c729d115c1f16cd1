#include "gabarit/host/runs/voter_trials.hpp"

#include "gabarit/host/tables/model.hpp"
#include "gabarit/app/rng.hpp"
#include "gabarit/host/tables/state_space.hpp"
#include "gabarit/host/tables/table_builder.hpp"

namespace gabarit::host {

Shape make_shape(const std::string& name, std::vector<Point> points) {
  SynthOptions o;
  o.shape = points;
  o.max_step = kMaxStep;
  fit_image_to_shape(o);
  return {name, std::move(points), o.width, o.height};
}

std::vector<Trial> make_trials(const Shape& shape, double noise, std::size_t count, std::uint64_t seed) {
  SynthOptions o;
  o.shape = shape.points;
  o.width = shape.width;
  o.height = shape.height;
  o.noise = noise;
  app::Rng rng(seed);
  std::vector<Trial> trials;
  trials.reserve(count);
  for (std::size_t i = 0; i < count; ++i) {
    Trial t;
    // fit_image_to_shape leaves >= 16 px of room: previous within +-8 of the
    // centre plus a step of +-4 keeps the shape and the +-5 window inside.
    t.previous = {static_cast<std::int32_t>(shape.width / 2) + rng.uniform_int(-8, 8),
                  static_cast<std::int32_t>(shape.height / 2) + rng.uniform_int(-8, 8)};
    t.truth = {t.previous.x + rng.uniform_int(-kMaxStep, kMaxStep), t.previous.y + rng.uniform_int(-kMaxStep, kMaxStep)};
    t.frame = render_frame(o, t.truth.x, t.truth.y, rng.next_u64());
    trials.push_back(std::move(t));
  }
  return trials;
}

std::vector<std::byte> shape_table(const Shape& shape, double keep, std::uint64_t seed, const DecimationPolicy& policy) {
  ModelStack model;
  model.depths.push_back(shape.points);
  model.detector.kind = table_format::DetectorKind::kBinary;
  BuildOptions o;
  o.space.x = parse_axis(kCellAxis, "x");
  o.space.y = parse_axis(kCellAxis, "y");
  o.space.theta = parse_axis("0:0:1", "theta");
  o.keep = keep;
  o.seed = seed;
  o.decimation = policy;
  return build_table(model, o);
}

}  // namespace gabarit::host
