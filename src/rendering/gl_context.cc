#include "rendering/gl_context.h"

#include <GL/osmesa.h>

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
}  // namespace

OsMesaContext::OsMesaContext(int width, int height) {
  if (width <= 0 || height <= 0) throw std::invalid_argument("OSMesa context needs a positive size");
  std::lock_guard<std::mutex> lock(glSetupMutex());
  OSMesaContext ctx = OSMesaCreateContextExt(OSMESA_RGBA, 24, 8, 0, nullptr);
  if (!ctx)
    throw std::runtime_error(
        "rendering: cannot create an OSMesa (software OpenGL) context; is libosmesa6 installed "
        "(scripts/setup.sh)?");
  buffer_.resize(static_cast<size_t>(width) * height * 4);
  if (!OSMesaMakeCurrent(ctx, buffer_.data(), GL_UNSIGNED_BYTE, width, height)) {
    OSMesaDestroyContext(ctx);
    throw std::runtime_error("rendering: cannot make the OSMesa context current at " + std::to_string(width) +
                             "x" + std::to_string(height));
  }
  ctx_ = ctx;
}

OsMesaContext::~OsMesaContext() {
  std::lock_guard<std::mutex> lock(glSetupMutex());
  if (ctx_) OSMesaDestroyContext(static_cast<OSMesaContext>(ctx_));
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
  const int fontscale = height >= 1400 ? mjFONTSCALE_200 : height >= 900 ? mjFONTSCALE_150 : mjFONTSCALE_100;
  mjr_makeContext(m, &con_, fontscale);
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
