#include "rendering/video_renderer.h"

#include <mujoco/mujoco.h>
#include <unistd.h>

#include <chrono>
#include <condition_variable>
#include <deque>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <vector>

#include "mujoco_model/mjcf_generator.h"
#include "mujoco_model/mujoco_handles.h"
#include "rendering/ffmpeg_writer.h"
#include "rendering/gl_context.h"
#include "rendering/replay.h"
#include "results/work_limits.h"

namespace tailsim {

namespace {

namespace fs = std::filesystem;

// ---------------------------------------------------------------- checks

std::string fmtG(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%g", v);
  return b;
}

void checkSettings(const RenderSettings& s) {
  auto bad = [](const std::string& what) { throw std::runtime_error("render settings: " + what); };
  const std::string size = std::to_string(s.width) + "x" + std::to_string(s.height);
  if (s.width < kRenderMinSize || s.height < kRenderMinSize || s.width > kRenderMaxSize || s.height > kRenderMaxSize)
    bad("width and height must lie in [" + std::to_string(kRenderMinSize) + ", " + std::to_string(kRenderMaxSize) +
        "], got " + size);
  if (s.width % 2 || s.height % 2) bad("width and height must be even (H.264 yuv420p), got " + size);
  if (s.fps < kRenderMinFps || s.fps > kRenderMaxFps)
    bad("fps must lie in [" + std::to_string(kRenderMinFps) + ", " + std::to_string(kRenderMaxFps) + "], got " +
        std::to_string(s.fps));
  if (!(s.slowmo >= kRenderMinSlowmo && s.slowmo <= kRenderMaxSlowmo))
    bad("slowmo must lie in [" + fmtG(kRenderMinSlowmo) + ", " + fmtG(kRenderMaxSlowmo) + "], got " + fmtG(s.slowmo));
  if (!(s.duration_s >= 0.0) || !std::isfinite(s.duration_s)) bad("duration_s must be >= 0 (0 = whole run)");
  if (s.camera != "top" && s.camera != "perspective")
    bad("camera must be top or perspective, got '" + s.camera + "'");
  if (s.msaa < 0 || s.msaa > kRenderMaxMsaa)
    bad("msaa must lie in [0, " + std::to_string(kRenderMaxMsaa) + "], got " + std::to_string(s.msaa));
  if (s.crf < kRenderMinCrf || s.crf > kRenderMaxCrf)
    bad("crf must lie in [" + std::to_string(kRenderMinCrf) + ", " + std::to_string(kRenderMaxCrf) + "], got " +
        std::to_string(s.crf));
}

std::string requireFfmpeg(const RenderSettings& s) {
  const std::string exe = findExecutable(s.ffmpeg);
  if (exe.empty()) {
    if (s.ffmpeg.find('/') != std::string::npos)
      throw std::runtime_error("rendering: ffmpeg not found at " + s.ffmpeg +
                               " (render.ffmpeg); install ffmpeg (scripts/setup.sh) or fix the path");
    const char* path = std::getenv("PATH");
    throw std::runtime_error("rendering: '" + s.ffmpeg + "' not found on PATH (" + (path ? path : "unset") +
                             "); install ffmpeg (scripts/setup.sh installs the Debian package) or set "
                             "render.ffmpeg to its full path");
  }
  return exe;
}

void requireWritableDir(const std::string& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir))
    throw std::runtime_error("rendering: output folder " + dir + " cannot be created: " +
                             (ec ? ec.message() : std::string("not a directory")));
  // Probe by creating a file: access(W_OK) says nothing useful for root or read-only mounts.
  std::string probe = (fs::path(dir) / ".tailsim-write-probe-XXXXXX").string();
  std::vector<char> buf(probe.begin(), probe.end());
  buf.push_back('\0');
  const int fd = ::mkstemp(buf.data());
  if (fd < 0)
    throw std::runtime_error("rendering: output folder " + dir + " is not writable: " + std::strerror(errno));
  ::close(fd);
  std::remove(buf.data());
}

// ---------------------------------------------------------------- model

// ---------------------------------------------------------------- ghost

// Shape of the ghost: taken from the MuJoCo model where it can be (so it overlays the model),
// else from RobotParams.
struct GhostShape {
  double body_half[3] = {0, 0, 0};  // box half sizes
  double body_offset[2] = {0, 0};   // box centre minus quadruped COM, body frame (x, y)
  double body_z = 0.1;              // box centre height
  double tail_z = 0.1;              // tail axis height
  double tail_radius = 0.012;
};

