// RAII ownership of MuJoCo 2.2 objects and exception-based error reporting.
//
// Errors: compile errors come back from mj_loadXML in a caller-owned buffer and are thrown as
// MujocoError with MuJoCo's text. Run-time trouble (NaN/Inf, singular inertia, full contact
// buffers) is read from the per-mjData warning counters d->warning[i]. MuJoCo 2.2's two
// process-wide hooks, mju_user_warning and mju_user_error, get tailsim's handlers, installed once
// per process by installMujocoMessageHandlers (which every function here that loads a model or
// makes data calls first): a warning's text goes to the calling thread's MujocoMessages, an error
// (e.g. out of arena memory) is thrown as MujocoError instead of ending the process.
#pragma once

#include <memory>
#include <stdexcept>
#include <string>

#include <mujoco/mujoco.h>

namespace tailsim {

class MujocoError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct MjModelDeleter {
  void operator()(mjModel* m) const { mj_deleteModel(m); }
};
struct MjDataDeleter {
  void operator()(mjData* d) const { mj_deleteData(d); }
};
using ModelPtr = std::unique_ptr<mjModel, MjModelDeleter>;
using DataPtr = std::unique_ptr<mjData, MjDataDeleter>;

// MuJoCo reports through two global hooks (mju_user_warning, mju_user_error); without them it
// appends to MUJOCO_LOG.TXT in the current directory (and exits on an error). tailsim installs its
// own handlers once per process (thread-safe, before the first model is loaded): a warning goes
// to the innermost MujocoMessages of the calling thread (stderr when there is none), an error is
// thrown as MujocoError ("MuJoCo error: ...") to the caller of the MuJoCo function.
void installMujocoMessageHandlers();

// Collects the MuJoCo warnings raised on this thread while it lives (scopes nest).
class MujocoMessages {
 public:
  MujocoMessages();
  ~MujocoMessages();
  MujocoMessages(const MujocoMessages&) = delete;
  MujocoMessages& operator=(const MujocoMessages&) = delete;
  const std::string& text() const { return text_; }  // "MuJoCo warning: ...; MuJoCo warning: ..."
  void add(const std::string& message);

 private:
  std::string text_;
  MujocoMessages* outer_;
};

// Compiles an MJCF document held in memory (through a private mjVFS, no temporary file).
// Throws MujocoError with MuJoCo's compiler message on failure.
ModelPtr loadModelFromXml(const std::string& xml);
// Loads an MJCF file from disk (throws MujocoError naming the file).
ModelPtr loadModelFromFile(const std::string& path);
// mj_makeData; throws MujocoError if it returns null.
DataPtr makeData(const mjModel* m);

// Total of d->warning[i].number over all warning types.
int warningCount(const mjData* d);
// "" if no warning occurred, else each warning type that occurred with its count and the info
// MuJoCo attached to its last occurrence (d->warning[i].lastinfo, e.g. the index of the bad DOF):
// "mjWARN_BADQACC x3 (info 7); mjWARN_CONTACTFULL x1 (info 100)".
std::string describeWarnings(const mjData* d);

// Id lookups that throw MujocoError naming the missing element.
int bodyId(const mjModel* m, const std::string& name);
int jointId(const mjModel* m, const std::string& name);
int geomId(const mjModel* m, const std::string& name);
int actuatorId(const mjModel* m, const std::string& name);

}  // namespace tailsim
