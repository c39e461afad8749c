#include "drivers/files/gdal_support.hpp"

#include <gdal.h>

#include <mutex>

namespace svslam::drivers::gdal {

void registerDrivers() {
  static std::once_flag once;
  std::call_once(once, [] {
    ErrorCapture quiet;
    GDALAllRegister();
  });
}

ErrorCapture::ErrorCapture() {
  CPLPushErrorHandlerEx(&ErrorCapture::handler, this);
  CPLErrorReset();
}

ErrorCapture::~ErrorCapture() { CPLPopErrorHandler(); }

std::string ErrorCapture::message(const std::string& fallback) const {
  return messages_.empty() ? fallback : messages_;
}

void CPL_STDCALL ErrorCapture::handler(CPLErr cls, CPLErrorNum /*num*/, const char* msg) {
  auto* self = static_cast<ErrorCapture*>(CPLGetErrorHandlerUserData());
  if (self == nullptr || (cls != CE_Failure && cls != CE_Fatal)) return;
  self->failed_ = true;
  if (!self->messages_.empty()) self->messages_ += "; ";
  self->messages_ += msg != nullptr ? msg : "(no message)";
}

}  // namespace svslam::drivers::gdal
