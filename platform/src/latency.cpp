#include "skyloc/platform/latency.h"

#include <bit>
#include <cmath>

namespace skyloc {

std::size_t LatencyHistogram::BucketOf(std::uint64_t ns) {
  constexpr std::uint64_t kExact = 1u << kExactBits;
  if (ns < kExact)
    return static_cast<std::size_t>(ns);
  int bit = 63 - std::countl_zero(ns);  // floor(log2(ns)) >= kExactBits
  if (bit >= kMaxBit)
    return kBuckets - 1;
  const int shift = bit - (kExactBits - 1);
  const std::uint64_t sub = (ns >> shift) - static_cast<std::uint64_t>(kSubBuckets);
  // In size_t throughout: on 32-bit ARM, uint64_t + size_t would be 64-bit again.
  return static_cast<std::size_t>(kExact) +
         static_cast<std::size_t>(bit - kExactBits) * kSubBuckets + static_cast<std::size_t>(sub);
}

std::uint64_t LatencyHistogram::BucketUpperEdge(std::size_t bucket) {
  constexpr std::size_t kExact = 1u << kExactBits;
  if (bucket < kExact)
    return bucket;
  const std::size_t range = (bucket - kExact) / kSubBuckets;  // 0 = [128, 256)
  const std::size_t sub = (bucket - kExact) % kSubBuckets;
  const int shift = static_cast<int>(range) + 1;
  const std::uint64_t lower = (static_cast<std::uint64_t>(kSubBuckets) + sub) << shift;
  return lower + (std::uint64_t{1} << shift) - 1;
}

void LatencyHistogram::Record(Nanoseconds duration) {
  const std::int64_t ns = duration.count();
  const std::uint64_t v = ns < 0 ? 0 : static_cast<std::uint64_t>(ns);
  std::uint32_t& c = counts_[BucketOf(v)];
  if (c != UINT32_MAX)
    ++c;
  ++count_;
  if (v > max_)
    max_ = v;
}

void LatencyHistogram::Clear() {
  counts_.fill(0);
  count_ = 0;
  max_ = 0;
}

Nanoseconds LatencyHistogram::Percentile(double p) const {
  if (count_ == 0)
    return Nanoseconds(0);
  if (p > 100.0)
    p = 100.0;
  std::uint64_t rank =
      static_cast<std::uint64_t>(std::ceil(p / 100.0 * static_cast<double>(count_)));
  if (rank < 1)
    rank = 1;
  std::uint64_t seen = 0;
  for (std::size_t b = 0; b < kBuckets; ++b) {
    seen += counts_[b];
    if (seen >= rank) {
      const std::uint64_t edge = BucketUpperEdge(b);
      return Nanoseconds(static_cast<std::int64_t>(edge < max_ ? edge : max_));
    }
  }
  return max();
}

int LatencyTable::AddStage(const char* name) {
  if (stages_ >= kMaxStages)
    return -1;
  names_[stages_] = name;
  histograms_[stages_].Clear();
  return static_cast<int>(stages_++);
}

void LatencyTable::Clear() {
  for (std::size_t i = 0; i < stages_; ++i)
    histograms_[i].Clear();
}

void LatencyTable::Print(std::FILE* out) const {
  std::fprintf(out, "%-12s %10s %10s %10s %10s\n", "stage", "frames", "p50_us", "p99_us", "max_us");
  for (std::size_t i = 0; i < stages_; ++i) {
    const LatencyHistogram& h = histograms_[i];
    auto us = [](Nanoseconds d) { return static_cast<double>(d.count()) / 1000.0; };
    std::fprintf(out, "%-12s %10llu %10.1f %10.1f %10.1f\n", names_[i],
                 static_cast<unsigned long long>(h.count()), us(h.Percentile(50)),
                 us(h.Percentile(99)), us(h.max()));
  }
}

}  // namespace skyloc
