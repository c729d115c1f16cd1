#include "gabarit/host/scenes/test_vector_scene.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include "gabarit/app/error.hpp"
#include "gabarit/app/image_io.hpp"
#include "gabarit/app/particle_run.hpp"
#include "gabarit/app/files.hpp"
#include "gabarit/app/scratch.hpp"
#include "gabarit/app/test_vectors.hpp"
#include "gabarit/byte_order.hpp"
#include "gabarit/crc32.hpp"
#include "gabarit/deterministic_math.hpp"
#include "gabarit/app/rng.hpp"
#include "gabarit/host/scenes/synth.hpp"
#include "gabarit/host/tables/table_budget.hpp"
#include "gabarit/host/tables/table_builder.hpp"
#include "gabarit/recovery_search.hpp"
#include "gabarit/tracking_session.hpp"

namespace gabarit::host {
namespace {

// The files' common trailer: a CRC-32 of every byte before it.
void seal(std::vector<std::byte>& file) {
  const std::size_t body = file.size() - vectors::kTrailerBytes;
  store_le<std::uint32_t>(file.data() + body, crc32(std::span<const std::byte>(file.data(), body)));
}

// Three nested closed curves (about half, a third and a sixth of the points)
// around the reference point: a compact ~1000-point object, radius ~45 px.
std::vector<Point> nested_curves(std::uint32_t points, std::uint64_t seed) {
  std::set<Point> all;
  const double shares[3] = {0.5, 0.33, 0.17};
  for (int i = 0; i < 3; ++i) {
    const auto n = std::max<std::size_t>(8, static_cast<std::size_t>(points * shares[i]));
    for (const Point& p : random_closed_curve(n, seed * 7 + static_cast<std::uint64_t>(i))) all.insert(p);
  }
  return {all.begin(), all.end()};
}

// Depth n of the focus stack: the model scaled by 1 + 0.04 n, so no two
// depths have the same features.
std::vector<Point> at_depth(const std::vector<Point>& base, std::uint16_t n) {
  const float s = 1.0f + 0.04f * static_cast<float>(n);
  std::set<Point> out;
  for (const Point& p : base) out.insert({round_to_int(s * static_cast<float>(p.x)), round_to_int(s * static_cast<float>(p.y))});
  return {out.begin(), out.end()};
}

// The model of one depth drawn at a pose into a binary image, with
// salt-and-pepper noise; hidden: noise only.
app::GrayImage render(const std::vector<Point>& model, std::uint32_t side, float x, float y, float theta, bool hidden,
                      double noise, app::Rng& rng) {
  app::GrayImage image(side, side, 0);
  const SinCos sc = sin_cos_deg(theta);
  for (const Point& m : model) {
    if (hidden) break;
    const std::int32_t px = round_to_int(x + sc.cos * static_cast<float>(m.x) - sc.sin * static_cast<float>(m.y));
    const std::int32_t py = round_to_int(y + sc.sin * static_cast<float>(m.x) + sc.cos * static_cast<float>(m.y));
    if (px >= 0 && py >= 0 && px < static_cast<std::int32_t>(side) && py < static_cast<std::int32_t>(side))
      image.at(static_cast<std::uint32_t>(px), static_cast<std::uint32_t>(py)) = 255;
  }
  for (auto& v : image.pixels)
    if (rng.bernoulli(noise)) v = static_cast<std::uint8_t>(255 - v);
  return image;
}

// One random step of the trajectory: integer steps within the table's cell
// centres' reach, angle steps of whole degrees, depth walking by one.
void walk(app::Rng& rng, float& x, float& y, float& theta, std::int32_t& depth, std::uint16_t depths) {
  x += static_cast<float>(rng.uniform_int(-5, 5));
  y += static_cast<float>(rng.uniform_int(-5, 5));
  theta += static_cast<float>(rng.uniform_int(-2, 2));
  depth = std::clamp(depth + rng.uniform_int(-1, 1), 0, static_cast<std::int32_t>(depths) - 1);
}

}  // namespace

namespace {

// vectors.gbv: the frames of a random walk (from set.init) and the host's
// closed-loop track_step record of each, as every target will replay them.
std::vector<std::byte> step_vectors(const VectorSceneOptions& o, const ModelStack& model, const TableView& table,
                                    const vectors::VectorSet& set, app::Rng& rng, app::TrackerBuffers& buffers,
                                    VectorSceneSummary& summary) {
  const std::uint32_t side = set.width;
  float x = set.init.x, y = set.init.y, theta = set.init.theta_deg;
  std::int32_t depth = set.init.depth;
  std::vector<std::byte> file(vectors::file_bytes(o.frames, side, side));
  std::vector<float> true_x, true_y, true_theta;
  std::vector<std::int32_t> true_depth;
  for (std::uint32_t f = 0; f < o.frames; ++f) {
    walk(rng, x, y, theta, depth, o.depths);
    const app::GrayImage image = render(model.depths[static_cast<std::size_t>(depth)], side, x, y, theta, false, o.noise, rng);
    std::copy_n(reinterpret_cast<const std::byte*>(image.pixels.data()), image.pixels.size(),
                file.begin() + static_cast<std::ptrdiff_t>(vectors::kHeaderBytes + std::size_t{f} * side * side));
    true_x.push_back(x);
    true_y.push_back(y);
    true_theta.push_back(theta);
    true_depth.push_back(depth);
  }

  // The host's results, closed loop, as every target will replay them.
  Pose pose = set.init;
  const std::size_t records_at = vectors::kHeaderBytes + std::size_t{o.frames} * side * side;
  for (std::uint32_t f = 0; f < o.frames; ++f) {
    const ImageView view{reinterpret_cast<const std::uint8_t*>(file.data()) + vectors::kHeaderBytes + std::size_t{f} * side * side,
                         side, side, side};
    StepResult step;
    if (const Status s = track_step(table, set.detector, view, pose, buffers.scratch(), step); s != Status::kOk)
      throw app::Error(std::string("vectors: track_step failed: ") + status_name(s));
    vectors::encode_record(step, std::span<std::byte, vectors::kRecordBytes>(file.data() + records_at + std::size_t{f} * vectors::kRecordBytes,
                                                                             vectors::kRecordBytes));
    if (std::abs(step.pose.x - true_x[f]) <= 1.5f && std::abs(step.pose.y - true_y[f]) <= 1.5f &&
        std::abs(step.pose.theta_deg - true_theta[f]) <= 1.5f && step.pose.depth == true_depth[f])
      ++summary.frames_on_truth;
    pose = step.pose;
  }
  vectors::encode_header(set, std::span<std::byte, vectors::kHeaderBytes>(file.data(), vectors::kHeaderBytes));
  seal(file);

  return file;
}

// session.gbs (each recovery placement a full track_step) and, in
// `screened_file`, session-screened.gbs (placements screened from shared
// search features): the session's sequence, its focus stack (each depth's
// model drawn centred in an image of its own) and the host's results.
std::vector<std::byte> session_vectors(const VectorSceneOptions& o, const ModelStack& model, const TableView& table,
                                       const vectors::VectorSet& set, std::int32_t extent, app::Rng& rng,
                                       app::TrackerBuffers& buffers, VectorSceneSummary& summary,
                                       std::vector<std::byte>& screened_file) {
  const std::uint32_t side = set.width;
  float x = 0, y = 0, theta = 0;
  std::int32_t depth = 0;
  // The session's sequence and focus stack: each depth's model drawn
  // centred in an image of its own (the reference point at the centre).
  if (o.session_frames < 1 || o.session_frames > 1000) throw app::Error("vectors: session frames must be in 1..1000");
  vectors::SessionVectorSet session;
  session.frame_count = o.session_frames;
  session.width = session.height = side;
  session.detector = set.detector;
  session.init = set.init;
  session.options = SessionOptions{};
  session.stack_depths = o.depths;
  const auto stack_side = static_cast<std::uint32_t>(2 * extent + 1);
  session.stack_width = session.stack_height = stack_side;
  session.stack_ref_x = session.stack_ref_y = static_cast<float>(extent);
  session.stack_step = 2;
  std::vector<std::byte> session_file(vectors::session_file_bytes(session.frame_count, side, side, session.stack_depths,
                                                                  stack_side, stack_side));
  const std::size_t stack_at = vectors::kSessionHeaderBytes;
  const std::size_t frames_at = stack_at + std::size_t{session.stack_depths} * stack_side * stack_side;
  const std::size_t session_records_at = frames_at + std::size_t{session.frame_count} * side * side;
  std::vector<app::GrayImage> stack_images;
  for (std::uint16_t d = 0; d < session.stack_depths; ++d) {
    app::Rng quiet(0);
    stack_images.push_back(render(model.depths[d], stack_side, static_cast<float>(extent), static_cast<float>(extent), 0.0f,
                                  false, 0.0, quiet));
    std::copy_n(reinterpret_cast<const std::byte*>(stack_images.back().pixels.data()), stack_images.back().pixels.size(),
                session_file.begin() + static_cast<std::ptrdiff_t>(stack_at + std::size_t{d} * stack_side * stack_side));
  }
  x = static_cast<float>(side / 2), y = static_cast<float>(side / 2), theta = 0;
  depth = static_cast<std::int32_t>(o.depths / 2);
  for (std::uint32_t f = 0; f < session.frame_count; ++f) {
    walk(rng, x, y, theta, depth, o.depths);
    const bool hidden = f >= o.hidden_from && f < o.hidden_from + o.hidden_frames;
    const app::GrayImage image = render(model.depths[static_cast<std::size_t>(depth)], side, x, y, theta, hidden, o.noise, rng);
    std::copy_n(reinterpret_cast<const std::byte*>(image.pixels.data()), image.pixels.size(),
                session_file.begin() + static_cast<std::ptrdiff_t>(frames_at + std::size_t{f} * side * side));
  }
  // The host's session results, recorded twice: each recovery placement a
  // full track_step (session.gbs), and screened from shared search features
  // (session-screened.gbs). Same frames, same stack.
  std::vector<ImageView> views;
  for (const app::GrayImage& image : stack_images) views.push_back(image.view());
  const FocusStack stack{views, session.stack_ref_x, session.stack_ref_y, session.stack_step};
  std::vector<RoiPoint> search_features(search_feature_capacity(table));
  const auto record = [&](bool shared) {
    session.shared_search_features = shared;
    std::vector<std::byte> out = session_file;
    TrackingSession tracker(table, nullptr, session.detector);
    if (const Status s = tracker.start(session.options, session.init); s != Status::kOk)
      throw app::Error(std::string("vectors: session start failed: ") + status_name(s));
    tracker.use_focus_stack(&stack);
    const SessionScratch scratch{buffers.scratch(), {}, shared ? std::span<RoiPoint>(search_features) : std::span<RoiPoint>()};
    summary.session_lost_frames = 0;
    summary.session_reacquired = false;
    for (std::uint32_t f = 0; f < session.frame_count; ++f) {
      const ImageView view{reinterpret_cast<const std::uint8_t*>(out.data()) + frames_at + std::size_t{f} * side * side, side,
                           side, side};
      SessionResult result;
      if (const Status s = tracker.step(view, scratch, result); s != Status::kOk)
        throw app::Error(std::string("vectors: session step failed: ") + status_name(s));
      vectors::encode_session_record(result, std::span<std::byte, vectors::kSessionRecordBytes>(
                                                 out.data() + session_records_at + std::size_t{f} * vectors::kSessionRecordBytes,
                                                 vectors::kSessionRecordBytes));
      summary.session_lost_frames += result.state == TrackState::kLost;
      summary.session_reacquired = summary.session_reacquired || result.reacquired;
    }
    vectors::encode_session_header(session, std::span<std::byte, vectors::kSessionHeaderBytes>(out.data(), vectors::kSessionHeaderBytes));
    seal(out);
    return out;
  };
  screened_file = record(true);
  return record(false);  // its summary is the one reported

}

// particle.gbp: the session's sequence (frames and initial pose from its
// file) through the particle tracker as gabarit track --tracker particle
// runs it on this table (app::ParticleTracker, the CLI's defaults but for
// the particle count: the edge measure on a table without model images, the
// intensity measure on one with them), and every frame's estimate.
std::vector<std::byte> particle_vectors(const VectorSceneOptions& o, const TableView& table,
                                        const std::vector<std::byte>& session_file, std::uint32_t& frames_tracking) {
  vectors::SessionVectorSet session;
  if (const Status s = vectors::open_session_vectors(session_file, session); s != Status::kOk)
    throw app::Error(std::string("vectors: session file invalid: ") + status_name(s));
  app::ParticleRunOptions run;
  run.particles = o.particles;
  run.seed = o.seed;
  // The firmware has no room for the finder (docs/particle-filter.md,
  // "Re-acquisition by detection"): its profile runs without it.
  run.detection = false;
  const app::ParticleMeasureKind measure = app::resolved_measure(run.measure, table);
  if (measure != app::ParticleMeasureKind::kEdges && measure != app::ParticleMeasureKind::kIntensity)
    throw app::Error("vectors: the particle vectors record the edge or the intensity measure");
  vectors::ParticleVectorSet set;
  set.frame_count = session.frame_count;
  set.width = session.width;
  set.height = session.height;
  set.detector = detector_of(table);
  set.init = session.init;
  set.particles = run.particles;
  set.seed = run.seed;
  set.proposals = run.proposals;
  set.edge_stride = run.edge_stride;
  set.edge_tolerance = run.edge_tolerance;
  set.finer = run.finer;
  set.intensity = measure == app::ParticleMeasureKind::kIntensity;
  set.intensity_samples = set.intensity ? run.intensity_samples : 0;
  std::vector<std::byte> file(vectors::particle_file_bytes(set.frame_count, set.width, set.height));
  std::copy(session.frames.begin(), session.frames.end(), file.begin() + static_cast<std::ptrdiff_t>(vectors::kParticleHeaderBytes));
  app::ParticleTracker tracker(table, set.width, set.height, run);
  tracker.start(set.init);
  const std::size_t records_at = vectors::kParticleHeaderBytes + session.frames.size();
  frames_tracking = 0;
  app::GrayImage frame(set.width, set.height, 0);
  for (std::uint32_t f = 0; f < set.frame_count; ++f) {
    const ImageView view = session.frame(f);
    std::copy_n(view.pixels, frame.pixels.size(), frame.pixels.begin());
    const ParticleEstimate e = tracker.step(frame);
    vectors::encode_particle_record(e, std::span<std::byte, vectors::kParticleRecordBytes>(
                                           file.data() + records_at + std::size_t{f} * vectors::kParticleRecordBytes,
                                           vectors::kParticleRecordBytes));
    frames_tracking += e.state == TrackState::kTracking;
  }
  vectors::encode_particle_header(set, std::span<std::byte, vectors::kParticleHeaderBytes>(file.data(), vectors::kParticleHeaderBytes));
  seal(file);
  return file;
}

// particle-table.gbt: the intensity measure needs a table with model
// images: the same model with its focus stack's images (each depth drawn
// centred, as the session's stack), to a smaller budget so that a firmware
// image holds it beside its vectors.
std::vector<std::byte> table_with_images(const VectorSceneOptions& o, const ModelStack& model, const BuildOptions& build,
                                         std::int32_t extent) {
  ModelStack with_images = model;
  const auto stack_side = static_cast<std::uint16_t>(2 * extent + 1);
  with_images.ref_x = with_images.ref_y = static_cast<float>(extent);
  with_images.image_width = with_images.image_height = stack_side;
  for (std::uint16_t d = 0; d < o.depths; ++d) {
    app::Rng quiet(0);
    with_images.images.push_back(render(model.depths[d], stack_side, static_cast<float>(extent), static_cast<float>(extent), 0.0f,
                                        false, 0.0, quiet).pixels);
  }
  if (o.keep > 0) return build_table(with_images, build);
  Budget budget;
  budget.max_bytes = o.particle_table_budget_bytes;
  BudgetReport report;
  return build_table_to_budget(with_images, build, budget, report);
}

}  // namespace

VectorSceneSummary write_test_vectors(const VectorSceneOptions& o, const std::string& dir) {
  if (o.model_points < 100 || o.model_points > 5000) throw app::Error("vectors: model points must be in 100..5000");
  if (o.depths < 1 || o.depths > 16) throw app::Error("vectors: depths must be in 1..16");
  if (o.frames < 1 || o.frames > 1000) throw app::Error("vectors: frames must be in 1..1000");
  if (!(o.keep >= 0 && o.keep <= 1)) throw app::Error("vectors: keep must be in (0, 1]");
  if (o.keep == 0 && o.table_budget_bytes == 0) throw app::Error("vectors: give a table budget or a keep ratio");
  if (!(o.noise >= 0 && o.noise <= 1)) throw app::Error("vectors: noise must be in [0, 1]");
  if (o.particles < 1 || o.particles > vectors::kMaxVectorParticles)
    throw app::Error("vectors: particles must be in 1.." + std::to_string(vectors::kMaxVectorParticles));

  ModelStack model;
  const std::vector<Point> base = nested_curves(o.model_points, o.seed);
  for (std::uint16_t n = 0; n < o.depths; ++n) model.depths.push_back(at_depth(base, n));
  model.detector.kind = table_format::DetectorKind::kBinary;

  // +-7 px in 2-px cells, +-3 deg in 2-deg cells, every depth: per frame the
  // object may move anywhere in that window.
  BuildOptions build;
  build.space.x = {-6.0f, 6.0f, 7};
  build.space.y = {-6.0f, 6.0f, 7};
  build.space.theta = {-2.0f, 2.0f, 3};
  build.keep = o.keep;
  build.seed = o.seed;
  BudgetReport budget_report;
  std::vector<std::byte> table_bytes;
  if (o.keep > 0) {
    table_bytes = build_table(model, build);
    budget_report.keep = o.keep;
  } else {
    Budget budget;
    budget.max_bytes = o.table_budget_bytes;
    table_bytes = build_table_to_budget(model, build, budget, budget_report);
  }
  TableView table;
  if (const Status s = TableView::open(table_bytes, table); s != Status::kOk) throw app::Error(std::string("vectors: built table invalid: ") + status_name(s));

  std::int32_t extent = 0;
  for (const auto& depth : model.depths)
    for (const Point& p : depth) extent = std::max({extent, std::abs(p.x), std::abs(p.y)});
  const std::uint32_t side = static_cast<std::uint32_t>(2 * (extent + 24) + 1);

  // The true trajectory: integer steps within the table's cell centres'
  // reach, angle steps of whole degrees, depth walking by one.
  app::Rng rng(o.seed ^ 0x7EC7025ull);
  float x = static_cast<float>(side / 2), y = static_cast<float>(side / 2), theta = 0;
  std::int32_t depth = static_cast<std::int32_t>(o.depths / 2);
  VectorSceneSummary summary;
  app::TrackerBuffers buffers(table, app::VoterChoice::kCsr);
  vectors::VectorSet set;
  set.frame_count = o.frames;
  set.width = side;
  set.height = side;
  set.detector = {table_format::DetectorKind::kBinary, 0};
  set.init = {x, y, theta, static_cast<std::uint16_t>(depth)};

  std::vector<std::byte> file = step_vectors(o, model, table, set, rng, buffers, summary);
  std::vector<std::byte> screened_file;
  std::vector<std::byte> session_file = session_vectors(o, model, table, set, extent, rng, buffers, summary, screened_file);
  const std::vector<std::byte> particle_file = particle_vectors(o, table, session_file, summary.particle_frames_tracking);
  const std::vector<std::byte> image_table_bytes = table_with_images(o, model, build, extent);
  TableView image_table;
  if (const Status s = TableView::open(image_table_bytes, image_table); s != Status::kOk)
    throw app::Error(std::string("vectors: built image table invalid: ") + status_name(s));
  const std::vector<std::byte> intensity_file =
      particle_vectors(o, image_table, session_file, summary.particle_intensity_frames_tracking);

  std::filesystem::create_directories(dir);
  app::write_file((std::filesystem::path(dir) / "table.gbt").string(), table_bytes);
  app::write_file((std::filesystem::path(dir) / "vectors.gbv").string(), file);
  app::write_file((std::filesystem::path(dir) / "session.gbs").string(), session_file);
  app::write_file((std::filesystem::path(dir) / "session-screened.gbs").string(), screened_file);
  app::write_file((std::filesystem::path(dir) / "particle.gbp").string(), particle_file);
  app::write_file((std::filesystem::path(dir) / "particle-table.gbt").string(), image_table_bytes);
  app::write_file((std::filesystem::path(dir) / "particle-intensity.gbp").string(), intensity_file);
  summary.particle_table_bytes = image_table_bytes.size();
  summary.particle_bytes = particle_file.size();
  summary.session_bytes = session_file.size();
  summary.model_points = model.depths[0].size();
  summary.table_bytes = table_bytes.size();
  summary.keep = budget_report.keep;
  summary.margin = o.keep > 0 ? 0 : budget_report.margin;
  summary.vector_bytes = file.size();
  summary.cells = table.cell_count();
  summary.width = summary.height = side;
  return summary;
}

}  // namespace gabarit::host
