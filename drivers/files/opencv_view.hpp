#pragma once
// A cv::Mat header over an ImageU8's pixels (no copy), for handing svslam images to OpenCV.
// The Mat must not outlive the image. The const overload is for OpenCV calls that only read.
#include <opencv2/core.hpp>

#include "core/image.hpp"

namespace svslam::drivers {

inline cv::Mat asMat(ImageU8& img) {
  return cv::Mat(img.height(), img.width(), CV_8U, img.row(0),
                 static_cast<std::size_t>(img.stride()));
}

inline cv::Mat asMat(const ImageU8& img) { return asMat(const_cast<ImageU8&>(img)); }

}  // namespace svslam::drivers
