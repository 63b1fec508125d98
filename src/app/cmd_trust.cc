// `tailsim trust`: the convergence and sensitivity study of an experiment's MuJoCo results
// (experiments/trust_study.h, docs/accuracy.md "tailsim trust").
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

#include "app/commands.h"
#include "experiments/experiment_loader.h"
#include "experiments/experiment_runner.h"
#include "experiments/trust_study.h"
#include "experiments/robot_model_cases.h"
#include "plotting/trust_report.h"

namespace tailsim {

void addTrustCommand(CLI::App& app, int& exit_code) {
  struct Options {
    std::string experiment, out, only_case;
  };
  auto o = std::make_shared<Options>();
  auto* cmd = app.add_subcommand(
      "trust", "convergence and sensitivity study of an experiment's MuJoCo results (timestep, contact, stroke jitter)");
  cmd->add_option("experiment", o->experiment, "experiment YAML (every simulate case is studied)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", o->out, "result folder for trust.md, trust.csv and plots/trust.png")
      ->required()
      ->check(CLI::Validator(
          [](std::string& v) { return v.empty() ? std::string("is empty: give a folder name") : std::string(); }, "PATH"));
  cmd->add_option("--case", o->only_case, "study this case only");
  cmd->callback([o, &exit_code] {
    try {
      const Experiment e = loadExperiment(o->experiment);  // every error before any work
      refuseRobotModels({e}, "trust");
      TrustOptions opt;
      opt.only_case = o->only_case;
      requireCase({e}, o->experiment, o->only_case);  // before the folder is made
      const FolderLock lock(o->out);
      refuseRunResults(o->out, "trust");
      claimDesignFolder(o->out, trustOutputs());
      const std::vector<TrustStudy> studies = runTrustStudy(e, opt);
      for (const TrustStudy& st : studies) {
        const TrustRow* d = st.row("default");
        const TrustRow* r = st.row("reference");
        std::printf("%s: MuJoCo phi_net %s deg, reference %s deg\n", st.case_name.c_str(),
                    d && d->ok ? (std::to_string(d->phi_net_deg) +
                                  (std::isfinite(d->uncertainty_deg) ? " +- " + std::to_string(d->uncertainty_deg)
                                                                     : std::string(" (uncertainty not estimated: "
                                                                                   "its check run failed)")))
                                     .c_str()
                               : "failed",
                    r && r->ok ? std::to_string(r->phi_net_deg).c_str() : "failed");
        if (!st.verdict.empty()) std::printf("  verdict: %s\n", st.verdict.c_str());
      }
      for (const std::string& f : writeTrust(studies, e, o->out)) std::printf("%s\n", f.c_str());
      exit_code = 0;
    } catch (const std::exception& ex) {
      std::fprintf(stderr, "error: %s\n", ex.what());
      exit_code = 1;
    }
  });
}

}  // namespace tailsim
