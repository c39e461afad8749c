#pragma once
// The shared token that LCM commands must carry, read from its own file (never from the
// configuration, which is world-readable).
#include <cstddef>
#include <string>

#include "core/status.hpp"

namespace svslam::drivers {

// Longest token accepted, bytes.
inline constexpr std::size_t kMaxCommandTokenBytes = 4096;

// Reads the token from `path`: the file's content without trailing whitespace (a final newline
// from `echo` is not part of the token). Errors, each naming the file: it cannot be opened or
// is not a regular file; its mode lets group or others access it (st_mode & 077 != 0: the file
// must be readable by the service alone, e.g. chmod 0600 or 0400); it is empty or holds only
// whitespace; it is longer than kMaxCommandTokenBytes.
Result<std::string> readCommandToken(const std::string& path);

}  // namespace svslam::drivers
