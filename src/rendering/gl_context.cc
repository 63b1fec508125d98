#include "rendering/gl_context.h"

#include <GL/osmesa.h>  // types and constants only: libOSMesa is loaded at run time (see osMesa())
#include <dlfcn.h>

#include <algorithm>
#include <mutex>
#include <stdexcept>
#include <string>

namespace tailsim {

namespace {
// Context creation and MuJoCo's GL setup (mjr_makeContext loads GL entry points into MuJoCo's
// process-wide function table) are serialized: cases render on several worker threads. Frames
// themselves render concurrently, each thread in its own OSMesa context.
std::mutex& glSetupMutex() {
  static std::mutex m;
  return m;
}

// libOSMesa (software OpenGL: Mesa's llvmpipe, which pulls in LLVM, z3 and ICU) is loaded the first
// time a context is made, not at process start: a run that renders nothing starts without it
// (~14 ms of dynamic loading saved per process). RTLD_GLOBAL makes its GL entry points
// visible to MuJoCo's loader (mjr_makeContext looks up OSMesaGetProcAddress in the process).
// The handle is never closed: MuJoCo keeps the GL function pointers for the life of the process.
struct OsMesaApi {
  decltype(&OSMesaCreateContextExt) createContextExt = nullptr;
  decltype(&OSMesaMakeCurrent) makeCurrent = nullptr;
  decltype(&OSMesaDestroyContext) destroyContext = nullptr;
};

OsMesaApi loadOsMesa() {
  void* lib = nullptr;
  std::string why;
  for (const char* name : {"libOSMesa.so.8", "libOSMesa.so"}) {
    lib = dlopen(name, RTLD_NOW | RTLD_GLOBAL);
    if (lib) break;
    if (const char* e = dlerror()) why = e;
  }
  if (!lib)
    throw std::runtime_error("rendering: cannot load libOSMesa (software OpenGL; " + why +
                             "); is libosmesa6 installed (scripts/setup.sh)?");
  OsMesaApi api;
  api.createContextExt = reinterpret_cast<decltype(api.createContextExt)>(dlsym(lib, "OSMesaCreateContextExt"));
  api.makeCurrent = reinterpret_cast<decltype(api.makeCurrent)>(dlsym(lib, "OSMesaMakeCurrent"));
  api.destroyContext = reinterpret_cast<decltype(api.destroyContext)>(dlsym(lib, "OSMesaDestroyContext"));
  if (!api.createContextExt || !api.makeCurrent || !api.destroyContext)
    throw std::runtime_error("rendering: libOSMesa lacks OSMesaCreateContextExt/MakeCurrent/DestroyContext");
  return api;
}

// Loaded once per process (thread-safe static initialisation); a failed load is retried next time.
const OsMesaApi& osMesa() {
  static const OsMesaApi api = loadOsMesa();
  return api;
}
}  // namespace

bool osMesaLoaded() {
  void* lib = dlopen("libOSMesa.so.8", RTLD_NOW | RTLD_NOLOAD);  // takes a reference when mapped
  if (lib) dlclose(lib);
  return lib != nullptr;
}

OsMesaContext::OsMesaContext(int width, int height) {
  if (width <= 0 || height <= 0) throw std::invalid_argument("OSMesa context needs a positive size");
  std::lock_guard<std::mutex> lock(glSetupMutex());
  const OsMesaApi& api = osMesa();
  OSMesaContext ctx = api.createContextExt(OSMESA_RGBA, 24, 8, 0, nullptr);
  if (!ctx)
    throw std::runtime_error(
        "rendering: cannot create an OSMesa (software OpenGL) context; is libosmesa6 installed "
        "(scripts/setup.sh)?");
  buffer_.resize(static_cast<size_t>(width) * height * 4);
  if (!api.makeCurrent(ctx, buffer_.data(), GL_UNSIGNED_BYTE, width, height)) {
    api.destroyContext(ctx);
    throw std::runtime_error("rendering: cannot make the OSMesa context current at " + std::to_string(width) +
                             "x" + std::to_string(height));
  }
  ctx_ = ctx;
}

OsMesaContext::~OsMesaContext() {
  std::lock_guard<std::mutex> lock(glSetupMutex());
  if (ctx_) osMesa().destroyContext(static_cast<OSMesaContext>(ctx_));
}

MjOffscreen::MjOffscreen(mjModel* m, int width, int height, int msaa, int maxgeom)
    : gl_(width, height), width_(width), height_(height) {
  std::lock_guard<std::mutex> lock(glSetupMutex());
  m->vis.global.offwidth = std::max(m->vis.global.offwidth, width);
  m->vis.global.offheight = std::max(m->vis.global.offheight, height);
  m->vis.quality.offsamples = msaa;
  mjv_defaultScene(&scn_);
  mjv_makeScene(m, &scn_, maxgeom);
  mjr_defaultContext(&con_);
  const int fontscale = height >= 1400 ? mjFONTSCALE_200 : height >= 700 ? mjFONTSCALE_150 : mjFONTSCALE_100;
  try {
    mjr_makeContext(m, &con_, fontscale);  // MuJoCo's errors throw (mujoco_handles.h)
  } catch (const std::exception& e) {
    mjr_freeContext(&con_);
    mjv_freeScene(&scn_);
    throw std::runtime_error("rendering: cannot make a " + std::to_string(width) + " x " + std::to_string(height) +
                             " off-screen framebuffer with " + std::to_string(msaa) +
                             " samples (" + e.what() + "): lower render.width, render.height or render.msaa");
  }
  mjr_setBuffer(mjFB_OFFSCREEN, &con_);
  if (con_.currentBuffer != mjFB_OFFSCREEN) {
    mjr_freeContext(&con_);
    mjv_freeScene(&scn_);
    throw std::runtime_error("rendering: MuJoCo's off-screen framebuffer is not supported by this OpenGL context");
  }
}

MjOffscreen::~MjOffscreen() {
  std::lock_guard<std::mutex> lock(glSetupMutex());
  mjr_freeContext(&con_);
  mjv_freeScene(&scn_);
}

}  // namespace tailsim
