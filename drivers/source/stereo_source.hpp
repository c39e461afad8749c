#pragma once
// Stereo sequence sources: each yields timestamped, rectified grey stereo pairs and the
// rectified calibration (left camera, baseline along +x).
//   kitti:DIR  KITTI odometry layout: image_0/ + image_1/ (or image_l/ + image_r/), calib.txt
//              with P0 and P1 (labelled "P0:" or not; same fx, fy, cx, cy), optional times.txt
//              (s, increasing, one per frame name); else 10 Hz. Left and right images are
//              paired by name; a frame with one side missing is skipped and counted
//              (skippedFrames); names starting with '.' are not images.
//   euroc:DIR  EuRoC ASL layout: mav0/cam0, mav0/cam1 (data.csv, sensor.yaml with pinhole
//              intrinsics, radial-tangential distortion, T_BS); rectified with OpenCV
//              (stereoRectify, precomputed remap maps).
//   synthetic[:key=value,...]  rendered stereo flight over a textured heightfield with exact
//              ground truth (synthetic_flight.hpp); the built-in default source.
#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/camera.hpp"
#include "core/image.hpp"
#include "core/status.hpp"
#include "core/time.hpp"
#include "map/dem_raster.hpp"

namespace svslam::drivers {

struct StereoFrame {
  int index = 0;  // 0-based position in the sequence
  TimeNs t_ns = 0;
  ImageU8 left, right;  // rectified, grey
};

class StereoSource {
 public:
  virtual ~StereoSource() = default;
  virtual const StereoCalibration& calibration() const = 0;
  // Number of frames, or -1 when unknown (live cameras).
  virtual int size() const = 0;
  // Frames of a recording left out when it was opened (kitti: the left or the right image is
  // missing), and their names (the first ten); 0 and "" when none.
  virtual int skippedFrames() const { return 0; }
  virtual std::string skippedFramesDetail() const { return ""; }
  // Reads the next pair into `out` (buffers reused); returns false at the end of the sequence.
  // A missing or corrupt image is an error naming the file.
  virtual Result<bool> next(StereoFrame& out) = 0;
  // Events worth a log line since the last call (live cameras: reconnected, frozen), one per
  // line; "" when none. Thread-safe: may be called while another thread is in next().
  virtual std::string takeWarnings() { return ""; }
  // The source's own counters for stats.json (live cameras: frames, dropped buffers,
  // reconnects...), in a fixed order; empty when it has none. Not while next() runs.
  virtual std::vector<std::pair<std::string, std::int64_t>> counters() const { return {}; }
  // Ground-truth pose of frame `index` when the source knows it exactly (synthetic): the left
  // camera in the frame of the first left camera (KITTI convention). False otherwise.
  virtual bool groundTruth(int index, Eigen::Isometry3d& T_first_cam) const {
    (void)index;
    (void)T_first_cam;
    return false;
  }
  // Gravity direction (unit vector, pointing down) in the frame of the first left camera (x
  // right, y down, z forward) when the source knows it (synthetic: exact). False otherwise.
  virtual bool gravityInFirstCamera(Eigen::Vector3d& g) const {
    (void)g;
    return false;
  }
  // The exact terrain height of the cells of `raster`'s window (its size and cell set by the
  // caller) that the left camera saw in frames 0 .. frames - 1, in the map frame given by
  // R_map_world (map/map_frame.hpp), when the source knows its terrain (synthetic); its count
  // band: frames in which both cameras saw the cell. False (raster untouched) otherwise.
  virtual bool groundTruthDem(const Eigen::Matrix3d& R_map_world, int frames,
                              map::DemRaster& raster) const {
    (void)R_map_world;
    (void)frames;
    (void)raster;
    return false;
  }
};

// StereoCalibration::validate, and bounds that keep projections finite: f_px <= 1e6 px,
// |cx_px|, |cy_px| <= 1e6 px, baseline_m <= 1e4 m, sides <= 65536 px.
Status checkStereoCalibration(const StereoCalibration& c);

Result<std::unique_ptr<StereoSource>> openKittiSource(const std::string& dir);
Result<std::unique_ptr<StereoSource>> openEurocSource(const std::string& dir);
// The rectified left camera that openEurocSource(dir) tracks, in the body (IMU) frame of the
// EuRoC ground truth: T_B_rect = T_BS(cam0) * [R0^T | 0], R0 the rotation stereoRectify gives
// cam0 (p_rect = R0 p_cam0; the centre does not move). svslam's poses are those of this
// camera, so T_W_B * T_B_rect is the ground truth to score them against (EuRoC MH01: R0 turns
// by 0.62 deg). Reads mav0/cam0 and mav0/cam1 sensor.yaml only.
Result<Eigen::Isometry3d> eurocBodyToRectifiedLeft(const std::string& dir);

// "synthetic[:key=value,...]" (keys in synthetic_flight.hpp).
Result<std::unique_ptr<StereoSource>> openSyntheticSource(const std::string& options);

// Polled while opening a source waits (lcm: for its first frame): true = give up. Empty: wait.
using StopQuery = std::function<bool()>;

// "kitti:DIR", "euroc:DIR", "synthetic[:key=value,...]", "v4l2:...", "libcamera:..." or
// "lcm:CHANNEL...". An open abandoned because `stop` returned true is an error saying so.
Result<std::unique_ptr<StereoSource>> openStereoSource(const std::string& spec,
                                                       const StopQuery& stop = {});

}  // namespace svslam::drivers
