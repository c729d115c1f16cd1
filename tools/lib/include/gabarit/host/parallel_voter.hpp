// Voting on several cores (Linux): the cells are split into one contiguous
// range per thread, each thread runs accumulate_votes_for_cells on its range
// of the shared counter array, so no two threads write the same counter and
// the counters are exactly those of the single-threaded reference voter
// (tested bit for bit).
//
// A frame's vote takes tens of microseconds, about what waking a sleeping
// thread costs, so the workers spin on an atomic job counter instead of
// sleeping (yielding after a while): a tracking application gives the voter
// its cores. The caller's thread takes the first range itself.
#pragma once

#include <atomic>
#include <cstdint>
#include <span>
#include <thread>
#include <vector>

#include "gabarit/voter.hpp"

namespace gabarit::host {

class ParallelVoter {
 public:
  // threads >= 1; with 1 the caller's thread does all the work.
  explicit ParallelVoter(unsigned threads);
  ~ParallelVoter();
  ParallelVoter(const ParallelVoter&) = delete;
  ParallelVoter& operator=(const ParallelVoter&) = delete;

  unsigned threads() const { return threads_; }

  // As accumulate_votes (counters must be cleared by the caller).
  Status accumulate(const TableView& table, std::span<const RoiPoint> features, std::span<VoteCounter> counters,
                    VoteTally& tally);

 private:
  void work(unsigned index);
  void run_range(unsigned index);
  unsigned threads_;
  // The job, written before generation_ is bumped (release) and read after
  // it is seen (acquire).
  const TableView* table_ = nullptr;
  std::span<const RoiPoint> features_;
  std::span<VoteCounter> counters_;
  std::atomic<std::uint64_t> generation_{0};
  std::atomic<unsigned> pending_{0};
  std::atomic<bool> stop_{false};
  std::vector<std::uint64_t> votes_;  // per thread
  std::vector<Status> status_;
  std::vector<std::thread> workers_;
};

}  // namespace gabarit::host
