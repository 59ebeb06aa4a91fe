// Cross-check against an independent evaluator: every ATE figure of
// ../shared/data/eval-reference/README.md (evo's own numbers), to 1e-5 m. Missing files are a failure,
// not a skip: this is the check that our evaluation means what the literature's does.
#include <gtest/gtest.h>

#include <filesystem>

#include "rsvio/eval/evaluate_files.h"

using namespace rsvio::eval;

namespace {

struct Figure {
  const char* gt;
  const char* est;
  size_t pairs;
  AlignMode align;
  double ate_rmse_m;
};

const Figure kFigures[] = {
    {"fr2_desk_groundtruth.txt", "fr2_desk_ORB.txt", 2174, AlignMode::kNone, 3.173994},
    {"fr2_desk_groundtruth.txt", "fr2_desk_ORB.txt", 2174, AlignMode::kSE3, 0.008119},
    {"fr2_desk_groundtruth.txt", "fr2_desk_ORB.txt", 2174, AlignMode::kSim3, 0.006123},
    {"V102_groundtruth.csv", "V102.txt", 798, AlignMode::kNone, 2.554174},
    {"V102_groundtruth.csv", "V102.txt", 798, AlignMode::kSE3, 0.091727},
    {"V102_groundtruth.csv", "V102.txt", 798, AlignMode::kSim3, 0.083841},
};

}  // namespace

TEST(EvalReference, ReproducesEveryListedAteFigure) {
  const std::filesystem::path dir = std::filesystem::path(RSVIO_SHARED_DIR) / "data" / "eval-reference";
  ASSERT_TRUE(std::filesystem::is_regular_file(dir / "README.md")) << "missing reference data in " << dir;
  for (const auto& f : kFigures) {
    SCOPED_TRACE(std::string(f.est) + " " + alignModeName(f.align));
    ASSERT_TRUE(std::filesystem::is_regular_file(dir / f.gt)) << dir / f.gt;
    ASSERT_TRUE(std::filesystem::is_regular_file(dir / f.est)) << dir / f.est;
    FileEvalRequest req;
    req.gt_path = (dir / f.gt).string();
    req.est_path = (dir / f.est).string();
    req.align = f.align;
    const FileEvalOutcome o = evaluateFiles(req);
    EXPECT_EQ(o.result.association.pairs.size(), f.pairs);
    EXPECT_NEAR(o.result.ate_m.rmse, f.ate_rmse_m, 1e-5);
    EXPECT_EQ(o.result.alignment.mode, f.align);
  }
}
