// RAII for the off-screen OpenGL state: an OSMesa context (software GL, no display needed)
// made current on the calling thread, and MuJoCo's mjvScene + mjrContext on top of it.
#pragma once

#include <mujoco/mujoco.h>

#include <vector>

namespace tailsim {

// True when libOSMesa is mapped into this process. It is loaded by the first OsMesaContext, never at
// start-up, so a process that renders nothing does not pay for it (tests check this).
bool osMesaLoaded();

// OSMesaCreateContextExt(OSMESA_RGBA, 24 depth, 8 stencil) + OSMesaMakeCurrent on a w x h buffer.
// Throws std::runtime_error when OSMesa cannot create or bind the context.
class OsMesaContext {
 public:
  OsMesaContext(int width, int height);
  ~OsMesaContext();
  OsMesaContext(const OsMesaContext&) = delete;
  OsMesaContext& operator=(const OsMesaContext&) = delete;

 private:
  void* ctx_ = nullptr;  // OSMesaContext
  std::vector<unsigned char> buffer_;
};

// mjvScene + mjrContext bound to the off-screen buffer of an OSMesa context. Sets
// m->vis.global.offwidth/offheight (>= width, height) and vis.quality.offsamples = msaa on the
// model before mjr_makeContext. Throws when the off-screen buffer is not available.
class MjOffscreen {
 public:
  MjOffscreen(mjModel* m, int width, int height, int msaa, int maxgeom);
  ~MjOffscreen();
  MjOffscreen(const MjOffscreen&) = delete;
  MjOffscreen& operator=(const MjOffscreen&) = delete;

  mjvScene& scene() { return scn_; }
  mjrContext& context() { return con_; }
  mjrRect viewport() const { return {0, 0, width_, height_}; }

 private:
  OsMesaContext gl_;  // first member: destroyed last
  mjvScene scn_;
  mjrContext con_;
  int width_, height_;
};

}  // namespace tailsim
