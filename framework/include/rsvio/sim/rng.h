// Random streams of the simulator: one independent stream per (seed, purpose[, index]).
//
// Contract (conventions.md, "Determinism")
// - Every consumer of randomness draws from its own stream, keyed by the run's seed, a purpose string
//   ("trajectory", "scene", "effect.image_noise", ...) and an optional index (a frame number, a scene
//   face). Switching an effect on or off therefore never shifts another consumer's numbers: the same
//   seed gives the same trajectory, scene and noise whatever effects are on, and a frame's noise does
//   not depend on which thread rendered it or in which order.
// - The generator is std::mt19937_64 (fully specified by the standard). Distributions are our own
//   (uniform01, gauss) because std::normal_distribution differs between standard libraries.
#pragma once
#include <cmath>
#include <cstdint>
#include <random>
#include <string_view>

namespace rsvio::sim {

// SplitMix64 finaliser: a bijective mixer, so distinct keys give unrelated seeds.
inline uint64_t mix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

// FNV-1a of the purpose string.
inline uint64_t hashPurpose(std::string_view purpose) {
  uint64_t h = 0xCBF29CE484222325ull;
  for (char c : purpose) {
    h ^= static_cast<unsigned char>(c);
    h *= 0x100000001B3ull;
  }
  return h;
}

inline uint64_t streamSeed(uint64_t seed, std::string_view purpose, uint64_t index = 0) {
  return mix64(mix64(mix64(seed) ^ hashPurpose(purpose)) ^ mix64(index + 0x5851F42D4C957F2Dull));
}

inline std::mt19937_64 makeStream(uint64_t seed, std::string_view purpose, uint64_t index = 0) {
  return std::mt19937_64(streamSeed(seed, purpose, index));
}

// Uniform in [0, 1) with 53 random bits.
inline double uniform01(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

inline double uniform(std::mt19937_64& rng, double lo, double hi) { return lo + (hi - lo) * uniform01(rng); }

// Standard normal by Box-Muller (one value per call; the second is dropped to keep the stream stateless).
inline double gauss(std::mt19937_64& rng) {
  const double u1 = 1.0 - uniform01(rng);  // (0, 1]
  const double u2 = uniform01(rng);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
}

}  // namespace rsvio::sim
