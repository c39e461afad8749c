// libcamera: stereo source (see libcamera_source.hpp). Only compiled with SVSLAM_HAVE_LIBCAMERA.
#include "drivers/camera/libcamera_source.hpp"

#include <libcamera/libcamera.h>
#include <sys/mman.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <map>
#include <mutex>

#include "drivers/camera/camera_faults.hpp"
#include "drivers/camera/pixel_formats.hpp"
#include "drivers/camera/v4l2_source.hpp"

namespace svslam::drivers {
namespace {

namespace lc = libcamera;

// One acquired, configured and started camera; requests come back through the camera's
// requestCompleted signal on libcamera's thread and are handed over through `done_`.
class LcCamera {
 public:
  explicit LcCamera(std::shared_ptr<lc::Camera> cam) : cam_(std::move(cam)) {}
  ~LcCamera() {
    if (started_) cam_->stop();
    cam_->requestCompleted.disconnect(this);
    requests_.clear();
    for (auto& [buffer, plane] : maps_) ::munmap(plane.base, plane.map_length);
    allocator_.reset();
    if (acquired_) cam_->release();
  }
  LcCamera(const LcCamera&) = delete;
  LcCamera& operator=(const LcCamera&) = delete;

  Status start(int width, int height) {
    const std::string& id = cam_->id();
    if (cam_->acquire() < 0)
      return Status::ioError("libcamera: camera '" + id + "' is in use by another process");
    acquired_ = true;
    config_ = cam_->generateConfiguration({lc::StreamRole::VideoRecording});
    if (!config_ || config_->empty())
      return Status::ioError("libcamera: camera '" + id + "' offers no video stream");
    lc::StreamConfiguration& sc = config_->at(0);
    sc.size = lc::Size(static_cast<unsigned>(width), static_cast<unsigned>(height));
    for (const lc::PixelFormat& f : {lc::formats::R8, lc::formats::YUV420, lc::formats::NV12})
      if (std::find(sc.formats().pixelformats().begin(), sc.formats().pixelformats().end(), f) !=
          sc.formats().pixelformats().end()) {
        sc.pixelFormat = f;
        break;
      }
    if (config_->validate() == lc::CameraConfiguration::Invalid)
      return Status::invalidArgument("libcamera: camera '" + id + "' refuses the configuration");
    if (sc.size.width != static_cast<unsigned>(width) ||
        sc.size.height != static_cast<unsigned>(height))
      return Status::invalidArgument("libcamera: camera '" + id + "': asked for " +
                                     std::to_string(width) + "x" + std::to_string(height) +
                                     ", granted " + sc.size.toString() + " " +
                                     sc.pixelFormat.toString());
    if (sc.pixelFormat == lc::formats::YUYV)
      format_ = PixelFormat::kYuyv;
    else if (sc.pixelFormat == lc::formats::MJPEG)
      format_ = PixelFormat::kMjpeg;
    else if (sc.pixelFormat != lc::formats::R8 && sc.pixelFormat != lc::formats::YUV420 &&
             sc.pixelFormat != lc::formats::NV12)
      return Status::invalidArgument("libcamera: camera '" + id + "' granted pixel format " +
                                     sc.pixelFormat.toString() + " (no 8-bit luma plane)");
    if (cam_->configure(config_.get()) < 0)
      return Status::ioError("libcamera: cannot configure camera '" + id + "'");
    width_ = width;
    height_ = height;
    stride_ = sc.stride;
    stream_ = sc.stream();
    allocator_ = std::make_unique<lc::FrameBufferAllocator>(cam_);
    if (allocator_->allocate(stream_) < 0)
      return Status::ioError("libcamera: cannot allocate buffers for '" + id + "'");
    for (const auto& buffer : allocator_->buffers(stream_)) {
      const lc::FrameBuffer::Plane& p = buffer->planes()[0];
      const std::size_t len = static_cast<std::size_t>(p.offset) + p.length;
      void* base = ::mmap(nullptr, len, PROT_READ, MAP_SHARED, p.fd.get(), 0);
      if (base == MAP_FAILED)
        return Status::ioError("libcamera: cannot mmap a buffer of '" + id + "'");
      maps_[buffer.get()] = {base, len, static_cast<std::uint8_t*>(base) + p.offset};
      std::unique_ptr<lc::Request> req = cam_->createRequest();
      if (!req || req->addBuffer(stream_, buffer.get()) < 0)
        return Status::ioError("libcamera: cannot create a request for '" + id + "'");
      requests_.push_back(std::move(req));
    }
    cam_->requestCompleted.connect(this, &LcCamera::onCompleted);
    if (cam_->start() < 0) return Status::ioError("libcamera: cannot start camera '" + id + "'");
    started_ = true;
    for (auto& req : requests_)
      if (cam_->queueRequest(req.get()) < 0)
        return Status::ioError("libcamera: cannot queue a request on '" + id + "'");
    return Status::ok();
  }

