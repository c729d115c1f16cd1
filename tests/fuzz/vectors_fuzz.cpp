// Fuzz target: the cross-target test-vector files (gabarit-vector-replay and
// the firmware read them): the same bytes opened as track_step vectors,
// session vectors and particle vectors. An accepted file's spans must lie
// inside the input, and its frames must be readable.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <span>

#include "gabarit/app/test_vectors.hpp"

namespace {

void require(bool condition) {
  if (!condition) std::abort();
}

// A span the reader handed out lies within the input.
void within(std::span<const std::byte> part, std::span<const std::byte> whole) {
  require(part.empty() || (part.data() >= whole.data() && part.data() + part.size() <= whole.data() + whole.size()));
}

// Every pixel of the last frame, read: out of bounds would trip ASan.
std::uint32_t touch(const gabarit::ImageView& frame) {
  std::uint32_t sum = 0;
  for (std::uint32_t y = 0; y < frame.height; ++y)
    for (std::uint32_t x = 0; x < frame.width; ++x) sum += frame.at(x, y);
  return sum;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::span<const std::byte> bytes(reinterpret_cast<const std::byte*>(data), size);
  namespace v = gabarit::vectors;
  v::VectorSet steps;
  if (v::open_vectors(bytes, steps) == gabarit::Status::kOk) {
    within(steps.frames, bytes);
    within(steps.expected, bytes);
    require(steps.expected.size() == std::size_t{steps.frame_count} * v::kRecordBytes);
    static_cast<void>(touch(steps.frame(steps.frame_count - 1)));
  }
  v::SessionVectorSet session;
  if (v::open_session_vectors(bytes, session) == gabarit::Status::kOk) {
    within(session.stack, bytes);
    within(session.frames, bytes);
    within(session.expected, bytes);
    require(session.expected.size() == std::size_t{session.frame_count} * v::kSessionRecordBytes);
    static_cast<void>(touch(session.frame(session.frame_count - 1)));
    if (session.stack_depths > 0) static_cast<void>(touch(session.stack_image(static_cast<std::uint16_t>(session.stack_depths - 1))));
  }
  v::ParticleVectorSet particles;
  if (v::open_particle_vectors(bytes, particles) == gabarit::Status::kOk) {
    within(particles.frames, bytes);
    within(particles.expected, bytes);
    require(particles.expected.size() == std::size_t{particles.frame_count} * v::kParticleRecordBytes);
    require(particles.particles >= 1 && particles.particles <= v::kMaxVectorParticles);
    require(particles.proposals <= gabarit::kMaxParticleProposals);
    static_cast<void>(touch(particles.frame(particles.frame_count - 1)));
  }
  return 0;
}
