// Per-stage latency accounting for the frame loop: fixed-size histograms kept as members,
// so recording a sample is a few integer operations (no allocation, no logging); the
// table is printed at exit and on SIGUSR1.
//
// Buckets are log-linear (as HdrHistogram): values below 128 ns are exact; above, each
// power-of-two range is split into 64 buckets, so a reported percentile is at most 1/64
// (1.6 %) above the true sample. Percentiles use the nearest-rank definition: the
// smallest recorded value v with at least ceil(p/100 * n) samples <= v, reported as the
// upper edge of v's bucket (never above the exact maximum).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdio>

#include "skyloc/platform/clock.h"

namespace skyloc {

class LatencyHistogram {
 public:
  static constexpr int kExactBits = 7;                       // 0..127 ns exact
  static constexpr int kSubBuckets = 1 << (kExactBits - 1);  // per power of two above
  static constexpr int kMaxBit = 42;                         // ~73 minutes; larger values clamp
  static constexpr std::size_t kBuckets =
      (1u << kExactBits) + static_cast<std::size_t>(kMaxBit - kExactBits) * kSubBuckets;

  void Record(Nanoseconds duration);
  void Clear();

  std::uint64_t count() const { return count_; }
  Nanoseconds max() const { return Nanoseconds(static_cast<std::int64_t>(max_)); }
  // p in (0, 100]. 0 when empty.
  Nanoseconds Percentile(double p) const;

  // Bucket arithmetic, public for tests.
  static std::size_t BucketOf(std::uint64_t ns);
  static std::uint64_t BucketUpperEdge(std::size_t bucket);

 private:
  std::array<std::uint32_t, kBuckets> counts_{};
  std::uint64_t count_ = 0;
  std::uint64_t max_ = 0;
};

// A fixed set of named stages, each with a histogram.
class LatencyTable {
 public:
  static constexpr std::size_t kMaxStages = 12;

  // Adds a stage at start-up; returns its id, or -1 when the table is full.
  int AddStage(const char* name);
  void Record(int stage, Nanoseconds duration) {
    if (stage >= 0 && static_cast<std::size_t>(stage) < stages_)
      histograms_[static_cast<std::size_t>(stage)].Record(duration);
  }
  const LatencyHistogram& stage(int id) const { return histograms_[static_cast<std::size_t>(id)]; }
  const char* name(int id) const { return names_[static_cast<std::size_t>(id)]; }
  std::size_t stages() const { return stages_; }
  void Clear();

  // "stage  frames  p50_us  p99_us  max_us", one line per stage.
  void Print(std::FILE* out) const;

 private:
  std::array<LatencyHistogram, kMaxStages> histograms_{};
  std::array<const char*, kMaxStages> names_{};
  std::size_t stages_ = 0;
};

// Records the time from construction to destruction (or Stop()) into one stage.
class StageTimer {
 public:
  StageTimer(LatencyTable& table, int stage, const Clock& clock)
      : table_(table), stage_(stage), clock_(clock), start_(clock.Now()) {}
  ~StageTimer() { Stop(); }
  StageTimer(const StageTimer&) = delete;
  StageTimer& operator=(const StageTimer&) = delete;
  void Stop() {
    if (stage_ >= 0)
      table_.Record(stage_, clock_.Now() - start_);
    stage_ = -1;
  }

 private:
  LatencyTable& table_;
  int stage_;
  const Clock& clock_;
  Nanoseconds start_;
};

}  // namespace skyloc
