#pragma once
// Vocabulary files: the bytes of BinaryVocabulary::serialize() (format "SVVOC1", see
// src/loop/binary_vocabulary.hpp), written atomically (a temporary beside it, then a rename).
//
// Errors name the path: notFound (no such file), invalidArgument (a directory or an empty file),
// ioError (a read or write failed), corruptData (the bytes are not a valid vocabulary; the
// reason from deserialize() follows the path).
#include <string>

#include "core/status.hpp"
#include "loop/binary_vocabulary.hpp"

namespace svslam::drivers {

Status saveVocabulary(const std::string& path, const BinaryVocabulary& vocabulary);
Result<BinaryVocabulary> loadVocabulary(const std::string& path);

}  // namespace svslam::drivers
