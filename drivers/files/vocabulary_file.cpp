#include "drivers/files/vocabulary_file.hpp"

#include <vector>

#include "drivers/files/file_bytes.hpp"

namespace svslam::drivers {

Status saveVocabulary(const std::string& path, const BinaryVocabulary& vocabulary) {
  const std::vector<std::uint8_t> bytes = vocabulary.serialize();
  return writeFileAtomically(path, bytes.data(), bytes.size());
}

Result<BinaryVocabulary> loadVocabulary(const std::string& path) {
  Result<Bytes> bytes = readFileBytes(path, "vocabulary file");
  if (!bytes) return bytes.status();
  Result<BinaryVocabulary> voc = BinaryVocabulary::deserialize(bytes->data(), bytes->size());
  if (!voc) return Status(voc.status().code(), path + ": " + voc.status().message());
  return voc;
}

}  // namespace svslam::drivers
