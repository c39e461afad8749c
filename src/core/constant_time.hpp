#pragma once
// Comparison of secrets whose running time depends only on the lengths of the inputs, not on
// where they differ (no early exit), so a remote sender cannot find a token byte by byte from
// answer times.
#include <cstddef>
#include <string_view>

namespace svslam {

// True when `given` equals `secret`. Runs over every byte of `secret` whatever `given` holds;
// only the length of `given` (known to its sender) changes the branch pattern.
inline bool constantTimeEquals(std::string_view given, std::string_view secret) {
  volatile unsigned char diff = given.size() == secret.size() ? 0 : 1;
  for (std::size_t i = 0; i < secret.size(); ++i) {
    const unsigned char g = i < given.size() ? static_cast<unsigned char>(given[i]) : 0;
    diff = diff | static_cast<unsigned char>(g ^ static_cast<unsigned char>(secret[i]));
  }
  return diff == 0;
}

}  // namespace svslam
