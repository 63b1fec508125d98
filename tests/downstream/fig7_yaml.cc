// Downstream use of tailsim::experiments: load an experiment file, run its cases in memory.
#include <tailsim/experiments/experiment_loader.h>
#include <tailsim/experiments/experiment_runner.h>

#include <cstdio>
#include <exception>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: fig7_yaml EXPERIMENT.yaml\n");
    return 2;
  }
  try {
    const tailsim::Experiment e = tailsim::loadExperiment(argv[1]);
    for (const tailsim::ExperimentCase& c : e.cases)
      for (const tailsim::RunResult& r : tailsim::runCase(c))
        std::printf("%s %s phi_net_deg %.6f\n", c.name.c_str(), r.summary.model.c_str(), r.summary.phi_net_deg);
  } catch (const std::exception& ex) {
    std::fprintf(stderr, "%s\n", ex.what());
    return 1;
  }
  return 0;
}