GhostShape ghostShape(const mjModel* m, mjData* d, const MujocoReplayLayout& L, const RobotParams& robot) {
  GhostShape g;
  // Body box: the largest box geom of the root body.
  int best = -1;
  double best_vol = 0.0;
  for (int i = 0; i < m->ngeom; ++i) {
    if (m->geom_bodyid[i] != L.root_body || m->geom_type[i] != mjGEOM_BOX) continue;
    const mjtNum* s = m->geom_size + 3 * i;
    if (s[0] * s[1] * s[2] > best_vol) best = i, best_vol = s[0] * s[1] * s[2];
  }
  if (best >= 0) {
    for (int k = 0; k < 3; ++k) g.body_half[k] = m->geom_size[3 * best + k];
    g.body_offset[0] = m->geom_pos[3 * best] - L.com_offset[0];
    g.body_offset[1] = m->geom_pos[3 * best + 1] - L.com_offset[1];
    g.body_z = d->geom_xpos[3 * best + 2];
  } else {
    g.body_half[0] = 0.5 * robot.quadruped.l_F_m + 0.05;
    g.body_half[1] = 0.5 * robot.quadruped.w_F_m;
    g.body_half[2] = 0.04;
    g.body_z = d->xipos[3 * L.root_body + 2];
  }
  g.tail_z = g.body_z;
  // Tail: height of joint 1's anchor, radius of the first capsule/cylinder in the tail bodies.
  if (!L.tail_qpos.empty()) {
    for (int j = 0; j < m->njnt; ++j) {
      if (m->jnt_qposadr[j] != L.tail_qpos[0]) continue;
      g.tail_z = d->xanchor[3 * j + 2];
      for (int i = 0; i < m->ngeom; ++i) {
        if (m->geom_bodyid[i] != m->jnt_bodyid[j]) continue;
        if (m->geom_type[i] == mjGEOM_CAPSULE || m->geom_type[i] == mjGEOM_CYLINDER) {
          g.tail_radius = m->geom_size[3 * i];
          break;
        }
      }
    }
  }
  return g;
}

void addGhost(mjvScene& scn, const GhostShape& g, const RobotParams& robot, const PlanarState& s) {
  static constexpr float kRgba[4] = {0.15f, 0.75f, 1.0f, 0.4f};      // tail: distinct cyan
  static constexpr float kBodyRgba[4] = {0.15f, 0.75f, 1.0f, 0.3f};  // body: the torso shows through
  const mjtNum cam[3] = {0.5 * (scn.camera[0].pos[0] + scn.camera[1].pos[0]),
                         0.5 * (scn.camera[0].pos[1] + scn.camera[1].pos[1]),
                         0.5 * (scn.camera[0].pos[2] + scn.camera[1].pos[2])};
  auto finish = [&](mjvGeom* geom) {
    geom->category = mjCAT_DECOR;
    geom->transparent = 1;
    geom->specular = 0.2f;
    geom->camdist = static_cast<float>(mju_dist3(cam, std::array<mjtNum, 3>{geom->pos[0], geom->pos[1], geom->pos[2]}.data()));
    ++scn.ngeom;
  };
  const double c = std::cos(s.phi), sn = std::sin(s.phi);
  // The ghost body is a shell kGrow larger than the model's torso: where both models agree it
  // wraps the model instead of z-fighting with it. The ghost tail is half as thick as the
  // model's and rides on top of it, so the model's orange tail stays visible around it.
  constexpr double kGrow = 0.006;  // [m]
  if (scn.ngeom < scn.maxgeom) {  // body box: centre p_Q + R_Q offset
    const mjtNum size[3] = {g.body_half[0] + kGrow, g.body_half[1] + kGrow, g.body_half[2] + kGrow};
    const mjtNum pos[3] = {s.x + c * g.body_offset[0] - sn * g.body_offset[1],
                           s.y + sn * g.body_offset[0] + c * g.body_offset[1], g.body_z};
    const mjtNum mat[9] = {c, -sn, 0, sn, c, 0, 0, 0, 1};
    mjvGeom* geom = scn.geoms + scn.ngeom;
    mjv_initGeom(geom, mjGEOM_BOX, size, pos, mat, kBodyRgba);
    finish(geom);
  }
  const PlanarTailPose tail = planarTailPose(robot, s);
  for (size_t i = 0; i + 1 < tail.joints.size() && scn.ngeom < scn.maxgeom; ++i) {
    mjvGeom* geom = scn.geoms + scn.ngeom;
    mjv_initGeom(geom, mjGEOM_CAPSULE, nullptr, nullptr, nullptr, kRgba);
    const double z = g.tail_z + g.tail_radius;
    mjv_makeConnector(geom, mjGEOM_CAPSULE, 0.5 * g.tail_radius, tail.joints[i][0], tail.joints[i][1], z,
                      tail.joints[i + 1][0], tail.joints[i + 1][1], z);
    finish(geom);
  }
}

