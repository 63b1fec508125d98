// Splitting a sweep into N shards for N processes or cluster jobs: `tailsim run EXP
// --shard K/N` runs the cases assigned to shard K, `tailsim merge` joins the shards' folders.
#pragma once

#include <string>
#include <vector>

#include "experiments/experiment_loader.h"
#include "experiments/work_estimate.h"

namespace tailsim {

// "K/N" with 1 <= K <= N <= kMaxShards. Throws std::invalid_argument naming the text.
struct ShardSpec {
  int index = 1;  // K, 1-based
  int count = 1;  // N
};
constexpr int kMaxShards = 100000;
ShardSpec parseShard(const std::string& text);

// Expected wall time of one case on one core [s], from its work estimate: a rough, documented cost
// model used only to balance shards (docs/scale.md): each model's registry cost (analytic and
// per-foot together 1 ms + 2 us per output row, MuJoCo 10 us per step), rendering 5 ms per frame.
double expectedCaseCostS(const WorkEstimate& w);

// Assigns every case to a shard 0..n_shards-1, balancing the summed cost: longest processing time
// first (cases sorted by cost, descending, ties by index; each to the least loaded shard, ties to
// the lowest shard). Deterministic: every process of a sharded run computes the same assignment.
std::vector<int> assignShards(const std::vector<double>& cost, int n_shards);

// Which cases of each experiment of a suite belong to shard K of N: one assignment over all cases of
// all members (in suite order), so the shards of a suite are balanced as a whole. [experiment][case].
std::vector<std::vector<char>> shardMembership(const std::vector<Experiment>& suite, ShardSpec shard);

// `tailsim merge SHARD_DIR... --out DIR`: joins the result folders of the shards of one run (same
// experiment file, each `tailsim run EXP --shard K/N --out SHARD_DIR`) into DIR, identical to the
// folder one process would have written (measured wall times aside: they are the shards'). DIR is
// built under a temporary name next to it and renamed when whole; it must not exist or be empty.
// Fails (nothing at DIR) when the shards come from different inputs or a case is in none of them.
struct MergeStats {
  int shards = 0, cases = 0, files_copied = 0;
  int stop_signal = 0;  // SIGINT, SIGTERM or SIGHUP stopped the merge: nothing written to --out (0: none)
};
MergeStats mergeShards(const std::vector<std::string>& shard_dirs, const std::string& out_dir, int threads,
                       bool allow_other_build = false);

}  // namespace tailsim
