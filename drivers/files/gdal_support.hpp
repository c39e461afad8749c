#pragma once
// Internal to drivers/files (never included by a public header): GDAL's driver registration and
// its error messages turned into text instead of lines on stderr.
#include <cpl_error.h>

#include <string>

namespace svslam::drivers::gdal {

// Registers GDAL's drivers once per process (thread-safe).
void registerDrivers();

// While alive, GDAL errors raised on this thread are collected here (GDAL's error handler stack
// is per thread) and nothing is printed. Warnings are ignored.
class ErrorCapture {
 public:
  ErrorCapture();
  ~ErrorCapture();
  ErrorCapture(const ErrorCapture&) = delete;
  ErrorCapture& operator=(const ErrorCapture&) = delete;

  bool failed() const { return failed_; }
  // The collected messages joined by "; ", or `fallback` when GDAL gave none.
  std::string message(const std::string& fallback = "GDAL gave no reason") const;

 private:
  static void CPL_STDCALL handler(CPLErr cls, CPLErrorNum num, const char* msg);
  std::string messages_;
  bool failed_ = false;
};

}  // namespace svslam::drivers::gdal
