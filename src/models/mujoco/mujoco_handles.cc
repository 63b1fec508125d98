#include "models/mujoco/mujoco_handles.h"

#include <cstdio>
#include <cstring>
#include <mutex>
#include <sstream>
#include <vector>

namespace tailsim {

namespace {

// mjVFS is ~40 kB; keep it on the heap and always release its file buffers.
struct VfsDeleter {
  void operator()(mjVFS* v) const {
    mj_deleteVFS(v);
    delete v;
  }
};

const char* warningName(int i) {
  static const char* kNames[mjNWARNING] = {"mjWARN_INERTIA",  "mjWARN_CONTACTFULL", "mjWARN_CNSTRFULL",
                                           "mjWARN_VGEOMFULL", "mjWARN_BADQPOS",     "mjWARN_BADQVEL",
                                           "mjWARN_BADQACC",  "mjWARN_BADCTRL"};
  return (i >= 0 && i < mjNWARNING) ? kNames[i] : "mjWARN_?";
}

int lookup(const mjModel* m, mjtObj type, const std::string& name, const char* what) {
  const int id = mj_name2id(m, type, name.c_str());
  if (id < 0) throw MujocoError(std::string("MuJoCo model has no ") + what + " named '" + name + "'");
  return id;
}

thread_local MujocoMessages* tl_messages = nullptr;

void onMujocoWarning(const char* msg) {
  const std::string m = std::string("MuJoCo warning: ") + (msg ? msg : "");
  if (tl_messages) tl_messages->add(m);
  else std::fprintf(stderr, "%s\n", m.c_str());
}

// MuJoCo must not continue after an error: the exception unwinds to the tailsim code that called
// into MuJoCo (runCase turns it into a failed run).
void onMujocoError(const char* msg) { throw MujocoError(std::string("MuJoCo error: ") + (msg ? msg : "")); }

}  // namespace

void installMujocoMessageHandlers() {
  static std::once_flag once;
  std::call_once(once, [] {
    mju_user_warning = onMujocoWarning;
    mju_user_error = onMujocoError;
  });
}

MujocoMessages::MujocoMessages() : outer_(tl_messages) {
  installMujocoMessageHandlers();
  tl_messages = this;
}

MujocoMessages::~MujocoMessages() { tl_messages = outer_; }

void MujocoMessages::add(const std::string& message) {
  if (text_.size() > 4000) return;  // a bounded record: the first messages say what went wrong
  if (!text_.empty()) text_ += "; ";
  text_ += message;
}

ModelPtr loadModelFromXml(const std::string& xml) {
  installMujocoMessageHandlers();
  std::unique_ptr<mjVFS, VfsDeleter> vfs(new mjVFS);
  mj_defaultVFS(vfs.get());
  const char* kName = "tailsim_model.xml";
  if (mj_makeEmptyFileVFS(vfs.get(), kName, static_cast<int>(xml.size())) != 0)
    throw MujocoError("MuJoCo VFS: cannot allocate the in-memory MJCF file");
  const int idx = mj_findFileVFS(vfs.get(), kName);
  std::memcpy(vfs->filedata[idx], xml.data(), xml.size());
  char err[1024] = "";
  mjModel* m = mj_loadXML(kName, vfs.get(), err, sizeof(err));
  if (!m) throw MujocoError(std::string("MuJoCo could not compile the generated MJCF: ") + err);
  return ModelPtr(m);
}

ModelPtr loadModelFromFile(const std::string& path) {
  installMujocoMessageHandlers();
  char err[1024] = "";
  mjModel* m = mj_loadXML(path.c_str(), nullptr, err, sizeof(err));
  if (!m) throw MujocoError("MuJoCo could not load " + path + ": " + err);
  return ModelPtr(m);
}

DataPtr makeData(const mjModel* m) {
  installMujocoMessageHandlers();
  mjData* d = mj_makeData(m);
  if (!d) throw MujocoError("mj_makeData failed");
  return DataPtr(d);
}

int warningCount(const mjData* d) {
  int n = 0;
  for (int i = 0; i < mjNWARNING; ++i) n += d->warning[i].number;
  return n;
}

std::string describeWarnings(const mjData* d) {
  std::ostringstream os;
  for (int i = 0; i < mjNWARNING; ++i) {
    if (d->warning[i].number == 0) continue;
    if (os.tellp() > 0) os << "; ";
    os << warningName(i) << " x" << d->warning[i].number << " (info " << d->warning[i].lastinfo << ")";
  }
  return os.str();
}

int bodyId(const mjModel* m, const std::string& name) { return lookup(m, mjOBJ_BODY, name, "body"); }
int jointId(const mjModel* m, const std::string& name) { return lookup(m, mjOBJ_JOINT, name, "joint"); }
int geomId(const mjModel* m, const std::string& name) { return lookup(m, mjOBJ_GEOM, name, "geom"); }
int actuatorId(const mjModel* m, const std::string& name) {
  return lookup(m, mjOBJ_ACTUATOR, name, "actuator");
}

}  // namespace tailsim
