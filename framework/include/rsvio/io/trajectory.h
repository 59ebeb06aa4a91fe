// Trajectory files: the shared schema of every pose file rsvio reads or writes.
//
// Contract (../shared/guides/conventions.md, "Outputs" and "Data"):
// - A pose is T_W_X: it maps points of frame X (body = IMU, or camera) into the world frame,
//   p_W = q * p_X + p. Position in metres (or the estimator's free scale for VO), unit quaternion.
// - Time: int64 nanoseconds inside; TUM files hold seconds with 9 decimals (written exactly from t_ns).
// - TUM trajectory (written by `rsvio run`): first line "# frame: body" or "# frame: camera", then one
//   pose per line "t tx ty tz qx qy qz qw" (quaternion x, y, z, w: TUM's order), whitespace separated.
//   Other '#' lines and blank lines are comments. A file without the header has frame kUnknown.
// - EuRoC ground truth (mav0/state_groundtruth_estimate0/data.csv): comma separated
//   "t_ns, p(3), q(w, x, y, z), v(3), bg(3), ba(3)"; mav0/mocap0/data.csv: "t_ns, p(3), q(w, x, y, z)".
//   Both are poses of the body/IMU frame in the world (T_W_B).
// - Timestamps must not decrease. Equal consecutive stamps are kept (published files have them, e.g.
//   ORB-SLAM's EuRoC output); evaluation decides what to do with them.
// - Bad files throw DataError "path:line: <what>, <field>"; nothing here crashes or exits.
#pragma once
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace rsvio::io {

// Which frame a trajectory's poses are of (T_W_body or T_W_camera).
enum class PoseFrame { kUnknown, kBody, kCamera };

const char* poseFrameName(PoseFrame f);  // "unknown", "body", "camera"

struct StampedPose {
  int64_t t_ns = 0;
  Eigen::Vector3d p_W_X = Eigen::Vector3d::Zero();                  // position of frame X in the world
  Eigen::Quaterniond q_W_X = Eigen::Quaterniond::Identity();        // orientation of frame X, unit norm
};

struct Trajectory {
  PoseFrame frame = PoseFrame::kUnknown;
  std::vector<StampedPose> poses;  // non-decreasing t_ns
  std::string source;              // file it was read from (for messages), may be empty

  bool empty() const { return poses.empty(); }
  size_t size() const { return poses.size(); }
};

// One row of EuRoC's state_groundtruth_estimate0/data.csv.
struct GroundTruthState {
  int64_t t_ns = 0;
  Eigen::Vector3d p_W_B = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_W_B = Eigen::Quaterniond::Identity();
  Eigen::Vector3d v_W_B = Eigen::Vector3d::Zero();  // m/s, world frame
  Eigen::Vector3d bg = Eigen::Vector3d::Zero();     // gyroscope bias, rad/s
  Eigen::Vector3d ba = Eigen::Vector3d::Zero();     // accelerometer bias, m/s^2
};

// TUM trajectory files.
Trajectory readTum(const std::string& path);
void writeTum(const std::string& path, const Trajectory& traj);
// Formats one pose line exactly as writeTum does (no newline). Seconds come from t_ns without rounding.
std::string formatTumLine(const StampedPose& pose);
// t_ns as seconds with exactly 9 decimals ("-" for negative), no rounding through double.
std::string formatSeconds(int64_t t_ns);
// "1311868164.363181" -> 1311868164363181000 exactly (decimal strings are converted digit by digit;
// exponent notation goes through double). Returns nullopt on a malformed or non-finite number.
std::optional<int64_t> parseSecondsToNs(const std::string& token);

// EuRoC ground truth.
std::vector<GroundTruthState> readEurocStateGroundTruth(const std::string& path);
Trajectory readEurocMocap(const std::string& path);  // frame kBody

// Any ground-truth file: EuRoC state (17 columns) or mocap (8 columns) when comma separated,
// otherwise TUM (comment lines allowed, e.g. TUM RGB-D's fr2_desk_groundtruth.txt). EuRoC files are
// body poses; a TUM file keeps its header's frame (kUnknown without one: TUM RGB-D's ground truth is
// of a mocap marker frame, neither our body nor our camera).
Trajectory readGroundTruth(const std::string& path);

// <dir>/mav0/state_groundtruth_estimate0/data.csv if it exists, else <dir>/mav0/mocap0/data.csv;
// nullopt when the dataset has neither.
std::optional<std::string> findDatasetGroundTruth(const std::string& dataset_dir);

}  // namespace rsvio::io