  // Next completed frame as grey + timestamp (ns); requeues the request.
  Result<bool> grab(ImageU8& grey, TimeNs& t_ns, int timeout_ms) {
    lc::Request* req = nullptr;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      if (!cv_.wait_for(lock, std::chrono::milliseconds(timeout_ms),
                        [this] { return !done_.empty(); }))
        return Status::ioError("timeout: no frame from libcamera camera '" + cam_->id() +
                               "' within " + std::to_string(timeout_ms) + " ms");
      req = done_.front();
      done_.pop_front();
    }
    if (req->status() == lc::Request::RequestCancelled) return false;  // camera stopping
    lc::FrameBuffer* buffer = req->findBuffer(stream_);
    const lc::FrameMetadata& md = buffer->metadata();
    Status s = md.status == lc::FrameMetadata::FrameSuccess
                   ? convertToGrey(format_, maps_[buffer].data, md.planes()[0].bytesused, width_,
                                   height_, stride_, grey)
                   : Status::ioError("libcamera: frame error on '" + cam_->id() + "'");
    const auto sensor_t = req->metadata().get(lc::controls::SensorTimestamp);
    t_ns = sensor_t ? static_cast<TimeNs>(*sensor_t) : static_cast<TimeNs>(md.timestamp);
    req->reuse(lc::Request::ReuseBuffers);
    if (cam_->queueRequest(req) < 0)
      return Status::ioError("libcamera: cannot requeue a request on '" + cam_->id() + "'");
    if (!s) return s;
    return true;
  }

 private:
  struct Mapped {
    void* base = nullptr;
    std::size_t map_length = 0;
    const std::uint8_t* data = nullptr;  // first plane (luma)
  };
  void onCompleted(lc::Request* req) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      done_.push_back(req);
    }
    cv_.notify_one();
  }

  std::shared_ptr<lc::Camera> cam_;
  std::unique_ptr<lc::CameraConfiguration> config_;
  std::unique_ptr<lc::FrameBufferAllocator> allocator_;
  std::vector<std::unique_ptr<lc::Request>> requests_;
  std::map<const lc::FrameBuffer*, Mapped> maps_;
  lc::Stream* stream_ = nullptr;
  PixelFormat format_ = PixelFormat::kGrey;  // R8 / YUV420 / NV12: first plane is grey
  int width_ = 0, height_ = 0;
  std::size_t stride_ = 0;
  bool acquired_ = false, started_ = false;
  std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<lc::Request*> done_;
};

class LibcameraStereoSource final : public StereoSource {
 public:
  LibcameraStereoSource(std::unique_ptr<lc::CameraManager> manager, TimeNs sync_ns, int timeout_ms,
                        FrozenCameraParams frozen, std::vector<std::string> ids)
      : manager_(std::move(manager)),
        pairer_(sync_ns),
        timeout_ms_(timeout_ms),
        frozen_(frozen, std::move(ids)) {}
  ~LibcameraStereoSource() override {
    cams_[0].reset();
    cams_[1].reset();
    manager_->stop();
  }
  Status init(const std::shared_ptr<lc::Camera> cams[2], int width, int height,
              StereoRectification rect) {
    rect_ = std::move(rect);
    for (int i = 0; i < 2; ++i) {
      cams_[i] = std::make_unique<LcCamera>(cams[i]);
      if (Status s = cams_[i]->start(width, height); !s) return s;
    }
    return Status::ok();
  }
  const StereoCalibration& calibration() const override { return rect_.calib; }
  int size() const override { return -1; }
  // The next pair as captured (no rectification).
  Result<bool> nextRaw(ImageU8& left, ImageU8& right, TimeNs& t_ns) {
    return pairer_.next(
        [this](int c, ImageU8& img, TimeNs& t) { return cams_[c]->grab(img, t, timeout_ms_); },
        left, right, t_ns);
  }
  Result<bool> next(StereoFrame& out) override {
    TimeNs t_ns = 0;
    auto r = nextRaw(raw_left_, raw_right_, t_ns);
    if (!r || !*r) return r;
    std::string warning;
    for (int c = 0; c < 2; ++c)
      if (Status s = frozen_.check(c, (c == 0 ? raw_left_ : raw_right_).cview(), warning); !s)
        return s;
    if (!warning.empty()) {
      std::lock_guard<std::mutex> lock(warn_mutex_);
      warnings_ += warning + "\n";
    }
    if (Status s = rect_.apply(raw_left_, raw_right_, out); !s) return s;
    out.index = index_++;
    out.t_ns = t_ns;
    return true;
  }
  std::string takeWarnings() override {
    std::lock_guard<std::mutex> lock(warn_mutex_);
    std::string w;
    w.swap(warnings_);
    return w;
  }
  std::vector<std::pair<std::string, std::int64_t>> counters() const override {
    std::vector<std::pair<std::string, std::int64_t>> c;
    for (int i = 0; i < 2; ++i) {
      const std::string p = i == 0 ? "left_" : "right_";
      c.emplace_back(p + "unpaired", static_cast<std::int64_t>(pairer_.dropped(i)));
      c.emplace_back(p + "frozen", static_cast<std::int64_t>(frozen_.detections(i)));
      c.emplace_back(p + "max_identical_run", frozen_.maxRun(i));
    }
    return c;
  }

