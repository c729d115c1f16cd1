// Voting on several cores (Linux), two ways, both exactly the counters of the
// single-threaded reference voter (tested bit for bit):
//   kCells     the cells are split into one contiguous range per thread; each
//              thread runs accumulate_votes_for_cells on its range of the
//              shared counters (no two threads write the same counter). Each
//              thread still reads every feature's list up to its range (a
//              binary search per list), so with lists of ~100 references the
//              saved work does not pay for the search (0.8-1.0x on 2 cores,
//              docs/tracking.md).
//   kFeatures  the features are split; each thread votes into its own
//              counters, then the caller adds them with the same saturation
//              (min(a + b, 65535) is the saturated total, since each part is
//              at most its own true count).
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
  enum class Split { kCells, kFeatures };
  // threads >= 1; with 1 the caller's thread does all the work.
  explicit ParallelVoter(unsigned threads, Split split = Split::kFeatures);
  ~ParallelVoter();
  ParallelVoter(const ParallelVoter&) = delete;
  ParallelVoter& operator=(const ParallelVoter&) = delete;

  unsigned threads() const { return threads_; }

  // As accumulate_votes (counters must be cleared by the caller), except that
  // after an error the counters are unspecified.
  Status accumulate(const TableView& table, std::span<const RoiPoint> features, std::span<VoteCounter> counters,
                    VoteTally& tally);

 private:
  void work(unsigned index);
  void run_range(unsigned index);
  unsigned threads_;
  Split split_;
  std::vector<std::vector<VoteCounter>> private_;  // kFeatures: counters of threads 1..n-1
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
