#pragma once
// Output files of `svslam run`, written as the run goes so that nothing already computed is
// lost when a later frame fails:
//   trajectory_kitti.txt  one 3x4 row-major [R | t] per input frame (left camera in the first
//                         left camera's frame, metres),
//   trajectory_tum.txt    t tx ty tz qx qy qz qw (t in seconds),
//   groundtruth_kitti.txt the source's exact poses, when it has them (synthetic),
//   stats.json            written at the end (atomically), also after a failure.
#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "core/status.hpp"
#include "core/time.hpp"

namespace svslam::run {

// The names of the files `svslam run` writes into its output folder (which of them a run
// writes depends on its mode, map and source).
namespace files {
inline constexpr const char* kTrajectoryKitti = "trajectory_kitti.txt";
inline constexpr const char* kTrajectoryTum = "trajectory_tum.txt";
inline constexpr const char* kGroundTruthKitti = "groundtruth_kitti.txt";
inline constexpr const char* kPoseCovariance = "pose_covariance.txt";
inline constexpr const char* kLandmarks = "landmarks.ply";
inline constexpr const char* kStats = "stats.json";
inline constexpr const char* kDem = "dem.tif";
inline constexpr const char* kOrthoTiff = "ortho.tif";
inline constexpr const char* kOrthoPng = "ortho.png";
inline constexpr const char* kHillshade = "dem_hillshade.png";
inline constexpr const char* kGroundTruthDem = "groundtruth_dem.tif";
inline constexpr const char* kLatency = "latency.txt";
inline constexpr const char* kTrajectoryOptimizedKitti = "trajectory_optimized_kitti.txt";
inline constexpr const char* kTrajectoryOptimizedTum = "trajectory_optimized_tum.txt";
inline constexpr const char* kLandmarksOptimized = "landmarks_optimized.ply";
inline constexpr const char* kDemOptimized = "dem_optimized.tif";
inline constexpr const char* kOrthoOptimizedTiff = "ortho_optimized.tif";
inline constexpr const char* kOrthoOptimizedPng = "ortho_optimized.png";
// `svslam plot` writes its pictures into the run folder by default: they belong to the run.
inline constexpr const char* kAll[] = {
    kTrajectoryKitti, kTrajectoryTum, kGroundTruthKitti, kPoseCovariance, kLandmarks, kStats, kDem,
    kOrthoTiff,       kOrthoPng,      kHillshade,        kGroundTruthDem, kLatency,
    kTrajectoryOptimizedKitti, kTrajectoryOptimizedTum, kLandmarksOptimized, kDemOptimized,
    kOrthoOptimizedTiff, kOrthoOptimizedPng,
    "trajectory_top.png", "trajectory_top.svg", "altitude.png", "altitude.svg", "landmarks.png",
    "landmarks.svg", "latency.png", "latency.svg"};
}  // namespace files

// A run owns its output folder: removes from `dir` every file of files::kAll (and the
// temporary "<name>.tmp" of an interrupted atomic write), so that no file of an earlier run is
// left beside the new ones. Other files, and folders, are left alone. Error naming the file
// that cannot be removed.
Status clearRunOutputs(const std::string& dir);

// A text file appended one whole line at a time, each line written through to the file
// (write(2), no user-space buffer). A failed write or close (disk full: ENOSPC; a file size
// limit: EFBIG, with SIGXFSZ ignored) is an error naming the file and the system's reason, and
// the file is cut back to its last whole line (what was written before stays intact, byte for
// byte); every later append then fails with the same error.
class AppendFile {
 public:
  AppendFile() = default;
  ~AppendFile();
  AppendFile(const AppendFile&) = delete;
  AppendFile& operator=(const AppendFile&) = delete;
  // Creates (truncates) `path`.
  Status open(const std::string& path);
  // Appends `n` bytes (one or more whole lines, newline included).
  Status append(const char* data, std::size_t n);
  // Closes the file; error when the system reports a failure. No-op when not open.
  Status close();
  bool isOpen() const { return fd_ >= 0; }
  const std::string& path() const { return path_; }

