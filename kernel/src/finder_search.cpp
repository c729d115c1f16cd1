#include "gabarit/finder_search.hpp"

#include "gabarit/deterministic_math.hpp"
#include "gabarit/refinement.hpp"

namespace gabarit {
namespace {

constexpr std::uint32_t kChannels = kOrientationChannels;
constexpr std::uint32_t kFineVotes = 4;  // track_steps per candidate, at most
constexpr std::uint32_t kScanChunk = 16;  // the peak scan's cells skipped at once (a power of two)
constexpr float kConvergeShare = 0.8f;   // of the best first verified score: the candidates converged
// ... and of min_score: converging raised no candidate's verified score by
// more than 0.083 from below 0.425 on the suite's tuning half (by 0.25 at
// most from above), and none that began below 0.425 reached min_score (0.5).
// During an occlusion every candidate is clutter scoring 0.1 to 0.45, and
// each converged took up to kFineVotes - 1 more track_steps for nothing.
constexpr float kConvergeFloor = 0.7f;

// Work units (about one counter increment each), by what each piece does.
// Measured on the scene suite (docs/detection.md): a unit costs about the
// same time whichever piece spends it, within a factor of two.
constexpr std::uint64_t kUnitsPerPixel = 1;          // block means: sequential reads
constexpr std::uint64_t kUnitsPerCoarsePixel = 24;   // the detector: Sobel and thresholds
constexpr std::uint64_t kUnitsPerChannel = 30;       // a feature's Sobel and orientation
constexpr std::uint64_t kUnitsPerIndex = 3;          // a feature placed in its channel's list
constexpr std::uint64_t kClearedCellsPerUnit = 12;   // the accumulator cleared: a memset
constexpr std::uint64_t kIncrementsPerUnit = 2;      // the coarse vote's increments, in runs
constexpr std::uint64_t kScannedCellsPerUnit = 1;    // the peak scan: mostly one compare
constexpr std::uint64_t kUnitsPerRoiPixel = 4;       // a tracking vote's feature extraction
constexpr std::uint64_t kUnitsPerVerifyPoint = 260;  // 9 Sobel gradients and their orientations
constexpr std::uint64_t kUnitsPerStackSample = 2;    // a bilinear sample and its sums
constexpr std::uint64_t kPixelsPerCopyUnit = 4;      // the first frame held: a copy

// Found candidates first, then by score, then by the coarse peak's; ties keep their order.
bool ranks_above(const FinderCandidate& a, const FinderCandidate& b) noexcept {
  if (a.found != b.found) return a.found;
  if (a.result.score != b.result.score) return a.result.score > b.result.score;
  return a.result.coarse_score > b.result.coarse_score;
}

// The rotated orientation's channel and the nearer neighbouring one.
void lists_of(const OrientedPoint& p, std::int32_t turn, bool orientation, std::uint32_t& a, std::uint32_t& b) noexcept {
  if (!orientation) {
    a = b = 0;
    return;
  }
  const std::uint32_t rotated = static_cast<std::uint32_t>(p.orientation + turn) & 255u;
  a = rotated >> 4;
  b = ((rotated & 15u) < 8u ? a + kChannels - 1 : a + 1) % kChannels;
}

bool converged(const Pose& from, const Pose& to) noexcept {
  const float dx = to.x - from.x, dy = to.y - from.y, dt = to.theta_deg - from.theta_deg;
  return dx * dx + dy * dy < 0.25f && dt < 0.3f && dt > -0.3f;
}

}  // namespace

std::uint64_t feature_extraction_work(std::uint64_t pixels) noexcept { return pixels * kUnitsPerRoiPixel; }

std::uint64_t track_features_work(const TableView& table) noexcept { return feature_extraction_work(table.roi_pixels()); }

std::uint64_t track_step_work(const TableView& table, const StepResult& step) noexcept {
  return track_features_work(table) + step.votes;
}

std::uint64_t stack_correlation_work(const FocusStack& stack, std::uint32_t correlations) noexcept {
  if (stack.images.empty() || stack.step == 0) return 0;
  return stack_sample_work(samples_per_correlation(stack) * correlations);
}

std::uint64_t stack_sample_work(std::uint64_t samples) noexcept { return samples * kUnitsPerStackSample; }

Status FinderSearch::begin(std::uint32_t width, std::uint32_t height, const FinderOptions& options, FinderScratch scratch) noexcept {
  phase_ = Phase::kIdle;
  const TableView& table = finder_.table();
  if (!valid(options) || width == 0 || height == 0 || width > 65535u * kMaxPyramidFactor || height > 65535u * kMaxPyramidFactor)
    return Status::kInvalidArgument;
  if (options.coarse_depth >= static_cast<std::int32_t>(table.depth_count())) return Status::kInvalidArgument;
  const FinderGeometry g = finder_geometry(table, finder_.detector(), options, width, height);
  const FinderScratchSizes need = finder_scratch_sizes(g, table);
  // Coarse windows are addressed in 16 bits, accumulator cells in 31.
  if (g.coarse_width > 65535u || g.coarse_height > 65535u || need.accumulator > 0x7FFFFFFFu) return Status::kInvalidArgument;
  if (scratch.coarse_image.size() < need.coarse_pixels || scratch.coarse_features.size() < need.coarse_pixels ||
      scratch.feature_index.size() < need.coarse_pixels || scratch.accumulator.size() < need.accumulator ||
      scratch.model.size() < need.model_points || scratch.rotated.size() < 2 * need.model_points ||
      scratch.candidates.size() < options.candidates)
    return Status::kBufferTooSmall;
  options_ = options;
  g_ = g;
  need_ = need;
  width_ = width;
  height_ = height;
  next_ = 0;
  peaks_ = 0;
  floor_votes_ = 0;
  const float min_distance_coarse = g.min_distance_px / static_cast<float>(g.factor);
  peak_distance2_ = static_cast<std::int64_t>(min_distance_coarse * min_distance_coarse) + 1;
  best_first_ = 0.0f;
  total_work_ = last_work_ = 0;
  frames_ = 0;
  holding_ = false;
  phase_ = Phase::kCoarseRows;
  return Status::kOk;
}

Status FinderSearch::advance(const ImageView& image, FinderScratch scratch, std::uint64_t budget) noexcept {
  last_work_ = 0;
  if (!active()) return Status::kInvalidArgument;
  if (!image.valid() || image.width != width_ || image.height != height_) {
    phase_ = Phase::kIdle;
    return Status::kInvalidArgument;
  }
  std::uint64_t spent = 0;
  const std::size_t pixels = std::size_t{width_} * height_;
  if (frames_ == 0) {
    // Spread over frames (a budget), hold the first frame if there is room.
    holding_ = budget != kUnlimitedWork && scratch.held_frame.size() >= pixels;
    if (holding_) {
      for (std::uint32_t y = 0; y < height_; ++y)
        for (std::uint32_t x = 0; x < width_; ++x) scratch.held_frame[std::size_t{y} * width_ + x] = image.at(x, y);
      spent += pixels / kPixelsPerCopyUnit;
    }
  }
  ++frames_;
  if (holding_ && scratch.held_frame.size() < pixels) {
    phase_ = Phase::kIdle;
    return Status::kBufferTooSmall;
  }
  const ImageView held{scratch.held_frame.data(), width_, height_, width_};
  const ImageView& source = holding_ ? held : image;
  do {
    const Status s = piece(source, scratch, budget - spent > 1 ? budget - spent : 1, spent);
    if (s != Status::kOk) {
      phase_ = Phase::kIdle;
      last_work_ = spent;
      return s;
    }
  } while (active() && spent < budget);
  last_work_ = spent;
  total_work_ += spent;
  return Status::kOk;
}

Status FinderSearch::piece(const ImageView& image, FinderScratch& scratch, std::uint64_t allowance, std::uint64_t& spent) noexcept {
  switch (phase_) {
    case Phase::kCoarseRows: spent += coarse_rows(image, scratch, allowance); return Status::kOk;
    case Phase::kCoarseFeatures: return coarse_features(scratch, allowance, spent);
    case Phase::kFeatureChannels: spent += feature_channels(scratch, allowance); return Status::kOk;
    case Phase::kFeatureIndex: spent += feature_index(scratch, allowance); return Status::kOk;
    case Phase::kRotationLists: spent += rotation_lists(scratch); return Status::kOk;
    case Phase::kRotationVote: spent += rotation_vote(scratch, allowance); return Status::kOk;
    case Phase::kRotationScan: spent += rotation_scan(scratch, allowance); return Status::kOk;
    case Phase::kFirstVotes: return first_vote(image, scratch, spent);
    case Phase::kConverge: return converge_vote(image, scratch, spent);
    case Phase::kIdle:
    case Phase::kDone: break;
  }
  return Status::kInvalidArgument;
}

// Step 1: the coarse frame, row by row (block means; binary: block maxima,
// so a thin outline survives).
std::uint64_t FinderSearch::coarse_rows(const ImageView& image, FinderScratch& scratch, std::uint64_t allowance) noexcept {
  const bool binary = finder_.detector().kind == table_format::DetectorKind::kBinary;
  const std::uint32_t f = g_.factor, cw = g_.coarse_width, ch = g_.coarse_height;
  const std::uint64_t row_work = std::uint64_t{f} * f * cw * kUnitsPerPixel + 1;
  std::uint64_t work = 0;
  do {
    const std::uint32_t cy = next_++;
    for (std::uint32_t cx = 0; cx < cw; ++cx) {
      const std::uint32_t x0 = cx * f, y0 = cy * f;
      const std::uint32_t x1 = x0 + f < image.width ? x0 + f : image.width;
      const std::uint32_t y1 = y0 + f < image.height ? y0 + f : image.height;
      std::uint32_t sum = 0, max = 0;
      for (std::uint32_t y = y0; y < y1; ++y)
        for (std::uint32_t x = x0; x < x1; ++x) {
          const std::uint32_t v = image.at(x, y);
          sum += v;
          max = v > max ? v : max;
        }
      const std::uint32_t area = (x1 - x0) * (y1 - y0);
      scratch.coarse_image[std::size_t{cy} * cw + cx] = static_cast<std::uint8_t>(binary ? max : (sum + area / 2) / area);
    }
    work += row_work;
  } while (next_ < ch && work + row_work <= allowance);
  if (next_ == ch) {
    phase_ = Phase::kCoarseFeatures;
    next_ = 0;
  }
  return work;
}

// Step 1, then: the coarse frame's features, row by row (the detector
// clips to the frame, not to the rows asked, so bands find what the whole
// frame does, in the same order) ...
Status FinderSearch::coarse_features(FinderScratch& scratch, std::uint64_t allowance, std::uint64_t& spent) noexcept {
  const std::uint32_t cw = g_.coarse_width, ch = g_.coarse_height;
  const ImageView coarse{scratch.coarse_image.data(), cw, ch, cw};
  const Detector& detector = finder_.detector();
  const std::uint64_t row_work = std::uint64_t{cw} * kUnitsPerCoarsePixel + 1;
  std::uint32_t rows = 1;
  while (next_ + rows < ch && (rows + 1) * row_work <= allowance) ++rows;
  if (next_ == 0) features_ = 0;
  FeatureCount fc;
  GABARIT_TRY(extract_features(coarse, {0, static_cast<std::int32_t>(next_), static_cast<std::uint16_t>(cw), static_cast<std::uint16_t>(rows)},
                               detector.kind, detector.threshold, scratch.coarse_features.subspan(features_, need_.coarse_pixels - features_),
                               fc));
  for (std::uint32_t i = 0; i < fc.written; ++i) scratch.coarse_features[features_ + i].row = static_cast<std::uint16_t>(scratch.coarse_features[features_ + i].row + next_);
  features_ += fc.written;
  next_ += rows;
  spent += rows * row_work;
  if (next_ < ch) return Status::kOk;
  for (std::uint32_t& c : channel_begin_) c = 0;
  next_ = 0;
  phase_ = Phase::kFeatureChannels;
  return Status::kOk;
}

// ... each feature's orientation channel (kept in the accumulator, which is
// larger than the coarse frame and not yet in use) and the channels' counts ...
std::uint64_t FinderSearch::feature_channels(FinderScratch& scratch, std::uint64_t allowance) noexcept {
  const ImageView coarse{scratch.coarse_image.data(), g_.coarse_width, g_.coarse_height, g_.coarse_width};
  std::uint64_t work = 0;
  do {
    if (next_ == features_) break;
    std::uint32_t c = 0;
    if (g_.orientation) {
      const RoiPoint& p = scratch.coarse_features[next_];
      const SobelGradient sg = sobel_gradient(coarse, p.col, p.row);
      c = orientation_channel(orientation_256(sg.gx, sg.gy));
    }
    scratch.accumulator[next_++] = static_cast<std::uint16_t>(c);
    ++channel_begin_[c + 1];
    work += kUnitsPerChannel;
  } while (work + kUnitsPerChannel <= allowance);
  if (next_ < features_) return work;
  for (std::uint32_t c = 0; c < kChannels; ++c) channel_begin_[c + 1] += channel_begin_[c];
  for (std::uint32_t c = 0; c < kChannels; ++c) list_begin_[c] = channel_begin_[c];  // the fill cursors, until the lists
  next_ = 0;
  phase_ = Phase::kFeatureIndex;
  return work + 1;
}

// ... and their indices in the padded accumulator, sorted by channel
// (channel_begin_[c] is channel c's first); then the coarse model.
std::uint64_t FinderSearch::feature_index(FinderScratch& scratch, std::uint64_t allowance) noexcept {
  const std::size_t astride = std::size_t{g_.coarse_width} + 2 * g_.pad;
  std::uint64_t work = 0;
  while (next_ < features_ && (work == 0 || work + kUnitsPerIndex <= allowance)) {
    const RoiPoint& p = scratch.coarse_features[next_];
    const std::uint32_t c = scratch.accumulator[next_++];
    scratch.feature_index[list_begin_[c]++] = static_cast<std::int32_t>((std::size_t{p.row} + g_.pad) * astride + p.col + g_.pad);
    work += kUnitsPerIndex;
  }
  if (next_ < features_) return work;
  model_n_ = finder_.load_model(g_.coarse_depth, g_.factor, g_.orientation, scratch.model);
  next_ = 0;
  phase_ = model_n_ == 0 ? Phase::kDone : Phase::kRotationLists;
  if (phase_ == Phase::kDone) peaks_ = 0;
  return work + model_n_ + 1;
}

// Step 2: every rotation of the coarse model voted by the coarse features of
// its channels into one accumulator, whose 3 x 3 peaks go to the shortlist.
// First the rotation's lists: per channel, each point's vote offset in one
// or two lists (its rotated orientation's channel and the nearer neighbour).
std::uint64_t FinderSearch::rotation_lists(FinderScratch& scratch) noexcept {
  rotation_ = next_;
  const float theta = options_.theta_min_deg + static_cast<float>(rotation_) * g_.theta_step_deg;
  const SinCos sc = sin_cos_deg(theta);
  const std::int32_t turn = round_to_int(wrap_degrees(theta) * (256.0f / 180.0f));
  const std::size_t astride = std::size_t{g_.coarse_width} + 2 * g_.pad;
  for (std::uint32_t& c : list_begin_) c = 0;
  for (std::uint32_t i = 0; i < model_n_; ++i) {
    std::uint32_t a, b;
    lists_of(scratch.model[i], turn, g_.orientation, a, b);
    ++list_begin_[a + 1];
    if (b != a) ++list_begin_[b + 1];
  }
  for (std::uint32_t c = 0; c < kChannels; ++c) list_begin_[c + 1] += list_begin_[c];
  std::uint32_t fill[kChannels];
  for (std::uint32_t c = 0; c < kChannels; ++c) fill[c] = list_begin_[c];
  for (std::uint32_t i = 0; i < model_n_; ++i) {
    const OrientedPoint& p = scratch.model[i];
    const float mx = static_cast<float>(p.x), my = static_cast<float>(p.y);
    const std::int32_t rx = round_to_int(sc.cos * mx - sc.sin * my);
    const std::int32_t ry = round_to_int(sc.sin * mx + sc.cos * my);
    // A feature at accumulator cell f votes for cell f - delta: the lists
    // hold -delta, the offset the vote adds.
    const auto offset = static_cast<std::int32_t>(-(ry * static_cast<std::int64_t>(astride) + rx));
    std::uint32_t a, b;
    lists_of(p, turn, g_.orientation, a, b);
    scratch.rotated[fill[a]++] = offset;
    if (b != a) scratch.rotated[fill[b]++] = offset;
  }
  for (std::size_t i = 0; i < need_.accumulator; ++i) scratch.accumulator[i] = 0;
  channel_ = 0;
  feature_ = channel_begin_[0];
  phase_ = Phase::kRotationVote;
  return std::uint64_t{model_n_} * 2 + need_.accumulator / kClearedCellsPerUnit + 1;
}

// The rotation's vote, feature by feature, as far as the allowance goes.
std::uint64_t FinderSearch::rotation_vote(FinderScratch& scratch, std::uint64_t allowance) noexcept {
  const std::uint32_t channels = g_.orientation ? kChannels : 1u;
  std::uint16_t* acc = scratch.accumulator.data();
  std::uint64_t work = 0;
  while (channel_ < channels) {
    const std::int32_t* offsets = scratch.rotated.data() + list_begin_[channel_];
    const std::uint32_t nd = list_begin_[channel_ + 1] - list_begin_[channel_];
    const std::uint32_t end = channel_begin_[channel_ + 1];
    if (nd == 0) feature_ = end;
    for (; feature_ < end; ++feature_) {
      const std::uint64_t feature_work = nd / kIncrementsPerUnit + 1;
      if (work > 0 && work + feature_work > allowance) return work;
      std::uint16_t* at = acc + scratch.feature_index[feature_];
      // Four at a time (increments commute: the counts are the same).
      std::uint32_t d = 0;
      for (; d + 4 <= nd; d += 4) {
        ++at[offsets[d]];
        ++at[offsets[d + 1]];
        ++at[offsets[d + 2]];
        ++at[offsets[d + 3]];
      }
      for (; d < nd; ++d) ++at[offsets[d]];
      work += feature_work;
    }
    ++channel_;
    if (channel_ < channels) feature_ = channel_begin_[channel_];
  }
  next_ = 0;  // the scan's first row
  phase_ = Phase::kRotationScan;
  return work + 1;
}

namespace {

// Whether any of kScanChunk counts reaches `least` (>= 1). Four 16-bit counts
// to a 64-bit word: a count v <= 0x7FFF has its lane's top bit set by
// v + (0x7FFF - (least - 1)) exactly when v >= least, without a carry out of
// the lane; a larger count sets it itself (the OR with the word), and then
// reaches any least up to 0x8000 (a carry it may send into the next lane
// only adds a true to a true). Larger leasts: one count at a time.
constexpr bool chunk_reaches(const std::uint16_t* counts, std::uint32_t least) noexcept {
  static_assert(kScanChunk % 4 == 0, "whole words");
  if (least > 0x8000u) {
    for (std::uint32_t k = 0; k < kScanChunk; ++k)
      if (counts[k] >= least) return true;
    return false;
  }
  constexpr std::uint64_t kLanes = 0x0001000100010001u, kTops = 0x8000800080008000u;
  const std::uint64_t lift = (0x7FFFu - (least - 1)) * kLanes;
  std::uint64_t tops = 0;
  for (std::uint32_t k = 0; k < kScanChunk; k += 4) {
    // Shifts rather than a copy of the bytes (constexpr; compilers merge it
    // into one load). Which lane a count takes does not matter.
    const std::uint64_t word = std::uint64_t{counts[k]} | std::uint64_t{counts[k + 1]} << 16 |
                               std::uint64_t{counts[k + 2]} << 32 | std::uint64_t{counts[k + 3]} << 48;
    tops |= (word + lift) | word;
  }
  return (tops & kTops) != 0;
}
// A chunk of zeros but one count at `at`, asked whether it reaches `least`.
constexpr bool one_count_reaches(std::uint32_t at, std::uint16_t count, std::uint32_t least) noexcept {
  std::uint16_t counts[kScanChunk] = {};
  counts[at] = count;
  return chunk_reaches(counts, least);
}
// Every lane, either side of least, and counts past 0x7FFF (whose carry
// into the next lane must not matter) and leasts past 0x8000.
static_assert(one_count_reaches(0, 5, 5) && !one_count_reaches(0, 4, 5) && one_count_reaches(7, 2, 2) && !one_count_reaches(13, 1, 2));
static_assert(one_count_reaches(3, 0x7FFF, 0x7FFF) && !one_count_reaches(3, 0x7FFE, 0x7FFF) && one_count_reaches(15, 0xFFFF, 2));
static_assert(one_count_reaches(2, 0x8000, 0x8000) && !one_count_reaches(2, 0x7FFF, 0x8000) && one_count_reaches(11, 0x8001, 0x8001));
static_assert(!one_count_reaches(11, 0x8000, 0x8001) && one_count_reaches(12, 0xFFFF, 0xFFFF) && !one_count_reaches(12, 0xFFFF, 0x10000));
static_assert(!one_count_reaches(0, 0, 2) && one_count_reaches(4, 0x9000, 3) && !one_count_reaches(9, 0x1234, 0x1235));

}  // namespace

// The peaks, row by row: local maxima whose 3 x 3 sum could enter the shortlist.
std::uint64_t FinderSearch::rotation_scan(FinderScratch& scratch, std::uint64_t allowance) noexcept {
  const std::uint32_t cw = g_.coarse_width, ch = g_.coarse_height;
  const std::size_t astride = std::size_t{cw} + 2 * g_.pad;
  const std::uint16_t* acc = scratch.accumulator.data();
  const std::uint64_t row_work = std::uint64_t{cw} / kScannedCellsPerUnit + 1;
  std::uint64_t work = 0;
  do {
    const std::uint32_t y = next_++;
    const std::uint16_t* row = acc + (std::size_t{y} + g_.pad) * astride + g_.pad;
    // No peak can enter below this: most of a row is skipped kScanChunk
    // cells at a time where none reaches it (chunk_reaches).
    const std::uint32_t least = floor_votes_ / 9 + 1 > 2 ? floor_votes_ / 9 + 1 : 2;
    for (std::uint32_t x = 0; x < cw; ++x) {
      if ((x & (kScanChunk - 1)) == 0 && x + kScanChunk <= cw && !chunk_reaches(row + x, least)) {
        x += kScanChunk - 1;
        continue;
      }
      const std::uint32_t v = row[x];
      if (v < 2 || 9 * v <= floor_votes_) continue;
      const std::uint16_t* c = row + x;
      const auto s = static_cast<std::ptrdiff_t>(astride);  // signed: the row above is at -s
      const std::uint32_t up[3] = {c[-s - 1], c[-s], c[-s + 1]};
      const std::uint32_t mid[2] = {c[-1], c[1]};
      const std::uint32_t down[3] = {c[s - 1], c[s], c[s + 1]};
      if (up[0] > v || up[1] > v || up[2] > v || mid[0] > v || mid[1] > v || down[0] > v || down[1] > v || down[2] > v) continue;
      const std::uint32_t sum = v + up[0] + up[1] + up[2] + mid[0] + mid[1] + down[0] + down[1] + down[2];
      if (sum <= floor_votes_) continue;
      offer_peak(scratch, static_cast<std::int32_t>(x), static_cast<std::int32_t>(y), sum);
    }
    work += row_work;
  } while (next_ < ch && work + row_work <= allowance);
  if (next_ < ch) return work;
  next_ = rotation_ + 1;
  phase_ = next_ < g_.rotations ? Phase::kRotationLists : Phase::kFirstVotes;
  if (phase_ == Phase::kFirstVotes) next_ = 0;
  return work;
}

// The shortlist keeps one peak per place: a peak within peak_distance2_
// (squared, coarse pixels) of a kept one replaces it if stronger, else is
// dropped; a full list drops its weakest for a stronger peak.
void FinderSearch::offer_peak(FinderScratch& scratch, std::int32_t x, std::int32_t y, std::uint32_t votes) noexcept {
  FinderCandidate* peaks = scratch.candidates.data();
  FinderCandidate p;
  p.x = x, p.y = y, p.rotation = rotation_, p.votes = votes;
  bool placed = false;
  for (std::uint32_t i = 0; i < peaks_ && !placed; ++i) {
    const std::int64_t dx = x - peaks[i].x, dy = y - peaks[i].y;
    if (dx * dx + dy * dy < peak_distance2_) {
      if (votes > peaks[i].votes) peaks[i] = p;
      placed = true;
    }
  }
  if (!placed && peaks_ < options_.candidates) {
    peaks[peaks_++] = p;
  } else if (!placed) {
    std::uint32_t w = 0;
    for (std::uint32_t i = 1; i < peaks_; ++i)
      if (peaks[i].votes < peaks[w].votes) w = i;
    if (votes > peaks[w].votes) peaks[w] = p;
  }
  if (peaks_ < options_.candidates) return;
  floor_votes_ = peaks[0].votes;
  for (std::uint32_t i = 1; i < peaks_; ++i) floor_votes_ = peaks[i].votes < floor_votes_ ? peaks[i].votes : floor_votes_;
}

// Step 3, the fine level: each peak voted with the table once and the result
// verified.
Status FinderSearch::first_vote(const ImageView& image, FinderScratch& scratch, std::uint64_t& spent) noexcept {
  if (next_ >= peaks_) {
    next_ = 0;
    votes_ = 0;
    phase_ = Phase::kConverge;
    ++spent;
    return Status::kOk;
  }
  FinderCandidate& c = scratch.candidates[next_++];
  const std::uint32_t f = g_.factor;
  const float half = static_cast<float>(f - 1) * 0.5f;
  const Pose start{static_cast<float>(c.x * static_cast<std::int32_t>(f)) + half, static_cast<float>(c.y * static_cast<std::int32_t>(f)) + half,
                   wrap_degrees(options_.theta_min_deg + static_cast<float>(c.rotation) * g_.theta_step_deg), g_.coarse_depth};
  c.result = Detection{};
  c.result.coarse_score = static_cast<float>(c.votes) / static_cast<float>(model_n_);
  c.result.score = -1.0f;  // lost at the first vote
  c.found = false;
  StepResult step;
  GABARIT_TRY(fine_vote(image, start, scratch, step, spent));
  if (step.state == TrackState::kLost) return Status::kOk;
  c.result.pose = step.pose;
  c.result.pose.theta_deg = wrap_degrees(c.result.pose.theta_deg);
  GABARIT_TRY(finder_.verify(image, c.result.pose, scratch, c.result.score));
  spent += verify_work(c.result.pose.depth);
  best_first_ = c.result.score > best_first_ ? c.result.score : best_first_;
  return Status::kOk;
}

// Then those within kConvergeShare of the best first verified score, and
// not hopelessly below min_score (kConvergeFloor), are voted again from each
// result until it stays in place (at most kFineVotes votes, as tracking
// frames would converge), refined within the cell and verified again. One
// vote per piece: a candidate spread over frames follows the target from
// frame to frame as tracking does.
Status FinderSearch::converge_vote(const ImageView& image, FinderScratch& scratch, std::uint64_t& spent) noexcept {
  if (next_ >= peaks_) {
    rank(scratch);
    phase_ = Phase::kDone;
    ++spent;
    return Status::kOk;
  }
  FinderCandidate& c = scratch.candidates[next_];
  if (votes_ == 0 && (c.result.score < 0.0f || c.result.score < kConvergeShare * best_first_ ||
                      c.result.score < kConvergeFloor * options_.min_score)) {
    // Lost at the first vote, or reported as voted once (if at all).
    if (c.result.score >= 0.0f) c.found = c.result.score >= options_.min_score;
    ++next_;
    ++spent;
    return Status::kOk;
  }
  if (votes_ == 0) {
    from_ = c.result.pose;
    GABARIT_TRY(fine_vote(image, from_, scratch, step_, spent));
    if (step_.state == TrackState::kLost) {
      c.result.score = -1.0f;
      ++next_;
      return Status::kOk;
    }
    votes_ = 2;
  } else {
    StepResult next;
    GABARIT_TRY(fine_vote(image, step_.pose, scratch, next, spent));
    if (next.state == TrackState::kLost) return finish_candidate(image, scratch, spent);
    from_ = step_.pose;
    step_ = next;
    ++votes_;
  }
  if (votes_ >= kFineVotes || converged(from_, step_.pose)) return finish_candidate(image, scratch, spent);
  return Status::kOk;
}

// The last vote's counters are still in the scratch: the sub-cell offset
// from its neighbouring cells (refinement.hpp); with a focus stack, the
// depth and angle by intensity; the verified score.
Status FinderSearch::finish_candidate(const ImageView& image, FinderScratch& scratch, std::uint64_t& spent) noexcept {
  const TableView& table = finder_.table();
  FinderCandidate& c = scratch.candidates[next_++];
  votes_ = 0;
  const SubCellOffset sub = refine_within_cell(table, scratch.fine.counters, step_.best.cell);
  Detection& d = c.result;
  d.pose = pose_of_cell(table, step_.best.cell, from_, step_.roi_centre_x, step_.roi_centre_y, sub.x, sub.y, sub.theta_deg);
  if (const FocusStack* stack = finder_.focus_stack(); stack != nullptr) {
    GABARIT_TRY(depth_by_intensity(image, d.pose, *stack, d.pose.depth));
    for (int k = 0; k < 2; ++k) GABARIT_TRY(angle_by_intensity(image, d.pose, *stack, d.pose.theta_deg));
    // The depths, then twice the angle's five samples.
    spent += stack_correlation_work(*stack, static_cast<std::uint32_t>(stack->images.size()) + 10);
  }
  d.pose.theta_deg = wrap_degrees(d.pose.theta_deg);
  d.vote_score = step_.score;
  GABARIT_TRY(finder_.verify(image, d.pose, scratch, d.score));
  spent += verify_work(d.pose.depth);
  c.found = d.score >= options_.min_score;
  return Status::kOk;
}

// track_step from `from`; the work of its extraction (the pixels it scans:
// at an angle the rotated ROI's, features.hpp) and its votes.
Status FinderSearch::fine_vote(const ImageView& image, const Pose& from, FinderScratch& scratch, StepResult& step,
                               std::uint64_t& spent) noexcept {
  const TableView& table = finder_.table();
  PreparedFrame frame;
  GABARIT_TRY(prepare_frame(table, finder_.detector(), image, from, scratch.fine, frame));
  VoteTally tally;
  GABARIT_TRY(vote_prepared(table, frame, scratch.fine, tally));
  GABARIT_TRY(finish_frame(table, from, frame, scratch.fine.counters, tally, step));
  spent += feature_extraction_work(frame.pixels_scanned) + step.votes;
  return Status::kOk;
}

std::uint64_t FinderSearch::verify_work(std::uint16_t depth) const noexcept {
  const std::uint32_t n = finder_.table().model_point_count(depth);
  return std::uint64_t{n < 512 ? n : 512} * kUnitsPerVerifyPoint;  // ModelFinder::verify checks at most 512
}

// Step 4: the candidates ranked (a stable insertion sort).
void FinderSearch::rank(FinderScratch& scratch) noexcept {
  for (std::uint32_t i = 1; i < peaks_; ++i) {
    const FinderCandidate c = scratch.candidates[i];
    std::uint32_t at = i;
    while (at > 0 && ranks_above(c, scratch.candidates[at - 1])) {
      scratch.candidates[at] = scratch.candidates[at - 1];
      --at;
    }
    scratch.candidates[at] = c;
  }
}

// Duplicates dropped (two peaks the table moved to one place).
Status FinderSearch::results(FinderScratch scratch, std::span<Detection> out, std::uint32_t& count) const noexcept {
  count = 0;
  if (!done()) return Status::kInvalidArgument;
  if (out.size() < options_.max_count) return Status::kBufferTooSmall;
  const float d2 = g_.min_distance_px * g_.min_distance_px;
  for (std::uint32_t i = 0; i < peaks_ && scratch.candidates[i].found && count < options_.max_count; ++i) {
    const Detection& d = scratch.candidates[i].result;
    bool duplicate = false;
    for (std::uint32_t j = 0; j < count && !duplicate; ++j) {
      const float dx = d.pose.x - out[j].pose.x, dy = d.pose.y - out[j].pose.y;
      duplicate = dx * dx + dy * dy < d2;
    }
    if (!duplicate) out[count++] = d;
  }
  return Status::kOk;
}

}  // namespace gabarit
