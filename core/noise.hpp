// The cut's force noise (docs/model.md, section 4): standard normal deviates drawn from a
// counter-based generator, a pure function of (seed, j).  A run continued over several
// kernel calls therefore draws the j-th deviate as one long call does, whatever the
// calls' lengths, and no generator state has to be carried between them.
#pragma once

#include <cmath>
#include <cstdint>

namespace bb::noise {

// splitmix64's output function (Steele, Lea and Flood, OOPSLA 2014): a bijection of
// 64-bit words whose outputs for consecutive inputs pass BigCrush.
inline std::uint64_t mix64(std::uint64_t z) {
    z += 0x9e3779b97f4a7c15ULL;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

constexpr double TWO_PI = 6.283185307179586;  // 2 pi rounded to a double
constexpr double TWO_M53 = 1.0 / 9007199254740992.0;  // 2^-53

// The j-th standard normal deviate of stream `seed`: Box-Muller of the uniforms
// u1 in (0, 1] and u2 in [0, 1), each the top 53 bits of a mixed word of (seed, j).
inline double normal_at(std::uint64_t seed, std::uint64_t j) {
    const std::uint64_t key = mix64(seed);
    const std::uint64_t a = mix64(key ^ mix64(2 * j));
    const std::uint64_t b = mix64(key ^ mix64(2 * j + 1));
    const double u1 = double((a >> 11) + 1) * TWO_M53;
    const double u2 = double(b >> 11) * TWO_M53;
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(TWO_PI * u2);
}

}  // namespace bb::noise
