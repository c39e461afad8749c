#pragma once
// The JSON lines of `svslam listen`: any svslam_lcm message, recognised by its type hash (the
// first 8 bytes of every LCM message, big-endian; the way lcm-spy picks a decoder), decoded with
// the validating decoders of drivers/lcm and written as one flat JSON object on one line.
//
// Every line starts with "type" (pose, stats, map_summary, map_tile, pose_correction, command,
// command_status, stereo_image) and "channel". Units as on the wire (lcm/*.lcm): utime in
// microseconds, t_ns in nanoseconds, positions in metres, quaternions (w, x, y, z). Bulky
// payloads are summarised: map_summary gives the landmark count (not the points), stereo_image
// the size, calibration and mean grey level of each image, map_tile the cells with data and
// their mean height. A command line says whether a token was carried, never the token.
#include <cstddef>
#include <cstdint>
#include <string>

namespace svslam::cli {

enum class ListenType {
  kUnknown,  // not an svslam_lcm type (or fewer than 8 bytes)
  kPose,
  kStats,
  kMapSummary,
  kMapTile,
  kPoseCorrection,
  kCommand,
  kCommandStatus,
  kStereoImage,
};

// The JSON "type" of `t` ("pose", "map_tile", ...; "unknown").
const char* listenTypeName(ListenType t);

// The svslam_lcm type whose hash the message starts with.
ListenType listenTypeOf(const std::uint8_t* data, std::size_t size);

struct ListenLine {
  ListenType type = ListenType::kUnknown;
  std::string json;   // the line without its newline; empty when not decoded
  std::string error;  // why the message could not be decoded (kUnknown: "unknown type hash")
};

// Decodes one received message: `json` on success, `error` for a malformed svslam message or a
// message of another type.
ListenLine listenLine(const std::string& channel, const std::uint8_t* data, std::size_t size);

}  // namespace svslam::cli