 private:
  std::unique_ptr<lc::CameraManager> manager_;  // outlives the cameras (destructor order)
  std::unique_ptr<LcCamera> cams_[2];
  StereoRectification rect_;
  TimestampPairer pairer_;
  int timeout_ms_;
  FrozenCameraWatch frozen_;
  ImageU8 raw_left_, raw_right_;
  int index_ = 0;
  std::mutex warn_mutex_;
  std::string warnings_;
};

class LibcameraRawCapture final : public RawStereoCapture {
 public:
  explicit LibcameraRawCapture(std::unique_ptr<LibcameraStereoSource> src) : src_(std::move(src)) {}
  Result<bool> next(ImageU8& left, ImageU8& right, TimeNs& t_ns) override {
    return src_->nextRaw(left, right, t_ns);
  }

 private:
  std::unique_ptr<LibcameraStereoSource> src_;
};

// raw: no calibration file needed (the rectification stays empty and only nextRaw is used).
Result<std::unique_ptr<LibcameraStereoSource>> openLibcamera(const std::string& spec_after_prefix,
                                                             bool raw) {
  auto spec = parseCameraSpec(
      spec_after_prefix, "libcamera",
      {"width", "height", "calib", "sync_ms", "timeout_ms", "frozen_frames", "frozen_action"});
  if (!spec) return spec.status();
  auto frozen = parseFrozenOptions(*spec, "libcamera");
  if (!frozen) return frozen.status();
  if (spec->devices.size() != 2)
    return Status::invalidArgument("libcamera: two camera ids needed (ID_LEFT,ID_RIGHT), got " +
                                   std::to_string(spec->devices.size()));
  int width = 640, height = 480, timeout_ms = 1000;
  double sync_ms = 5.0;
  try {
    const auto& o = spec->options;
    if (o.count("width")) width = std::stoi(o.at("width"));
    if (o.count("height")) height = std::stoi(o.at("height"));
    if (o.count("timeout_ms")) timeout_ms = std::stoi(o.at("timeout_ms"));
    if (o.count("sync_ms")) sync_ms = std::stod(o.at("sync_ms"));
  } catch (const std::exception&) {
    return Status::invalidArgument(
        "libcamera: width, height, timeout_ms and sync_ms must be "
        "numbers");
  }
  if (width < 2 || height < 2 || width > 16384 || height > 16384 || timeout_ms < 1 ||
      !(sync_ms >= 0.0 && sync_ms <= 1000.0))
    return Status::invalidArgument(
        "libcamera: width/height in [2, 16384], timeout_ms >= 1, "
        "sync_ms in [0, 1000]");
  auto manager = std::make_unique<lc::CameraManager>();
  if (int err = manager->start(); err < 0)
    return Status::ioError("libcamera: camera manager did not start (error " + std::to_string(err) +
                           ")");
  std::shared_ptr<lc::Camera> cams[2];
  for (int i = 0; i < 2; ++i) {
    cams[i] = manager->get(spec->devices[static_cast<std::size_t>(i)]);
    if (cams[i]) continue;
    const auto all = manager->cameras();
    std::string list = std::to_string(all.size()) + " cameras";
    for (std::size_t k = 0; k < all.size(); ++k) list += (k ? ", " : ": ") + all[k]->id();
    cams[0].reset();
    manager->stop();
    return Status::notFound("libcamera: camera '" + spec->devices[static_cast<std::size_t>(i)] +
                            "' not found (" + list + ")");
  }
  StereoRectification rect;
  auto calib = spec->options.find("calib");
  if (raw) {
    // no rectification: the views are delivered as captured
  } else if (calib == spec->options.end()) {
    cams[0].reset();
    cams[1].reset();
    manager->stop();
    return Status::invalidArgument("libcamera: calib=FILE is required (see docs/cameras.md)");
  } else {
    auto loaded = loadStereoRectification(calib->second, width, height);
    if (!loaded) {
      cams[0].reset();
      cams[1].reset();
      manager->stop();
      return loaded.status();
    }
    rect = std::move(loaded).value();
  }
  auto source = std::make_unique<LibcameraStereoSource>(
      std::move(manager), static_cast<TimeNs>(sync_ms * static_cast<double>(kNsPerMs)), timeout_ms,
      *frozen, spec->devices);
  if (Status s = source->init(cams, width, height, std::move(rect)); !s) return s;
  return source;
}

}  // namespace

Result<std::unique_ptr<StereoSource>> openLibcameraSource(const std::string& spec_after_prefix) {
  auto src = openLibcamera(spec_after_prefix, false);
  if (!src) return src.status();
  return std::unique_ptr<StereoSource>(std::move(src).value());
}

Result<std::unique_ptr<RawStereoCapture>> openLibcameraRawCapture(
    const std::string& spec_after_prefix) {
  auto src = openLibcamera(spec_after_prefix, true);
  if (!src) return src.status();
  return std::unique_ptr<RawStereoCapture>(
      std::make_unique<LibcameraRawCapture>(std::move(src).value()));
}

}  // namespace svslam::drivers
