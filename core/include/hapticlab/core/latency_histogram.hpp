#pragma once
/// @file Fixed-bin latency histograms for the real-time loops (wake-up lateness, tick
/// duration). One writer (the loop's thread) records with relaxed atomic stores into bins
/// allocated at construction: Add allocates nothing, locks nothing. Any thread may read a
/// Snapshot concurrently (counts may be a tick apart between bins; good enough for
/// statistics).
///
/// Bins: 0.5 us wide from 0 to 5 ms (10000 bins) and one overflow bin; the exact maximum is
/// kept separately. A percentile is the upper edge of the bin where the cumulative count
/// reaches it (a conservative value: never below the true percentile, at most 0.5 us above,
/// except in the overflow bin, where it is the maximum).

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace hapticlab {

/// A plain copy of a histogram: counts per bin, merged and queried off the real-time path.
struct LatencySummary {
  static constexpr double kBinWidthS = 0.5e-6;
  static constexpr std::size_t kBins = 10000;  ///< regular bins; index kBins is the overflow
  std::vector<std::uint64_t> counts = std::vector<std::uint64_t>(kBins + 1, 0);
  std::uint64_t total = 0;
  double max_s = 0;

  /// The value [s] at or below which a fraction q (0..1) of the recorded values lie.
  double Quantile(double q) const {
    if (total == 0) return 0;
    const auto need =
        static_cast<std::uint64_t>(std::ceil(std::clamp(q, 0.0, 1.0) * static_cast<double>(total)));
    std::uint64_t cum = 0;
    for (std::size_t i = 0; i < kBins; ++i) {
      cum += counts[i];
      if (cum >= std::max<std::uint64_t>(need, 1))
        return std::min(max_s, static_cast<double>(i + 1) * kBinWidthS);
    }
    return max_s;
  }
  void Merge(const LatencySummary& o) {
    for (std::size_t i = 0; i <= kBins; ++i) counts[i] += o.counts[i];
    total += o.total;
    max_s = std::max(max_s, o.max_s);
  }
  /// A coarser text histogram: counts per row of `per_row` bins for the first `rows` rows, up
  /// to the last non-empty one, and in `*beyond` every count after them, the overflow bin's
  /// included. Each count is in exactly one place (they add up to `total`).
  std::vector<std::uint64_t> Rows(std::size_t per_row, std::size_t rows,
                                  std::uint64_t* beyond) const {
    std::vector<std::uint64_t> out;
    *beyond = 0;
    if (per_row == 0) return out;
    for (std::size_t i = 0; i <= kBins; ++i) {
      if (counts[i] == 0) continue;
      const std::size_t row = i / per_row;
      if (i == kBins || row >= rows) {
        *beyond += counts[i];
        continue;
      }
      if (out.size() <= row) out.resize(row + 1, 0);
      out[row] += counts[i];
    }
    return out;
  }
  /// Sparse text form for storage: "bin:count bin:count ..." (non-empty bins only).
  std::string Sparse() const {
    std::string s;
    for (std::size_t i = 0; i <= kBins; ++i)
      if (counts[i])
        s += (s.empty() ? "" : " ") + std::to_string(i) + ":" + std::to_string(counts[i]);
    return s;
  }
  /// Parses Sparse(); returns false on malformed text.
  bool ParseSparse(const std::string& s, double max_value_s) {
    counts.assign(kBins + 1, 0);
    total = 0;
    max_s = max_value_s;
    std::size_t pos = 0;
    while (pos < s.size()) {
      std::size_t colon = s.find(':', pos), end = s.find(' ', pos);
      if (end == std::string::npos) end = s.size();
      if (colon == std::string::npos || colon > end) return false;
      try {
        const auto bin = std::stoull(s.substr(pos, colon - pos));
        const auto n = std::stoull(s.substr(colon + 1, end - colon - 1));
        if (bin > kBins) return false;
        counts[bin] += n;
        total += n;
      } catch (...) {
        return false;
      }
      pos = end + 1;
    }
    return true;
  }
};

class LatencyHistogram {
 public:
  LatencyHistogram()
      : bins_(std::make_unique<std::atomic<std::uint64_t>[]>(LatencySummary::kBins + 1)) {}
  /// Real-time safe; one writer thread. Negative values count as 0.
  void Add(double value_s) noexcept {
    const double v = value_s > 0 ? value_s : 0.0;
    const double b = v / LatencySummary::kBinWidthS;
    const std::size_t i = b >= static_cast<double>(LatencySummary::kBins)
                              ? LatencySummary::kBins
                              : static_cast<std::size_t>(b);
    bins_[i].store(bins_[i].load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
    total_.store(total_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
    if (v > max_.load(std::memory_order_relaxed)) max_.store(v, std::memory_order_relaxed);
  }
  LatencySummary Snapshot() const {
    LatencySummary s;
    for (std::size_t i = 0; i <= LatencySummary::kBins; ++i) {
      s.counts[i] = bins_[i].load(std::memory_order_relaxed);
      s.total += s.counts[i];
    }
    s.max_s = max_.load(std::memory_order_relaxed);
    return s;
  }
  std::uint64_t total() const { return total_.load(std::memory_order_relaxed); }

 private:
  std::unique_ptr<std::atomic<std::uint64_t>[]> bins_;
  std::atomic<std::uint64_t> total_{0};
  std::atomic<double> max_{0};
};

}  // namespace hapticlab
