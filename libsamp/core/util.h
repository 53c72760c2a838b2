// Small helpers shared by several layers (one copy each): the median of a
// sample, ASCII lower case, fixed-point text of a number, the SplitMix64
// mixing function. Pure functions.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace samp {

// Median of `values` (the mean of the two middle values for an even count);
// 0 for an empty sample.
double Median(std::vector<double> values);

// ASCII lower case of `s`.
std::string Lower(std::string s);

// `value` with `digits` digits after the point ("%.*f", C locale).
std::string Fixed(double value, int digits);

// SplitMix64 (Steele, Lea, Flood 2014): a bijective 64-bit mix, the seed
// derivation of every seeded component. Inline: the procedural textures call
// it per pixel.
inline std::uint64_t SplitMix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

}  // namespace samp
