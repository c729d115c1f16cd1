// gabarit-vector-replay TABLE VECTORS [SESSION|PARTICLE|TABLE ...]: replays
// the cross-target test vectors (and session and particle vectors, told
// apart by their magic; a table among them is the one the particle vectors
// after it run on) on this machine (x86-64, or aarch64/armhf under
// qemu-user) and exits 0 only if every pose and vote count is bit-identical
// to the host's.
#include <cstdio>
#include <cstring>
#include <span>
#include <utility>
#include <vector>

#include "gabarit/app/test_vectors.hpp"
#include "gabarit/particle_measures.hpp"
#include "gabarit/recovery_search.hpp"
#include "gabarit/table_format.hpp"
#include "gabarit/table_view.hpp"
#include "gabarit/tracker.hpp"

namespace {

bool read_file(const char* path, std::vector<std::byte>& out) {
  std::FILE* f = std::fopen(path, "rb");
  if (f == nullptr) return false;
  std::byte chunk[65536];
  std::size_t n = 0;
  while ((n = std::fread(chunk, 1, sizeof(chunk), f)) > 0) out.insert(out.end(), chunk, chunk + n);
  const bool ok = std::ferror(f) == 0;
  std::fclose(f);
  return ok;
}

bool has_magic(const std::vector<std::byte>& bytes, const char (&magic)[8]) {
  return bytes.size() >= sizeof(magic) && std::memcmp(bytes.data(), magic, sizeof(magic)) == 0;
}

// A table in 8-byte-aligned storage (the table format's sections are aligned).
struct AlignedTable {
  std::vector<std::uint64_t> words;
  gabarit::TableView view;
  gabarit::Status open(const std::vector<std::byte>& bytes) {
    words.assign((bytes.size() + 7) / 8, 0);
    std::memcpy(words.data(), bytes.data(), bytes.size());
    return gabarit::TableView::open({reinterpret_cast<const std::byte*>(words.data()), bytes.size()}, view);
  }
};

// Replays particle vectors (particle.gbp): 0 when every estimate is the host's.
int replay_particles(const gabarit::TableView& table, const char* path, std::span<const std::byte> bytes) {
  gabarit::vectors::ParticleVectorSet set;
  if (auto s = gabarit::vectors::open_particle_vectors(bytes, set); s != gabarit::Status::kOk) {
    std::fprintf(stderr, "gabarit-vector-replay: %s: %s\n", path, gabarit::status_name(s));
    return 1;
  }
  std::vector<gabarit::Particle> cloud(gabarit::particle_scratch_particles(set.particles)), next(cloud.size());
  std::vector<std::uint32_t> order(gabarit::particle_scratch_order(set.particles));
  std::vector<std::uint64_t> bits(gabarit::edge_map_words(set.width, set.height));
  std::vector<gabarit::RoiPoint> edge_features(gabarit::edge_map_features(set.width));
  std::vector<gabarit::RoiPoint> features(gabarit::tracker_feature_capacity(table));
  std::vector<gabarit::VoteCounter> counters(gabarit::voter_counter_count(table.cell_count()));
  std::vector<std::uint8_t> mask(gabarit::tracker_mask_bytes(table));
  std::vector<std::uint16_t> magnitudes(gabarit::tracker_magnitude_entries(table));
  gabarit::TrackerScratch proposer{features, counters, mask};
  proposer.magnitudes = magnitudes;
  std::vector<gabarit::ImageView> stack_views(table.depth_count());
  std::vector<gabarit::IntensityCorrelationMeasure> measures(2);
  gabarit::vectors::Report report;
  if (auto s = gabarit::vectors::check_particle_vectors(
          table, set, {{cloud, next, order}, bits, edge_features, proposer, stack_views, measures}, report);
      s != gabarit::Status::kOk) {
    std::fprintf(stderr, "gabarit-vector-replay: %s: particle filter: %s\n", path, gabarit::status_name(s));
    return 1;
  }
  if (!report.match) {
    std::printf("FAIL: %s: particle frame %u field %s: expected 0x%llx, got 0x%llx\n", path, report.frame, report.field,
                static_cast<unsigned long long>(report.expected), static_cast<unsigned long long>(report.actual));
    return 1;
  }
  std::printf("PASS: particle tracker (%s measure), %u frames %ux%u, %u particles, seed %llu: estimates bit-identical to the host\n",
              set.intensity ? "intensity" : "edge", report.frames_checked, set.width, set.height, set.particles,
              static_cast<unsigned long long>(set.seed));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: gabarit-vector-replay TABLE.gbt VECTORS.gbv [SESSION.gbs|PARTICLE.gbp|TABLE.gbt ...]   (from `gabarit vectors`;\n"
                 "a table among the files is the one the particle vectors after it run on)\n");
    return 2;
  }
  std::vector<std::byte> table_bytes, vector_bytes;
  for (const auto& [path, bytes] : {std::pair{argv[1], &table_bytes}, std::pair{argv[2], &vector_bytes}}) {
    if (!read_file(path, *bytes)) {
      std::fprintf(stderr, "gabarit-vector-replay: cannot read %s (the release preset writes build/release/vectors)\n", path);
      return 1;
    }
  }
  // Copy into 8-byte-aligned storage: the table format's sections are aligned.
  std::vector<std::uint64_t> aligned((table_bytes.size() + 7) / 8);
  std::memcpy(aligned.data(), table_bytes.data(), table_bytes.size());
  gabarit::TableView table;
  if (auto s = gabarit::TableView::open({reinterpret_cast<const std::byte*>(aligned.data()), table_bytes.size()}, table);
      s != gabarit::Status::kOk) {
    std::fprintf(stderr, "gabarit-vector-replay: %s: %s\n", argv[1], gabarit::status_name(s));
    return 1;
  }
  gabarit::vectors::VectorSet set;
  if (auto s = gabarit::vectors::open_vectors(vector_bytes, set); s != gabarit::Status::kOk) {
    std::fprintf(stderr, "gabarit-vector-replay: %s: %s\n", argv[2], gabarit::status_name(s));
    return 1;
  }
  std::vector<gabarit::RoiPoint> features(gabarit::tracker_feature_capacity(table));
  std::vector<gabarit::VoteCounter> counters(gabarit::voter_counter_count(table.cell_count()));
  std::vector<std::uint8_t> mask(gabarit::tracker_mask_bytes(table));
  gabarit::vectors::Report report;
  if (auto s = gabarit::vectors::check_vectors(table, set, {features, counters, mask}, report); s != gabarit::Status::kOk) {
    std::fprintf(stderr, "gabarit-vector-replay: track_step: %s\n", gabarit::status_name(s));
    return 1;
  }
  if (!report.match) {
    std::printf("FAIL: frame %u field %s: expected 0x%llx, got 0x%llx\n", report.frame, report.field,
                static_cast<unsigned long long>(report.expected), static_cast<unsigned long long>(report.actual));
    return 1;
  }
  std::printf("PASS: %u frames %ux%u, poses and votes bit-identical to the host\n", report.frames_checked, set.width,
              set.height);
  // The session vectors: with or without the recovery's shared search features.
  std::vector<gabarit::RoiPoint> search_features(gabarit::search_feature_capacity(table));
  AlignedTable particle_table;  // a table given among the files: the particle vectors' after it
  const char* particle_table_path = nullptr;
  for (int i = 3; i < argc; ++i) {
    std::vector<std::byte> session_bytes;
    gabarit::vectors::SessionVectorSet session;
    if (!read_file(argv[i], session_bytes)) {
      std::fprintf(stderr, "gabarit-vector-replay: cannot read %s\n", argv[i]);
      return 1;
    }
    if (has_magic(session_bytes, gabarit::table_format::kMagic)) {
      if (auto s = particle_table.open(session_bytes); s != gabarit::Status::kOk) {
        std::fprintf(stderr, "gabarit-vector-replay: %s: %s\n", argv[i], gabarit::status_name(s));
        return 1;
      }
      particle_table_path = argv[i];
      continue;
    }
    if (has_magic(session_bytes, gabarit::vectors::kParticleMagic)) {
      const gabarit::TableView& on = particle_table_path != nullptr ? particle_table.view : table;
      if (replay_particles(on, argv[i], session_bytes) != 0) return 1;
      continue;
    }
    if (auto s = gabarit::vectors::open_session_vectors(session_bytes, session); s != gabarit::Status::kOk) {
      std::fprintf(stderr, "gabarit-vector-replay: %s: %s\n", argv[i], gabarit::status_name(s));
      return 1;
    }
    std::vector<gabarit::ImageView> stack_views(session.stack_depths);
    if (auto s = gabarit::vectors::check_session_vectors(table, session, {{features, counters, mask}, {}, search_features},
                                                         stack_views, report);
        s != gabarit::Status::kOk) {
      std::fprintf(stderr, "gabarit-vector-replay: %s: session: %s\n", argv[i], gabarit::status_name(s));
      return 1;
    }
    if (!report.match) {
      std::printf("FAIL: %s: session frame %u field %s: expected 0x%llx, got 0x%llx\n", argv[i], report.frame, report.field,
                  static_cast<unsigned long long>(report.expected), static_cast<unsigned long long>(report.actual));
      return 1;
    }
    std::printf("PASS: session%s, %u frames %ux%u with %u focus-stack images: poses, confidence and votes bit-identical to the host\n",
                session.shared_search_features ? " (recovery screened from shared features)" : "", report.frames_checked,
                session.width, session.height, unsigned{session.stack_depths});
  }
  return 0;
}
