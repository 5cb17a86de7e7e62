#pragma once
// Counter-based random numbers: every number a pure function of (seed,
// stream, index), so a draw does not depend on threads, on the order work
// is done in, or on which other draws were made. One mixer (splitmix64's
// finalizer) serves the renderer's streams (renderer/src/sampler.h) and a
// data set's parameters (dataset_spec.h).

#include <cstdint>

namespace purkinje {

// splitmix64's finalizer: a bijection of 64-bit words with full avalanche.
inline std::uint64_t mix64(std::uint64_t z) {
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

// The key of (seed, stream, index) in two steps, so that loops over pixels
// hash the invariant part once. Each step is a bijection, so distinct
// indices of one (seed, stream) never share a key.
inline std::uint64_t stream_key(std::uint64_t seed, std::uint64_t stream) {
  return mix64(mix64(seed + 0x9E3779B97F4A7C15ull) ^ (stream + 0x632BE59BD9B4E019ull));
}
inline std::uint64_t counter_key(std::uint64_t stream_key, std::uint64_t index) {
  return mix64(stream_key ^ (index + 0xD1B54A32D192ED03ull));
}

// Uniform in [0, 1) from a key's top 53 bits.
inline double to_unit(std::uint64_t bits) { return static_cast<double>(bits >> 11) * 0x1.0p-53; }

}  // namespace purkinje
