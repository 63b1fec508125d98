// The files of `tailsim trust` (experiments/trust_study.h): its table, CSV and figure.
#pragma once

#include <string>
#include <vector>

#include "experiments/trust_study.h"

namespace tailsim {

// DIR/trust.md (one table a case: phi_net, its change against the default, its error against the
// reference, the wall time of each setting; what the answer depends on; the verdict), DIR/trust.csv
// (one row a case and setting) and DIR/plots/trust.png/.svg (error against the reference over the
// wall time, one point a setting). Files are tailsim's own (the folder's manifest, atomic writes);
// the caller holds DIR's FolderLock. Returns the paths written.
std::vector<std::string> writeTrust(const std::vector<TrustStudy>& studies, const Experiment& e, const std::string& dir);

// The files writeTrust writes, relative to DIR (checked before any work: claimDesignFolder).
std::vector<std::string> trustOutputs();

}  // namespace tailsim
