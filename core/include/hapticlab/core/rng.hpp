#pragma once
/// @file Portable, seedable random numbers: the same sequence on every machine and standard
/// library (std::shuffle and std::*_distribution are implementation-defined), so a plan or a
/// simulation is reproducible from its seed alone.

#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <utility>
#include <vector>

namespace hapticlab {

/// SplitMix64 (Steele, Lea, Flood 2014): seeds expansion and seed derivation.
inline std::uint64_t SplitMix64(std::uint64_t& state) noexcept {
  std::uint64_t z = (state += 0x9e3779b97f4a7c15ull);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

/// A child seed from a parent seed and a stream number (participant index, trial index...).
inline std::uint64_t DeriveSeed(std::uint64_t parent, std::uint64_t stream) noexcept {
  std::uint64_t s = parent ^ (0xd1b54a32d192ed03ull * (stream + 1));
  SplitMix64(s);
  return SplitMix64(s);
}

/// xoshiro256** (Blackman & Vigna 2018). Allocation-free; usable in real-time code.
class Rng {
 public:
  explicit Rng(std::uint64_t seed = 1) noexcept { Seed(seed); }
  void Seed(std::uint64_t seed) noexcept {
    std::uint64_t x = seed;
    for (auto& s : s_) s = SplitMix64(x);
    has_spare_ = false;
  }
  std::uint64_t NextU64() noexcept {
    const std::uint64_t result = Rotl(s_[1] * 5, 7) * 9;
    const std::uint64_t t = s_[1] << 17;
    s_[2] ^= s_[0];
    s_[3] ^= s_[1];
    s_[1] ^= s_[2];
    s_[0] ^= s_[3];
    s_[2] ^= t;
    s_[3] = Rotl(s_[3], 45);
    return result;
  }
  /// Uniform in [0, 1).
  double Uniform() noexcept { return static_cast<double>(NextU64() >> 11) * 0x1.0p-53; }
  double Uniform(double a, double b) noexcept { return a + (b - a) * Uniform(); }
  /// Uniform integer in [0, n) without modulo bias (values below 2^64 mod n are rejected).
  /// @pre n > 0
  std::uint64_t Below(std::uint64_t n) noexcept {
    const std::uint64_t threshold = (0 - n) % n;
    for (;;) {
      const std::uint64_t x = NextU64();
      if (x >= threshold) return x % n;
    }
  }
  /// Standard normal (Box-Muller, no rejection loop: bounded work per call).
  double Normal() noexcept {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    const double u1 = 1.0 - Uniform(), u2 = Uniform();
    const double r = std::sqrt(-2.0 * std::log(u1)), th = 2.0 * std::numbers::pi * u2;
    spare_ = r * std::sin(th);
    has_spare_ = true;
    return r * std::cos(th);
  }
  double Normal(double mean, double sd) noexcept { return mean + sd * Normal(); }
  /// Fisher-Yates shuffle with this generator.
  template <class T>
  void Shuffle(std::vector<T>& v) noexcept {
    using std::swap;  // vector<bool> proxies have their own swap
    for (std::size_t i = v.size(); i > 1; --i) swap(v[i - 1], v[Below(i)]);
  }

 private:
  static std::uint64_t Rotl(std::uint64_t x, int k) noexcept { return (x << k) | (x >> (64 - k)); }
  std::array<std::uint64_t, 4> s_{};
  double spare_ = 0;
  bool has_spare_ = false;
};

}  // namespace hapticlab