// ---------------------------------------------------------------- scene

// Visual-only changes to the renderer's own compiled copy of the model (physics untouched):
// softer lights so the grey torso and the translucent ghost do not saturate to white, and a
// floor checker of 0.1 m squares so that translation shows under the tracking camera.
void adjustVisuals(mjModel* m) {
  m->vis.headlight.ambient[0] = m->vis.headlight.ambient[1] = m->vis.headlight.ambient[2] = 0.25f;
  m->vis.headlight.diffuse[0] = m->vis.headlight.diffuse[1] = m->vis.headlight.diffuse[2] = 0.3f;
  m->vis.headlight.specular[0] = m->vis.headlight.specular[1] = m->vis.headlight.specular[2] = 0.1f;
  for (int i = 0; i < m->nlight; ++i)
    for (int k = 0; k < 3; ++k) m->light_diffuse[3 * i + k] = std::min(m->light_diffuse[3 * i + k], 0.45f);
  const int floor = mj_name2id(m, mjOBJ_GEOM, mjcf::kFloorGeom);
  if (floor >= 0 && m->geom_matid[floor] >= 0) {
    const int mat = m->geom_matid[floor];
    // builtin checker: 2 x 2 squares per texture repeat; texuniform: repeats per metre.
    if (m->mat_texuniform[mat]) m->mat_texrepeat[2 * mat] = m->mat_texrepeat[2 * mat + 1] = 5.0f;
  }
}

// Everything one render needs, set up before the first frame. Members are destroyed in
// reverse order: the GL objects before the model.
struct RenderRig {
  ModelPtr model;
  DataPtr data;
  MujocoReplayLayout layout;
  std::optional<PlanarStateSampler> mujoco, analytic;
  std::optional<MjOffscreen> gl;
  mjvOption opt;
  mjvCamera cam;
  GhostShape ghost;
  double look_z = 0.1;
  std::vector<uint8_t> pixels;
};

void setupRig(RenderRig& r, const RenderInputs& in, const RenderSettings& s) {
  if (!in.robot || !in.mujoco) throw std::invalid_argument("rendering: RenderInputs needs robot and mujoco");
  const int n = in.robot->numLinks();
  r.mujoco.emplace(*in.mujoco, n, "MuJoCo");
  if (in.analytic && s.ghost) r.analytic.emplace(*in.analytic, n, "analytic");
  if (in.mjcf_xml.empty()) throw std::invalid_argument("rendering: RenderInputs.mjcf_xml is empty");
  r.model = loadModelFromXml(in.mjcf_xml);
  r.data = makeData(r.model.get());
  adjustVisuals(r.model.get());
  r.layout = findReplayLayout(r.model.get(), n);
  r.gl.emplace(r.model.get(), s.width, s.height, s.msaa, r.model->ngeom + 64 + 8 * n);
  mjvScene& scn = r.gl->scene();
  scn.flags[mjRND_SHADOW] = s.shadows;
  scn.flags[mjRND_REFLECTION] = s.reflections;
  mjv_defaultOption(&r.opt);
  r.opt.geomgroup[3] = 1;  // the feet (collision spheres, group 3) are part of the picture

  // Pose at the first sample to read the model's heights for the ghost and the camera.
  const mjModel* m = r.model.get();
  mjData* d = r.data.get();
  setReplayQpos(m, r.layout, r.mujoco->at(r.mujoco->startTime()), d->qpos);
  mj_kinematics(m, d);
  r.ghost = ghostShape(m, d, r.layout, *in.robot);
  r.look_z = r.ghost.body_z;

  // Tracking camera: it looks at the quadruped COM (set per frame); the distance keeps a circle
  // of the body plus the stretched tail in view whatever the yaw.
  const QuadrupedParams& q = in.robot->quadruped;
  double tail_len = 0.0;
  for (const TailLink& l : in.robot->tail) tail_len += l.length_m;
  const double body_r = std::hypot(std::max(r.ghost.body_half[0], 0.5 * q.l_F_m), std::max(r.ghost.body_half[1], 0.5 * q.w_F_m));
  const double radius = std::max(q.d_Q2B_m + tail_len, body_r) + 0.05;
  const double half_fov = 0.5 * m->vis.global.fovy * M_PI / 180.0;
  mjv_defaultFreeCamera(m, &r.cam);
  r.cam.type = mjCAMERA_FREE;
  if (s.camera == "top") {
    r.cam.elevation = -90.0;  // straight down; azimuth 90: world x right, world y up on screen
    r.cam.azimuth = 90.0;
    r.cam.distance = 1.15 * radius / std::tan(half_fov) + r.look_z;
  } else {
    r.cam.elevation = -35.0;
    r.cam.azimuth = 45.0;  // from behind and to the right (-x, -y): the tail is in front of the body
    r.cam.distance = 1.35 * radius / std::tan(half_fov);
  }
  r.pixels.resize(static_cast<size_t>(s.width) * s.height * 3);
}