 private:
  int fd_ = -1;
  std::string path_;
  std::int64_t whole_bytes_ = 0;  // bytes of the lines written whole
  Status error_;                  // the first write error (sticky)
};

// One line per pose in a KITTI and a TUM file (AppendFile: each line written through, a
// failure names the file and leaves whole lines).
class TrajectoryWriter {
 public:
  TrajectoryWriter() = default;
  TrajectoryWriter(const TrajectoryWriter&) = delete;
  TrajectoryWriter& operator=(const TrajectoryWriter&) = delete;
  // Creates (truncates) `kitti_path` and, when not empty, `tum_path`.
  Status open(const std::string& kitti_path, const std::string& tum_path);
  Status append(TimeNs t_ns, const Eigen::Isometry3d& T);
  // Error when closing either file failed (the first one).
  Status close();

 private:
  AppendFile kitti_, tum_;
};

// A text file written line by line, each line written through (pose_covariance.txt: 36 numbers
// per frame, the 6x6 pose covariance row-major, [rot (rad), trans (m)]).
class LineWriter {
 public:
  LineWriter() = default;
  LineWriter(const LineWriter&) = delete;
  LineWriter& operator=(const LineWriter&) = delete;
  Status open(const std::string& path);
  Status append(const std::string& line);  // adds the newline
  Status close();

 private:
  AppendFile file_;
  std::string buf_;  // the line and its newline, reused
};

// One landmark of landmarks.ply.
struct PlyLandmark {
  int id = 0;
  Eigen::Vector3d p_world = Eigen::Vector3d::Zero();  // m
  Eigen::Vector3d sigma_m = Eigen::Vector3d::Zero();  // 1-sigma radii along x, y, z (sqrt diag)
  bool active = false;                                // in the filter state (else retired)
  int observations = 0;
};
// ASCII PLY: x y z sigma_x sigma_y sigma_z id active observations, written atomically.
Status writeLandmarksPly(const std::string& path, const std::vector<PlyLandmark>& landmarks);

// Per-stage durations in milliseconds, summarised as p50 / p99 / max.
// Each stage keeps its newest `capacity` samples in a ring allocated when the stage is first
// seen, so add() allocates nothing afterwards; percentiles are over the kept samples, max and
// count over every sample added.
class StageTimes {
 public:
  explicit StageTimes(std::size_t capacity = std::size_t{1} << 15);  // samples kept per stage
  void add(std::string_view stage, double ms);
  // {"stage": {"p50_ms": .., "p99_ms": .., "max_ms": .., "count": n}, ...} in insertion order.
  std::string json() const;
  double median(const std::string& stage) const;  // NaN when no sample
  // Appends the samples of `other` (stages new to this one go after its own, in order).
  void merge(const StageTimes& other);

 private:
  struct Samples {
    std::vector<double> ring;  // capacity_ slots, ms
    std::size_t next = 0;      // slot of the next sample
    std::size_t kept_n = 0;    // slots holding a sample (<= ring.size())
    std::int64_t count = 0;    // samples ever added (kept or not)
    double max_ms = 0;
    std::vector<double> kept() const;  // the kept samples, oldest first
  };
  Samples& stage(std::string_view name);
  void push(Samples& s, double ms) const;

  std::size_t capacity_;
  std::vector<std::string> order_;
  std::map<std::string, Samples, std::less<>> samples_;
};

// Nearest-rank percentile (p in [0, 100]) of `v` (copied, sorted); NaN when empty.
double percentile(std::vector<double> v, double p);

// Writes `text` to `path` through a temporary file and a rename. On failure the temporary is
// removed, an earlier file at `path` stays as it was, and the error names `path` and the
// system's reason.
Status writeFileAtomic(const std::string& path, const std::string& text);

}  // namespace svslam::run
