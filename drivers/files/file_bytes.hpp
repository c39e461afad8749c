#pragma once
// Whole files as bytes: read into memory with errors that name the file and what it should
// have been, and written atomically (a temporary beside it, then a rename), so that a reader
// never sees half a file.
#include <cstddef>
#include <string>
#include <vector>

#include "core/status.hpp"

namespace svslam::drivers {

using Bytes = std::vector<unsigned char>;

// Whole file in memory; `what` names the kind of file in messages ("image", "PFM file", ...).
// A missing file is notFound, a directory or an empty file invalidArgument.
Result<Bytes> readFileBytes(const std::string& path, const char* what);

// Writes `path + ".tmp"`, then renames it over `path`; removes the temporary on any failure.
Status writeFileAtomically(const std::string& path, const void* data, std::size_t n);

}  // namespace svslam::drivers
