// What a finished run tells the user on the terminal besides its progress lines (user-contract.md:
// "Warnings a run records ... are printed on stderr too"): every warning of report.json once, and one
// line naming what the run did not use (an IMU it ignored, ground truth it did not find), so a run that
// "succeeds" on the wrong folder says so. Used by `rsvio run`; `rsvio demo` may call it too.
#pragma once
#include <string>
#include <vector>

#include "rsvio/io/report.h"

namespace rsvio::app {

// Prints each warning once (duplicates dropped, order kept) as "rsvio <command>: warning: <text>".
void printRunWarnings(const Report& report, const std::string& command = "run");

// "" or one line such as "not used: IMU (ignored: this configuration runs visual odometry); ground
// truth (none found in DIR: no mav0/state_groundtruth_estimate0 or mav0/mocap0; DIR/.. has it: is --data
// one level too deep?)". evaluate: the config's output.evaluate.
std::string notUsedLine(const Report& report, const std::string& data_dir, bool evaluate);

}  // namespace rsvio::app
