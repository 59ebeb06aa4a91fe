// Nearest-timestamp association with gaps, offsets, ties and duplicate stamps.
#include "rsvio/eval/association.h"

#include <gtest/gtest.h>

using namespace rsvio::eval;

namespace {
constexpr int64_t kMs = 1'000'000;
}

TEST(Association, ConstantOffsetWithinLimitMatchesEveryEstimate) {
  std::vector<int64_t> gt, est;
  for (int i = 0; i < 200; ++i) gt.push_back(i * 5 * kMs);           // 200 Hz ground truth, 1 s
  for (int i = 0; i < 20; ++i) est.push_back(i * 50 * kMs + 2 * kMs);  // 20 Hz estimate, 2 ms late
  const Association a = associateNearest(est, gt, 10 * kMs);
  ASSERT_EQ(a.pairs.size(), 20u);
  for (size_t k = 0; k < a.pairs.size(); ++k) {
    EXPECT_EQ(a.pairs[k].i_est, k);
    EXPECT_EQ(a.pairs[k].i_gt, 10 * k);   // nearest: 2 ms before the next one is 3 ms away
    EXPECT_EQ(a.pairs[k].dt_ns, -2 * kMs);
  }
  EXPECT_EQ(a.largest_abs_dt_ns, 2 * kMs);
  EXPECT_EQ(a.unmatched(), 0u);
}

TEST(Association, OffsetBeyondLimitMatchesNothing) {
  std::vector<int64_t> gt{0, 100 * kMs, 200 * kMs}, est{15 * kMs, 115 * kMs};
  EXPECT_TRUE(associateNearest(est, gt, 10 * kMs).pairs.empty());
  EXPECT_EQ(associateNearest(est, gt, 15 * kMs).pairs.size(), 2u);  // the limit is inclusive
}

TEST(Association, GapsInGroundTruthAndEstimatesOutsideIt) {
  std::vector<int64_t> gt, est;
  for (int i = 0; i <= 10; ++i) gt.push_back(i * 10 * kMs);        // 0 .. 100 ms
  for (int i = 30; i <= 40; ++i) gt.push_back(i * 10 * kMs);       // gap 100 .. 300 ms
  for (int i = -2; i <= 45; ++i) est.push_back(i * 10 * kMs + kMs);  // before, inside the gap, after
  const Association a = associateNearest(est, gt, 5 * kMs);
  // Matched: estimates at 1..101 ms (11) and 301..401 ms (11); not the two before 0, the gap, nor after 400.
  ASSERT_EQ(a.pairs.size(), 22u);
  EXPECT_EQ(a.unmatched(), est.size() - 22);
  for (const auto& p : a.pairs) EXPECT_EQ(p.dt_ns, -kMs);
  EXPECT_EQ(a.pairs.front().i_gt, 0u);
  EXPECT_EQ(a.pairs[11].i_gt, 11u);  // first after the gap
  EXPECT_EQ(a.pairs.back().i_gt, gt.size() - 1);
}

TEST(Association, TiesGoToTheEarlierStampAndDuplicatesShareOnePose) {
  std::vector<int64_t> gt{0, 10 * kMs, 10 * kMs, 20 * kMs};
  std::vector<int64_t> est{5 * kMs, 10 * kMs, 10 * kMs, 15 * kMs};
  const Association a = associateNearest(est, gt, 10 * kMs);
  ASSERT_EQ(a.pairs.size(), 4u);
  EXPECT_EQ(a.pairs[0].i_gt, 0u);  // 5 ms: 0 and 10 ms are equally near -> earlier
  EXPECT_EQ(a.pairs[1].i_gt, 1u);  // exact, first of the duplicate ground-truth stamps
  EXPECT_EQ(a.pairs[2].i_gt, 1u);  // duplicate estimate: same ground-truth pose
  EXPECT_EQ(a.pairs[3].i_gt, 1u);  // 15 ms: tie between 10 and 20 -> earlier (first of the 10s)
}

TEST(Association, EmptyInputs) {
  EXPECT_TRUE(associateNearest(std::vector<int64_t>{1, 2}, std::vector<int64_t>{}, kMs).pairs.empty());
  EXPECT_TRUE(associateNearest(std::vector<int64_t>{}, std::vector<int64_t>{1}, kMs).pairs.empty());
}
