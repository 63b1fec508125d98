// `tailsim merge SHARD... --out DIR`: join the result folders of `run --shard K/N`.
#include <csignal>
#include <cstdio>
#include <memory>

#include "app/commands.h"
#include "experiments/sharding.h"
#include "common/work_limits.h"

namespace tailsim {

void addMergeCommand(CLI::App& app, int& exit_code) {
  struct Args {
    std::vector<std::string> dirs;
    std::string out;
    int threads = 0;
    bool allow_other_build = false;
  };
  auto a = std::make_shared<Args>();
  auto* merge = app.add_subcommand("merge", "join the result folders of `run --shard K/N` into one folder");
  merge->add_option("shards", a->dirs, "the shards' result folders")->required()->check(CLI::ExistingDirectory);
  merge->add_option("--out", a->out, "the merged result folder (new or empty)")->required()->check(nonEmptyPath());
  merge->add_option("--threads", a->threads, "worker threads (default 0: all cores; at most 1024)")
      ->check(CLI::Range(0, limits::kMaxThreads));
  merge->add_flag("--allow-other-build", a->allow_other_build,
                  "keep cases computed by another tailsim version or commit (warned, recorded in summary.json) instead of refusing them");
  merge->callback([a, &exit_code] {
    const MergeStats m = mergeShards(a->dirs, a->out, a->threads, a->allow_other_build);
    if (m.stop_signal > 0) {
      const char* name = m.stop_signal == SIGTERM ? "SIGTERM" : m.stop_signal == SIGHUP ? "SIGHUP" : "Ctrl-C";
      std::fprintf(stderr, "interrupted by %s: merge stopped, nothing written to %s; run the same command again\n", name,
                   a->out.c_str());
      exit_code = 128 + m.stop_signal;
      return;
    }
    std::printf("merged %d shards: %d cases, %d files into %s\n", m.shards, m.cases, m.files_copied, a->out.c_str());
    exit_code = kExitOk;
  });
}

}  // namespace tailsim