using Clock = std::chrono::steady_clock;
double since(Clock::time_point& t0) {
  const Clock::time_point t1 = Clock::now();
  const double s = std::chrono::duration<double>(t1 - t0).count();
  t0 = t1;
  return s;
}

// Poses the model (and ghost) for simulated time t and renders into the off-screen buffer.
void renderFrame(RenderRig& r, const RenderInputs& in, const RenderSettings& s, double t,
                 RenderStats* stats = nullptr) {
  Clock::time_point tic = Clock::now();
  const mjModel* m = r.model.get();
  mjData* d = r.data.get();
  const PlanarState st = r.mujoco->at(t);
  setReplayQpos(m, r.layout, st, d->qpos);
  mj_kinematics(m, d);
  mj_comPos(m, d);
  mj_camlight(m, d);
  r.cam.lookat[0] = st.x;
  r.cam.lookat[1] = st.y;
  r.cam.lookat[2] = r.look_z;
  mjvScene& scn = r.gl->scene();
  mjv_updateScene(m, d, &r.opt, nullptr, &r.cam, mjCAT_ALL, &scn);
  std::optional<PlanarState> ghost;
  if (r.analytic) {
    ghost = r.analytic->at(t);
    addGhost(scn, r.ghost, *in.robot, *ghost);
  }
  if (stats) stats->pose_s += since(tic);
  const mjrRect vp = r.gl->viewport();
  mjr_render(vp, &scn, &r.gl->context());

  // On-frame text.
  char left[512], right[512];
  const double rad2deg = 180.0 / M_PI;
  std::string l = in.title.empty() ? "" : in.title + "\n";
  std::string v = in.title.empty() ? "" : " \n";
  std::snprintf(left, sizeof(left), "t\nphi MuJoCo\n");
  std::snprintf(right, sizeof(right), "%.3f s\n%+.2f deg\n", t, st.phi * rad2deg);
  l += left;
  v += right;
  if (ghost) {
    std::snprintf(right, sizeof(right), "%+.2f deg\n", ghost->phi * rad2deg);
    l += "phi analytic (ghost)\n";
    v += right;
  }
  if (in.trajectory) {
    l += "tail\n";
    v += std::string(tailPhaseName(tailPhase(*in.trajectory, t))) + "\n";
  }
  l.pop_back();
  v.pop_back();
  mjr_overlay(mjFONT_NORMAL, mjGRID_TOPLEFT, vp, l.c_str(), v.c_str(), &r.gl->context());
  std::snprintf(left, sizeof(left), "%gx slow motion", s.slowmo);
  mjr_overlay(mjFONT_NORMAL, mjGRID_BOTTOMRIGHT, vp, left, nullptr, &r.gl->context());
  if (stats) stats->render_s += since(tic);
}

void checkMujocoWarnings(const mjData* d) {
  for (int i = 0; i < mjNWARNING; ++i)
    if (d->warning[i].number > 0)
      throw std::runtime_error("rendering: MuJoCo warning " + std::to_string(i) + " raised while rendering");
}

struct FrameTimes {
  double t_start, t_end;
  long frames;
};

