#include "run_summary.h"

#include <filesystem>
#include <iostream>
#include <set>

#include "rsvio/io/trajectory.h"

namespace rsvio::app {

namespace fs = std::filesystem;

void printRunWarnings(const Report& report, const std::string& command) {
  std::set<std::string> seen;
  for (const auto& w : report.warnings) {
    if (!seen.insert(w).second) continue;
    std::cerr << "rsvio " << command << ": warning: " << w << "\n";
  }
}

std::string notUsedLine(const Report& report, const std::string& data_dir, bool evaluate) {
  std::vector<std::string> parts;
  for (const auto& w : report.warnings) {
    if (w.find("IMU ignored") != std::string::npos) {
      parts.push_back("IMU (ignored: this configuration runs visual odometry)");
      break;
    }
  }
  if (!evaluate) {
    parts.push_back("ground truth (output.evaluate is false)");
  } else if (!report.eval) {
    if (!io::findDatasetGroundTruth(data_dir)) {
      std::string gt = "ground truth (none found in " + data_dir +
                       ": no mav0/state_groundtruth_estimate0/data.csv or mav0/mocap0/data.csv";
      fs::path dir = fs::absolute(fs::path(data_dir)).lexically_normal();
      if (dir.filename().empty()) dir = dir.parent_path();  // "data/mav0/" -> "data/mav0"
      const fs::path parent = dir.parent_path();
      if (dir.filename() == "mav0" || (!parent.empty() && io::findDatasetGroundTruth(parent.string())))
        gt += "; --data is one level too deep? give the folder that holds mav0/: " + parent.string();
      parts.push_back(gt + "; no ATE)");
    } else {
      for (const auto& w : report.warnings)
        if (w.rfind("evaluation skipped", 0) == 0) parts.push_back("ground truth (" + w + ")");
    }
  }
  std::string line;
  for (const auto& p : parts) line += (line.empty() ? "" : "; ") + p;
  return line.empty() ? "" : "not used: " + line;
}

}  // namespace rsvio::app
