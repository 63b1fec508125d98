// Shards of a sweep: parsing, determinism, balance, every case exactly once.
#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <random>

#include "experiments/sharding.h"

using namespace tailsim;

TEST(Sharding, ParsesKOverNAndRejectsEverythingElse) {
  EXPECT_EQ(parseShard("3/8").index, 3);
  EXPECT_EQ(parseShard("3/8").count, 8);
  EXPECT_EQ(parseShard("1/1").count, 1);
  for (const char* bad : {"", "0/4", "5/4", "1/0", "-1/4", "1/", "/4", "a/4", "1/4/2", "1.5/4", " 1/4", "1/100001"})
    EXPECT_THROW(parseShard(bad), std::invalid_argument) << bad;
}

TEST(Sharding, EveryCaseOnceBalancedAndDeterministic) {
  std::mt19937 rng(13);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    const int n_cases = 1 + static_cast<int>(rng() % 500), n_shards = 1 + static_cast<int>(rng() % 16);
    std::vector<double> cost(n_cases);
    for (double& c : cost) c = u(rng) < 0.2 ? 30.0 * u(rng) : 0.001 + 0.002 * u(rng);  // MuJoCo-like and analytic-like
    const std::vector<int> a = assignShards(cost, n_shards);
    ASSERT_EQ(a, assignShards(cost, n_shards));  // same answer in every process
    std::vector<double> load(n_shards, 0.0);
    for (int i = 0; i < n_cases; ++i) {
      ASSERT_GE(a[i], 0);
      ASSERT_LT(a[i], n_shards);
      load[a[i]] += cost[i];
    }
    // LPT bound: the heaviest shard exceeds the mean by at most the largest single case.
    const double mean = std::accumulate(cost.begin(), cost.end(), 0.0) / n_shards;
    EXPECT_LE(*std::max_element(load.begin(), load.end()), mean + *std::max_element(cost.begin(), cost.end()) + 1e-12);
  }
}

TEST(Sharding, EqualCostsDealRoundRobin) {
  const std::vector<int> a = assignShards(std::vector<double>(7, 1.0), 3);
  EXPECT_EQ(a, (std::vector<int>{0, 1, 2, 0, 1, 2, 0}));
}

TEST(Sharding, CostModelMakesMujocoHeavier) {
  WorkEstimate mj, an;
  mj.rows = an.rows = 751;
  mj.models = {findModel(kMujocoModel)};
  mj.model_steps = {{findModel(kMujocoModel), StepLimit{3850, 0}}};
  an.models = {findModel(kAnalyticModel)};
  EXPECT_GT(expectedCaseCostS(mj), 10 * expectedCaseCostS(an));
}
