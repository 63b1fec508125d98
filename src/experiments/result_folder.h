// Result folders as the runner finds and leaves them: which experiment's results a folder holds,
// which of its files are tailsim's (DIR/.tailsim-manifest), claiming a folder for an experiment or
// a suite, clearing it (--fresh) and removing a killed run's temporary files
// (docs/ARCHITECTURE.md "Result folder").
#pragma once

#include <filesystem>
#include <string>
#include <vector>
#include <nlohmann/json.hpp>

#include "experiments/experiment_loader.h"

namespace tailsim {
namespace runner {

// The folder of a result folder holding the HDF5 parts of finished cases (time_series.h5.d).
inline const char* const kH5Parts = "time_series.h5.d";

// A JSON file of the folder (discarded, not an exception, when absent or not JSON; an error when
// it is not a regular file or too large: readResultFile).
nlohmann::json readJsonFile(const std::filesystem::path& p);
// Whether p is a regular file itself (a symlink to one is not).
bool isRegularFile(const std::filesystem::path& p);

// Writes DIR/<name> (a top-level file of the folder) when what is there is tailsim's; else refuses.
void writeOwnFile(const std::filesystem::path& root, const std::string& name, const std::string& text);
// Refuses (std::runtime_error, as writeOwnFile) when any of DIR/<names> is there and not tailsim's:
// checked before a run writes anything, so a refused run leaves the folder as it was.
void refuseForeignFiles(const std::filesystem::path& root, const std::vector<std::string>& names);
// Deletes the entries tailsim writes into a result folder, and in them only what tailsim writes;
// anything else stays (named on stderr).
void clearResultFolder(const std::filesystem::path& root);
// The experiment file a folder's results come from (e's file, or the original named by the
// results of a folder re-run from its own copy).
std::string recordedSource(const Experiment& e);
// Refuses to put e's results into a folder that holds another experiment's or a suite's; with
// fresh, removes them first.
void claimFolder(const Experiment& e, const std::filesystem::path& root, bool fresh);
// Refuses a suite's top folder holding a single experiment's results; with fresh, removes them.
void claimSuiteFolder(const std::filesystem::path& root, bool fresh);
// Removes the temporary files of earlier runs whose process is gone; returns how many.
int removeStaleTemps(const std::filesystem::path& root);

}  // namespace runner
}  // namespace tailsim
