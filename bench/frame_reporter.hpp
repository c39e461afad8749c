#pragma once
// Google Benchmark's console output plus a per-frame summary: the real time per frame (ms) of
// every benchmark with a positive "frames" counter, for a derived reporter to print in Finalize.
#include <benchmark/benchmark.h>

#include <map>
#include <string>
#include <vector>

namespace svslam::bench {

class FrameReporter : public benchmark::ConsoleReporter {
 public:
  // What the "frames" counter of a benchmark counts.
  enum class Frames {
    kOnePerIteration,  // every iteration is one frame
    kPerIteration,     // every iteration processes "frames" frames
  };
  explicit FrameReporter(Frames frames) : frames_(frames) {}

  void ReportRuns(const std::vector<Run>& runs) override {
    for (const Run& r : runs) {
      if (r.run_type != Run::RT_Iteration || r.error_occurred) continue;
      const auto it = r.counters.find("frames");
      if (it == r.counters.end() || it->second.value <= 0) continue;
      const double ms = r.GetAdjustedRealTime();  // unit: ms per iteration
      per_frame_ms_[r.benchmark_name()] =
          frames_ == Frames::kPerIteration ? ms / it->second.value : ms;
    }
    ConsoleReporter::ReportRuns(runs);
  }

 protected:
  std::map<std::string, double> per_frame_ms_;

 private:
  Frames frames_;
};

// The main of a benchmark program: runs the benchmarks the command line selects, reported by a
// default-constructed `Reporter`.
template <typename Reporter>
int benchmarkMain(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  Reporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  benchmark::Shutdown();
  return 0;
}

}  // namespace svslam::bench