FrameTimes frameTimes(const TimeSeries& mujoco, const RenderSettings& s) {
  if (!mujoco.has("t_s") || mujoco.numRows() == 0)
    throw std::invalid_argument("rendering: the MuJoCo time series has no t_s rows");
  FrameTimes f;
  f.t_start = mujoco.values("t_s").front();
  f.t_end = mujoco.values("t_s").back();
  if (s.duration_s > 0.0) f.t_end = std::min(f.t_end, f.t_start + s.duration_s);
  const double frames = renderFrameCount(f.t_end - f.t_start, s);
  if (!(frames >= 1.0 && frames <= kRenderMaxFrames))
    throw std::runtime_error("render settings: the video would have " + fmtG(frames) + " frames, more than " +
                             std::to_string(static_cast<long>(kRenderMaxFrames)) + " (lower fps, slowmo or duration_s)");
  f.frames = static_cast<long>(frames);
  return f;
}

// Hands frames from the GL thread to a writer thread (which feeds ffmpeg), so rendering frame
// k+1 overlaps encoding frame k. A fixed set of buffers bounds the memory; the writer's first
// exception is rethrown to the GL thread. The destructor stops and joins the writer (no frame
// is written after an exception).
class FramePipeline {
 public:
  using Consumer = std::function<void(long frame, const uint8_t* rows_bottom_up)>;
  FramePipeline(size_t frame_bytes, int buffers, Consumer consume) : consume_(std::move(consume)) {
    for (int i = 0; i < buffers; ++i) {
      store_.emplace_back(frame_bytes);
      free_.push_back(store_.back().data());
    }
    writer_ = std::thread([this] { writerLoop(); });
  }
  ~FramePipeline() {
    {
      std::lock_guard<std::mutex> lk(mu_);
      stop_ = true;
    }
    cv_.notify_all();
    writer_.join();
  }
  FramePipeline(const FramePipeline&) = delete;
  FramePipeline& operator=(const FramePipeline&) = delete;

  // A free buffer (blocks while the writer is behind).
  uint8_t* acquire() {
    std::unique_lock<std::mutex> lk(mu_);
    cv_.wait(lk, [this] { return !free_.empty() || error_; });
    if (error_) std::rethrow_exception(error_);
    uint8_t* b = free_.front();
    free_.pop_front();
    return b;
  }
  void submit(long frame, uint8_t* buffer) {
    {
      std::lock_guard<std::mutex> lk(mu_);
      ready_.push_back({frame, buffer});
    }
    cv_.notify_all();
  }
  // Waits until every submitted frame is consumed; rethrows the writer's exception.
  void drain() {
    std::unique_lock<std::mutex> lk(mu_);
    cv_.wait(lk, [this] { return (ready_.empty() && !busy_) || error_; });
    if (error_) std::rethrow_exception(error_);
  }

 private:
  void writerLoop() {
    std::unique_lock<std::mutex> lk(mu_);
    for (;;) {
      cv_.wait(lk, [this] { return !ready_.empty() || stop_; });
      if (stop_ || error_) return;
      const auto [frame, buf] = ready_.front();
      ready_.pop_front();
      busy_ = true;
      lk.unlock();
      std::exception_ptr err;
      try {
        consume_(frame, buf);
      } catch (...) {
        err = std::current_exception();
      }
      lk.lock();
      busy_ = false;
      free_.push_back(buf);
      if (err) error_ = err;
      cv_.notify_all();
      if (error_) return;
    }
  }

  Consumer consume_;
  std::vector<std::vector<uint8_t>> store_;
  std::deque<uint8_t*> free_;
  std::deque<std::pair<long, uint8_t*>> ready_;
  std::mutex mu_;
  std::condition_variable cv_;
  bool stop_ = false, busy_ = false;
  std::exception_ptr error_;
  std::thread writer_;
};

}  // namespace

void checkRenderPrerequisites(const RenderSettings& settings, const std::string& out_dir) {
  checkSettings(settings);
  const std::string exe = requireFfmpeg(settings);
  const std::string probe = probeFfmpeg(exe);
  if (!probe.empty()) throw std::runtime_error("rendering: ffmpeg (" + exe + ") does not work: " + probe);
  requireWritableDir(out_dir);
  OsMesaContext probe_gl(settings.width, settings.height);
}

