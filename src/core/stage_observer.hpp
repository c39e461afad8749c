#pragma once
// StageObserver: lets the caller time (or trace) the stages of a pure library component
// without the library reading a clock. The component calls stageDone(name) at the end of each
// stage, in order; the first stage starts when process() is entered. Names are static strings.
namespace svslam {

class StageObserver {
 public:
  virtual ~StageObserver() = default;
  virtual void stageDone(const char* stage) = 0;
};

}  // namespace svslam
