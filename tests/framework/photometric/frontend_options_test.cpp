// The "frontend" config section: table keys are unique and complete, defaults reproduce the structs'
// defaults (so a config without the section runs DSO's settings), values reach the structs, and bad
// values are reported with their path.
#include <gtest/gtest.h>

#include <set>

#include "rsvio/config/validate.h"
#include "rsvio/frontend/frontend_options.h"

namespace rsvio {
namespace {

Params section(const nlohmann::json& given, std::vector<ConfigProblem>* problems) {
  return Params(validateParams(given, frontendParamTable(), "frontend", *problems), "frontend");
}

TEST(FrontendOptions, KeysAreUniqueAndDescribed) {
  std::set<std::string> keys;
  for (const ParamSpec& s : frontendParamTable()) {
    EXPECT_TRUE(keys.insert(s.key).second) << "duplicate key " << s.key;
    EXPECT_FALSE(s.description.empty()) << s.key;
    EXPECT_FALSE(s.default_value.is_null()) << s.key << " has no default";
  }
  for (const char* k : {"points", "residual_huber", "track_cutoff", "trace_step_px", "pyramid_levels"})
    EXPECT_TRUE(keys.count(k)) << k;
}

TEST(FrontendOptions, DefaultsAreTheStructDefaults) {
  std::vector<ConfigProblem> problems;
  const FrontendOptions o = frontendOptions(section(nlohmann::json::object(), &problems), 42, 8);
  ASSERT_TRUE(problems.empty());
  const PixelSelectorOptions ds;
  const ResidualOptions dr;
  const TrackerOptions dt;
  const CandidateOptions dc;
  EXPECT_EQ(o.select.num_points, ds.num_points);
  EXPECT_EQ(o.select.block_px, ds.block_px);
  EXPECT_EQ(o.select.seed, 42u);
  EXPECT_DOUBLE_EQ(o.residual.huber_th, dr.huber_th);
  EXPECT_DOUBLE_EQ(o.residual.grad_weight_c, dr.grad_weight_c);
  EXPECT_DOUBLE_EQ(o.track.residual.outlier_th, dr.outlier_th);
  EXPECT_DOUBLE_EQ(o.track.cutoff_th, dt.cutoff_th);
  EXPECT_DOUBLE_EQ(o.track.min_inlier_ratio, dt.min_inlier_ratio);
  EXPECT_EQ(o.track.threads, 2);  // capped
  EXPECT_DOUBLE_EQ(o.trace.step_px, dc.step_px);
  EXPECT_DOUBLE_EQ(o.trace.min_quality, dc.min_quality);
}

TEST(FrontendOptions, ValuesReachTheStructsAndBadOnesAreReported) {
  std::vector<ConfigProblem> problems;
  const FrontendOptions o = frontendOptions(
      section({{"points", 800}, {"residual_huber", 5.0}, {"track_levels", 6}, {"pyramid_levels", 4},
               {"trace_step_px", 0.5}},
              &problems),
      1, 1);
  ASSERT_TRUE(problems.empty());
  EXPECT_EQ(o.select.num_points, 800);
  EXPECT_DOUBLE_EQ(o.track.residual.huber_th, 5.0);
  EXPECT_EQ(o.track.max_levels, 4);  // never more than the pyramid has
  EXPECT_EQ(o.track.threads, 1);
  EXPECT_DOUBLE_EQ(o.trace.step_px, 0.5);
  problems.clear();
  section({{"points", -3}, {"track_cutof", 20}}, &problems);
  ASSERT_EQ(problems.size(), 2u);
  std::string all;
  for (const auto& p : problems) all += p.str() + "\n";
  EXPECT_NE(all.find("frontend.points"), std::string::npos) << all;
  EXPECT_NE(all.find("track_cutoff"), std::string::npos) << all;  // did-you-mean
}

}  // namespace
}  // namespace rsvio