RenderStats renderVideo(const RenderInputs& in, const RenderSettings& settings, const std::string& mp4_path,
                        const std::string& png_path) {
  const auto t_call = Clock::now();
  checkSettings(settings);
  const std::string exe = requireFfmpeg(settings);
  if (!in.robot || !in.mujoco) throw std::invalid_argument("rendering: RenderInputs needs robot and mujoco");
  const FrameTimes ft = frameTimes(*in.mujoco, settings);
  const double dt_frame = 1.0 / (settings.fps * settings.slowmo);  // simulated seconds per frame

  // Poster: the frame at joint 1's peak speed (t1, mid-swing), else the middle of the video.
  long poster = ft.frames / 2;
  if (in.trajectory && !in.trajectory->joints.empty()) {
    const double t1 = in.trajectory->joints[0].t1();
    if (t1 >= ft.t_start && t1 <= ft.t_end) poster = std::lround((t1 - ft.t_start) / dt_frame);
  }
  poster = std::min(std::max(poster, 0L), ft.frames - 1);

  RenderStats st;
  st.width = settings.width;
  st.height = settings.height;
  st.sim_start_s = ft.t_start;
  st.poster_time_s = ft.t_start + poster * dt_frame;
  // ffmpeg first: its start-up (~0.2 s of loading libraries) overlaps the model compile and
  // the GL setup. On any exception below its destructor kills it and removes the temporaries.
  std::vector<FfmpegOutput> outputs = {{FfmpegOutput::Kind::kMp4, mp4_path, 0}};
  if (!png_path.empty()) outputs.push_back({FfmpegOutput::Kind::kPng, png_path, poster});
  FfmpegSink video(exe, settings.width, settings.height, {settings.fps, settings.crf, settings.preset}, outputs);
  RenderRig rig;
  setupRig(rig, in, settings);
  // Warm-up render (not encoded): llvmpipe compiles its shaders on the first draw (~0.1 s).
  renderFrame(rig, in, settings, ft.t_start);
  mjr_readPixels(rig.pixels.data(), nullptr, rig.gl->viewport(), &rig.gl->context());
  const auto t0 = Clock::now();
  st.setup_s = std::chrono::duration<double>(t0 - t_call).count();
  const int w = settings.width, h = settings.height;
  std::vector<uint8_t> flipped(static_cast<size_t>(w) * h * 3);
  double encode_s = 0.0;  // writer thread only, read after drain()
  {
    // Writer thread: flip rows (mjr_readPixels is bottom-up), feed ffmpeg.
    FramePipeline pipe(flipped.size(), 3, [&](long, const uint8_t* bottom_up) {
      Clock::time_point tic = Clock::now();
      const size_t row = static_cast<size_t>(w) * 3;
      for (int y = 0; y < h; ++y) std::memcpy(flipped.data() + row * y, bottom_up + row * (h - 1 - y), row);
      video.writeFrame(flipped.data());
      encode_s += since(tic);
    });
    for (long k = 0; k < ft.frames; ++k) {
      const double t = ft.t_start + k * dt_frame;
      renderFrame(rig, in, settings, t, &st);
      Clock::time_point tic = Clock::now();
      uint8_t* buf = pipe.acquire();
      st.encode_s += since(tic);  // GL thread blocked because the encoder is behind
      mjr_readPixels(buf, nullptr, rig.gl->viewport(), &rig.gl->context());
      st.read_s += since(tic);
      pipe.submit(k, buf);
      st.sim_end_s = t;
      if (k == 0) st.first_frame_s = std::chrono::duration<double>(Clock::now() - t0).count();
    }
    checkMujocoWarnings(rig.data.get());
    if (mjr_getError()) throw std::runtime_error("rendering: OpenGL error while rendering");
    Clock::time_point tic = Clock::now();
    pipe.drain();
    video.finish();
    st.encode_s += since(tic);
  }
  st.writer_s = encode_s;
  // Both files complete: publish them (any failure above leaves neither under its final name).
  video.commit();
  st.frames = ft.frames;
  st.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  st.fps = st.frames / st.seconds;
  return st;
}

double benchBareRenderLoop(const RenderInputs& in, const RenderSettings& settings, int frames) {
  checkSettings(settings);
  RenderRig rig;
  setupRig(rig, in, settings);
  const FrameTimes ft = frameTimes(*in.mujoco, settings);
  renderFrame(rig, in, settings, 0.5 * (ft.t_start + ft.t_end));  // pose the scene once (and warm up)
  mjr_readPixels(rig.pixels.data(), nullptr, rig.gl->viewport(), &rig.gl->context());
  mjvScene& scn = rig.gl->scene();
  const mjrRect vp = rig.gl->viewport();
  const auto t0 = std::chrono::steady_clock::now();
  for (int k = 0; k < frames; ++k) {
    mjr_render(vp, &scn, &rig.gl->context());
    mjr_readPixels(rig.pixels.data(), nullptr, vp, &rig.gl->context());
  }
  const double sec = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return frames / sec;
}

}  // namespace tailsim
