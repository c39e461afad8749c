#pragma once
// The svslam subcommands. Each takes the words after its name, prints its result on stdout (JSON;
// config: YAML) and errors on stderr, and returns the process exit code (0 = success).
#include <string>
#include <vector>

namespace svslam::cli {

int runDisparity(const std::vector<std::string>& args);
int runEvalDisparity(const std::vector<std::string>& args);
int runFitSigma(const std::vector<std::string>& args);
int runEvalTrajectory(const std::vector<std::string>& args);
int runEvalDem(const std::vector<std::string>& args);  // tools/eval_dem_command.cpp
int runPipeline(const std::vector<std::string>& args);
int runConfig(const std::vector<std::string>& args);  // prints the documented defaults (YAML)
int runTrainVocabulary(const std::vector<std::string>& args);  // tools/train_vocabulary_command.cpp
int runPlot(const std::vector<std::string>& args);  // tools/plot_command.cpp (PNG + SVG)
int runCalibrate(const std::vector<std::string>& args);        // tools/calibrate_command.cpp
int runListen(const std::vector<std::string>& args);           // cli/listen_command.cpp (LCM)

}  // namespace svslam::cli
