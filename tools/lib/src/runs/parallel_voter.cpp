#include "gabarit/host/runs/parallel_voter.hpp"

#include "gabarit/app/error.hpp"

namespace gabarit::host {
namespace {

// Spins this many times before yielding the core to other threads.
constexpr int kSpinsBeforeYield = 4096;

void relax(int& spins) {
  if (++spins > kSpinsBeforeYield) {
    std::this_thread::yield();
  } else {
#if defined(__x86_64__) || defined(__i386__)
    __builtin_ia32_pause();
#elif defined(__aarch64__) || defined(__arm__)
    asm volatile("yield");
#endif
  }
}

}  // namespace

ParallelVoter::ParallelVoter(unsigned threads, Split split)
    : threads_(threads == 0 ? 1 : threads), split_(split), private_(threads_), votes_(threads_, 0), status_(threads_, Status::kOk) {
  if (threads == 0 || threads > 256) throw app::Error("parallel voter: threads must be in 1..256");
  for (unsigned i = 1; i < threads_; ++i) workers_.emplace_back([this, i] { work(i); });
}

ParallelVoter::~ParallelVoter() {
  stop_.store(true, std::memory_order_release);
  for (std::thread& t : workers_) t.join();
}

void ParallelVoter::run_range(unsigned index) {
  if (split_ == Split::kFeatures) {
    // Thread i of n takes features [size * i / n, size * (i + 1) / n); thread 0
    // votes into the caller's counters, the others into their own.
    const std::size_t size = features_.size();
    const auto part = features_.subspan(size * index / threads_, size * (index + 1) / threads_ - size * index / threads_);
    std::span<VoteCounter> counters = counters_;
    if (index > 0) {
      private_[index].assign(counters_.size(), 0);
      counters = private_[index];
    }
    VoteTally tally;
    status_[index] = accumulate_votes(*table_, part, counters, tally);
    votes_[index] = tally.votes;
    return;
  }
  // Thread i of n takes cells [cells * i / n, cells * (i + 1) / n).
  const std::uint32_t cells = table_->cell_count();
  const auto begin = static_cast<std::uint32_t>(std::uint64_t{cells} * index / threads_);
  const auto end = static_cast<std::uint32_t>(std::uint64_t{cells} * (index + 1) / threads_);
  VoteTally tally;
  status_[index] = accumulate_votes_for_cells(*table_, features_, counters_, begin, end, tally);
  votes_[index] = tally.votes;
}

void ParallelVoter::work(unsigned index) {
  std::uint64_t seen = 0;
  for (;;) {
    int spins = 0;
    std::uint64_t g;
    while ((g = generation_.load(std::memory_order_acquire)) == seen) {
      if (stop_.load(std::memory_order_acquire)) return;
      relax(spins);
    }
    seen = g;
    run_range(index);
    pending_.fetch_sub(1, std::memory_order_acq_rel);
  }
}

Status ParallelVoter::accumulate(const TableView& table, std::span<const RoiPoint> features, std::span<VoteCounter> counters,
                                 VoteTally& tally) {
  table_ = &table;
  features_ = features;
  counters_ = counters;
  pending_.store(threads_ - 1, std::memory_order_relaxed);
  generation_.fetch_add(1, std::memory_order_acq_rel);
  run_range(0);
  int spins = 0;
  while (pending_.load(std::memory_order_acquire) != 0) relax(spins);
  std::uint64_t votes = 0;
  for (unsigned i = 0; i < threads_; ++i) {
    if (status_[i] != Status::kOk) return status_[i];
    votes += votes_[i];
  }
  if (split_ == Split::kFeatures) {
    for (unsigned i = 1; i < threads_; ++i) {
      const std::vector<VoteCounter>& part = private_[i];
      for (std::size_t c = 0; c < counters.size(); ++c) {
        const std::uint32_t sum = std::uint32_t{counters[c]} + part[c];
        counters[c] = static_cast<VoteCounter>(sum > kVoteCounterMax ? kVoteCounterMax : sum);
      }
    }
  }
  tally.votes += votes;
  tally.features += static_cast<std::uint32_t>(features.size());
  return Status::kOk;
}

}  // namespace gabarit::host
