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

#include "models/mujoco/mjcf_generator.h"
#include "results/columns.h"
#include "models/mujoco/mujoco_handles.h"
#include "rendering/ffmpeg_writer.h"
#include "rendering/gl_context.h"
#include "rendering/replay.h"
#include "common/palette.h"
#include "common/work_limits.h"
#include "common/number_text.h"
#include "common/units.h"

namespace tailsim {

namespace {

namespace fs = std::filesystem;

// ---------------------------------------------------------------- checks

// The declared limits of every render setting (render_settings.h), the same the loader applies.
void checkSettings(const RenderSettings& s) {
  try {
    settings::validateFields(s, "render.");
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(std::string("render settings: ") + e.what());
  }
}

std::string requireFfmpeg(const RenderSettings& s) {
  const std::string exe = findExecutable(s.ffmpeg);
  if (exe.empty()) {
    if (s.ffmpeg.find('/') != std::string::npos)
      throw std::runtime_error("rendering: ffmpeg not found at " + s.ffmpeg +
                               "; install ffmpeg (scripts/setup.sh) or fix the path");
    const char* path = std::getenv("PATH");
    throw std::runtime_error("rendering: '" + s.ffmpeg + "' not found on PATH (" + (path ? path : "unset") +
                             "); install ffmpeg (scripts/setup.sh installs the Debian package) or put its "
                             "folder on PATH");
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

// Colours of the models, the same as in every plot (common/palette.h): MuJoCo vermillion (its
// own geoms, solid), analytic blue (an outline ghost).
constexpr Rgb kMujocoRgb = rgbOf(kMujocoColor);
constexpr Rgb kAnalyticRgb = rgbOf(kAnalyticColor);

// One ghost edge: an opaque capsule of radius r from a to b.
void addEdge(mjvScene& scn, const mjtNum* cam, double r, const mjtNum a[3], const mjtNum b[3]) {
  if (scn.ngeom >= scn.maxgeom) return;
  static constexpr float kRgba[4] = {kAnalyticRgb.r, kAnalyticRgb.g, kAnalyticRgb.b, 1.0f};
  mjvGeom* geom = scn.geoms + scn.ngeom;
  mjv_initGeom(geom, mjGEOM_CAPSULE, nullptr, nullptr, nullptr, kRgba);
  mjv_makeConnector(geom, mjGEOM_CAPSULE, r, a[0], a[1], a[2], b[0], b[1], b[2]);
  geom->category = mjCAT_DECOR;
  geom->specular = 0.1f;
  geom->camdist = static_cast<float>(mju_dist3(cam, std::array<mjtNum, 3>{geom->pos[0], geom->pos[1], geom->pos[2]}.data()));
  ++scn.ngeom;
}

// The analytic model as an outline (wireframe) ghost: the 12 edges of its body box and, per tail
// link, the outline of the link seen from above (two sides and the two ends), lines of radius
// line_r. The box is kGrow larger than the model's torso and the tail outline lies on top of the
// model's tail, one line width outside it: where both models agree, the outline frames the
// vermillion MuJoCo model instead of covering it.
void addGhost(mjvScene& scn, const GhostShape& g, const RobotParams& robot, const PlanarState& s, double line_r) {
  const mjtNum cam[3] = {0.5 * (scn.camera[0].pos[0] + scn.camera[1].pos[0]),
                         0.5 * (scn.camera[0].pos[1] + scn.camera[1].pos[1]),
                         0.5 * (scn.camera[0].pos[2] + scn.camera[1].pos[2])};
  const double c = std::cos(s.phi), sn = std::sin(s.phi);
  constexpr double kGrow = 0.006;  // [m]
  const double hx = g.body_half[0] + kGrow, hy = g.body_half[1] + kGrow, hz = g.body_half[2] + kGrow;
  const double cx = s.x + c * g.body_offset[0] - sn * g.body_offset[1];
  const double cy = s.y + sn * g.body_offset[0] + c * g.body_offset[1];
  auto corner = [&](int i, mjtNum p[3]) {  // i: bit 0 x, bit 1 y, bit 2 z
    const double lx = (i & 1 ? hx : -hx), ly = (i & 2 ? hy : -hy);
    p[0] = cx + c * lx - sn * ly;
    p[1] = cy + sn * lx + c * ly;
    p[2] = g.body_z + (i & 4 ? hz : -hz);
  };
  for (int i = 0; i < 8; ++i)
    for (int bit = 1; bit < 8; bit <<= 1)
      if (!(i & bit)) {
        mjtNum a[3], b[3];
        corner(i, a);
        corner(i | bit, b);
        addEdge(scn, cam, line_r, a, b);
      }
  const PlanarTailPose tail = planarTailPose(robot, s);
  const double w = g.tail_radius + line_r;  // half width of the link outline
  const double z = g.tail_z + g.tail_radius + line_r;
  for (size_t i = 0; i + 1 < tail.joints.size(); ++i) {
    const double ux = std::cos(tail.link_yaw[i]), uy = std::sin(tail.link_yaw[i]);
    const double x0 = tail.joints[i][0], y0 = tail.joints[i][1], x1 = tail.joints[i + 1][0], y1 = tail.joints[i + 1][1];
    const mjtNum p[4][3] = {{x0 - uy * w, y0 + ux * w, z}, {x1 - uy * w, y1 + ux * w, z},
                            {x1 + uy * w, y1 - ux * w, z}, {x0 + uy * w, y0 - ux * w, z}};
    for (int e = 0; e < 4; ++e) addEdge(scn, cam, line_r, p[e], p[(e + 1) % 4]);
  }
}

// The heading: a grey line along the body's heading at the start (phi0) and a dark line along its
// heading now, both from the quadruped COM, `length` long, at height z (just above the body's top,
// so the top camera sees them): a turn of a few degrees shows as the angle between them (the tip
// moves length * dphi: 7 deg over 0.2 m is 2.4 cm, some 15 px at the default size).
void addHeading(mjvScene& scn, const PlanarState& s, double phi0, double length, double z, double r) {
  const auto add = [&](int type, const float rgba[4], double yaw, double radius) {
    if (scn.ngeom >= scn.maxgeom) return;
    mjvGeom* geom = scn.geoms + scn.ngeom;
    mjv_initGeom(geom, type, nullptr, nullptr, nullptr, rgba);
    mjv_makeConnector(geom, type, radius, s.x, s.y, z, s.x + length * std::cos(yaw), s.y + length * std::sin(yaw), z);
    geom->category = mjCAT_DECOR;
    ++scn.ngeom;
  };
  static constexpr float kStart[4] = {0.55f, 0.55f, 0.55f, 1.0f}, kNow[4] = {0.08f, 0.08f, 0.08f, 1.0f};
  add(mjGEOM_CAPSULE, kStart, phi0, r);
  add(mjGEOM_CAPSULE, kNow, s.phi, r);
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
    // A neutral grey checker: the models' colours (vermillion, blue) stand out on it.
    const int tex = m->mat_texid[mat];
    if (tex >= 0) {
      const int end = tex + 1 < m->ntex ? m->tex_adr[tex + 1] : m->ntexdata;
      for (int i = m->tex_adr[tex]; i + 2 < end; i += 3) {
        const double lum = (m->tex_rgb[i] + m->tex_rgb[i + 1] + m->tex_rgb[i + 2]) / (3.0 * 255.0);
        const auto grey = static_cast<mjtByte>(std::clamp(255.0 * (0.45 + 1.2 * lum), 0.0, 255.0));
        m->tex_rgb[i] = m->tex_rgb[i + 1] = m->tex_rgb[i + 2] = grey;
      }
    }
  }
  // The MuJoCo model in its plot colour, vermillion: the tail links alternate full and lighter
  // vermillion (the joints show), the torso and legs are a light tint of it, the feet stay dark.
  const int root = mj_name2id(m, mjOBJ_BODY, mjcf::kQuadrupedBody);
  for (int i = 0; i < m->ngeom; ++i) {
    const int b = m->geom_bodyid[i];
    if (root < 0 || m->body_rootid[b] != root || m->geom_type[i] == mjGEOM_SPHERE) continue;
    const bool tail = b != root;
    const float mix = tail ? ((b - root) % 2 ? 0.0f : 0.25f) : (m->geom_type[i] == mjGEOM_BOX ? 0.45f : 0.3f);
    float* rgba = m->geom_rgba + 4 * i;
    rgba[0] = kMujocoRgb.r + mix * (1.0f - kMujocoRgb.r);
    rgba[1] = kMujocoRgb.g + mix * (1.0f - kMujocoRgb.g);
    rgba[2] = kMujocoRgb.b + mix * (1.0f - kMujocoRgb.b);
    rgba[3] = 1.0f;
    m->geom_matid[i] = -1;
  }
}

// The frame's layout: the 3-D scene on the left under a title strip, a panel on the right with
// the text (time, tail phase), the colour key (one label per model, in its colour) and the
// inset plot of phi(t). The panel is wide enough for its text in the context's font.
struct FrameLayout {
  mjrRect scene, title, panel, key[2], inset;
};

int textWidth(const mjrContext& con, const std::string& s) {
  int w = 0;
  for (unsigned char ch : s) w += ch < 127 ? con.charWidth[ch] : con.charWidth[static_cast<int>('x')];
  return w;
}

FrameLayout frameLayout(int W, int H, const mjrContext& con, const std::vector<std::string>& labels) {
  FrameLayout L;
  const int ch = con.charHeight, pad = std::max(4, ch / 3);
  int need = textWidth(con, "heading change +000.0 deg") + 2 * pad;
  for (const std::string& l : labels) need = std::max(need, textWidth(con, l + "  +000.00 deg") + 2 * pad);
  const int pw = std::min(W / 2, std::max(static_cast<int>(std::lround(0.3 * W)), need));
  const int title_h = ch + 2 * pad;
  L.scene = {0, 0, W - pw, H - title_h};
  L.title = {0, H - title_h, W - pw, title_h};
  L.panel = {W - pw, 0, pw, H};
  const int text_h = 3 * ch + 4 * pad;  // three lines of text at the top of the panel
  const int lab_h = ch + 2 * pad;
  L.key[0] = {W - pw + pad, H - text_h - lab_h, pw - 2 * pad, lab_h};
  L.key[1] = {W - pw + pad, L.key[0].bottom - pad - lab_h, pw - 2 * pad, lab_h};
  L.inset = {W - pw + pad / 2, pad, pw - pad, std::max(1, L.key[1].bottom - 2 * pad)};
  return L;
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
  double look_offset[2] = {0, 0};  // camera target minus the quadruped COM (world x, y)
  double line_r = 0.002;           // ghost outline radius [m] (~1.3 px)
  double phi0 = 0.0;               // heading at the first frame [rad]
  double heading_length = 0.2;     // heading line and arrow [m]
  double heading_z = 0.2;          // their height [m]
  FrameLayout layout2d;
  std::unique_ptr<mjvFigure> figure;  // the phi(t) inset (mjvFigure is ~1 MB: on the heap)
  std::vector<uint8_t> pixels;
};

// Every point of the robot's outline (body box corners, tail joints) relative to the tracked
// quadruped COM, over the frames of the video, for both models: the camera frames this box.
struct Extent {
  double lo[2] = {1e300, 1e300}, hi[2] = {-1e300, -1e300};
  void add(double x, double y) {
    lo[0] = std::min(lo[0], x), hi[0] = std::max(hi[0], x);
    lo[1] = std::min(lo[1], y), hi[1] = std::max(hi[1], y);
  }
};

Extent robotExtent(const RenderRig& r, const RobotParams& robot, double t0, double t1) {
  Extent e;
  const int samples = 200;
  for (int k = 0; k <= samples; ++k) {
    const double t = t0 + (t1 - t0) * k / samples;
    const PlanarState ref = r.mujoco->at(t);
    for (const std::optional<PlanarStateSampler>* smp : {&r.mujoco, &r.analytic}) {
      if (!*smp) continue;
      const PlanarState s = (*smp)->at(t);
      const double c = std::cos(s.phi), sn = std::sin(s.phi);
      for (int i = 0; i < 4; ++i) {
        const double lx = r.ghost.body_offset[0] + (i & 1 ? 1 : -1) * r.ghost.body_half[0];
        const double ly = r.ghost.body_offset[1] + (i & 2 ? 1 : -1) * r.ghost.body_half[1];
        e.add(s.x + c * lx - sn * ly - ref.x, s.y + sn * lx + c * ly - ref.y);
      }
      for (const auto& j : planarTailPose(robot, s).joints) {
        const double rr = r.ghost.tail_radius;
        e.add(j[0] - ref.x - rr, j[1] - ref.y - rr);
        e.add(j[0] - ref.x + rr, j[1] - ref.y + rr);
      }
    }
  }
  return e;
}

}  // namespace

RoundTicks roundTicks(double lo, double hi, int intervals) {
  RoundTicks t;
  const double raw = (hi - lo) / std::max(1, intervals);
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  double step = 10.0 * p;
  for (double m : {1.0, 2.0, 2.5, 5.0})
    if (m * p >= raw * (1.0 - 1e-9)) {
      step = m * p;
      break;
    }
  // Snap to the step's grid, allowing for the last bits of a range that ends on a tick.
  t.lo = std::floor(lo / step + 1e-9) * step;
  t.hi = std::ceil(hi / step - 1e-9) * step;
  t.count = static_cast<int>(std::lround((t.hi - t.lo) / step)) + 1;
  t.step = step;
  t.decimals = std::max(0, static_cast<int>(std::ceil(-std::log10(step) - 1e-9)));
  if (std::abs(step * std::pow(10.0, t.decimals) - std::round(step * std::pow(10.0, t.decimals))) > 1e-6) ++t.decimals;  // 2.5
  return t;
}

namespace {

// The phi(t) inset: both models' phi over the shown time, the time cursor (the figure's
// selection line) set per frame.
void setupFigure(RenderRig& r, double t0, double t1, int height) {
  r.figure = std::make_unique<mjvFigure>();
  mjvFigure& f = *r.figure;
  mjv_defaultFigure(&f);
  f.flg_legend = 0;  // the colour key above the inset says which line is which model
  f.flg_ticklabel[0] = f.flg_ticklabel[1] = 1;
  f.flg_extend = 0;
  f.flg_selection = 1;
  f.linewidth = std::max(1.5f, 2.0f * height / 480.0f);
  f.gridsize[0] = 3;
  f.gridsize[1] = 3;
  const float fig_rgba[4] = {0.10f, 0.10f, 0.12f, 1.0f}, pane_rgba[4] = {0.16f, 0.16f, 0.18f, 1.0f};
  std::copy(fig_rgba, fig_rgba + 4, f.figurergba);
  std::copy(pane_rgba, pane_rgba + 4, f.panergba);
  f.gridrgb[0] = f.gridrgb[1] = f.gridrgb[2] = 0.35f;
  f.textrgb[0] = f.textrgb[1] = f.textrgb[2] = 0.92f;
  std::snprintf(f.title, sizeof f.title, "phi [deg]");
  std::snprintf(f.xlabel, sizeof f.xlabel, "t [s]");
  std::snprintf(f.xformat, sizeof f.xformat, "%%.2f");
  std::snprintf(f.yformat, sizeof f.yformat, "%%.0f");
  std::snprintf(f.minwidth, sizeof f.minwidth, "-00");
  double lo = 0.0, hi = 0.0;
  int line = 0;
  for (const auto& [smp, rgb] : {std::pair{&r.mujoco, kMujocoRgb}, std::pair{&r.analytic, kAnalyticRgb}}) {
    if (!*smp) continue;
    // About one point per 2 px: llvmpipe drops sub-pixel segments of wide lines (a flat line
    // drawn from 400 points over 160 px came out dotted).
    const int pts = std::clamp(r.layout2d.inset.width / 2, 50, mjMAXLINEPNT);
    for (int k = 0; k < pts; ++k) {
      const double t = t0 + (t1 - t0) * k / (pts - 1);
      const double phi = units::degrees((*smp)->at(t).phi);
      f.linedata[line][2 * k] = static_cast<float>(t);
      f.linedata[line][2 * k + 1] = static_cast<float>(phi);
      lo = std::min(lo, phi), hi = std::max(hi, phi);
    }
    f.linepnt[line] = pts;
    f.linergb[line][0] = rgb.r, f.linergb[line][1] = rgb.g, f.linergb[line][2] = rgb.b;
    ++line;
  }
  // Ranges from round tick to round tick, one grid line per tick: labels at round numbers.
  const RoundTicks tx = roundTicks(t0, std::max(t1, t0 + 1e-6), 4), ty = roundTicks(lo, std::max(hi, lo + 1.0), 3);
  f.range[0][0] = static_cast<float>(tx.lo);
  f.range[0][1] = static_cast<float>(tx.hi);
  f.range[1][0] = static_cast<float>(ty.lo);
  f.range[1][1] = static_cast<float>(ty.hi);
  f.gridsize[0] = tx.count;
  f.gridsize[1] = ty.count;
  std::snprintf(f.xformat, sizeof f.xformat, "%%.%df", tx.decimals);
  std::snprintf(f.yformat, sizeof f.yformat, "%%.%df", ty.decimals);
}

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
  const double t0 = r.mujoco->startTime();
  const double t1 = s.duration_s > 0.0 ? std::min(r.mujoco->endTime(), t0 + s.duration_s) : r.mujoco->endTime();

  // Tracking camera: it follows the quadruped COM (set per frame) with a fixed offset; the
  // offset and distance frame the box that every point of both models' outlines stays in over
  // the video (relative to the COM), with a 10 % margin, in the scene part of the frame.
  r.layout2d = frameLayout(s.width, s.height, r.gl->context(),
                           {in.solid_label + " (solid)", in.outline_label + " (outline)"});
  const double aspect = static_cast<double>(r.layout2d.scene.width) / r.layout2d.scene.height;
  const Extent e = robotExtent(r, *in.robot, t0, t1);
  r.look_offset[0] = 0.5 * (e.lo[0] + e.hi[0]);
  r.look_offset[1] = 0.5 * (e.lo[1] + e.hi[1]);
  // 10 % margin: the robot keeps clear of the title strip and the frame's edges.
  const double half_w = 0.5 * (e.hi[0] - e.lo[0]) * 1.1 + 0.01, half_h = 0.5 * (e.hi[1] - e.lo[1]) * 1.1 + 0.01;
  const double tan_half = std::tan(units::radians(0.5 * m->vis.global.fovy));
  mjv_defaultFreeCamera(m, &r.cam);
  r.cam.type = mjCAMERA_FREE;
  if (s.camera == RenderCamera::kTop) {
    // Straight down; azimuth 0: world x (the body's heading at phi = 0) up on screen, world y to
    // the left, so the long axis of body + tail runs along the frame's height. A rotation of the
    // view, not a mirror: a positive (counter-clockwise) phi turns the body counter-clockwise.
    r.cam.elevation = -90.0;
    r.cam.azimuth = 0.0;
    r.cam.distance = std::max(half_w, half_h / aspect) / tan_half;
  } else {
    // From behind and to the right (-x, -y), 35 deg down: the tail is in front of the body. The
    // box's circumscribed circle fits the smaller field of view.
    r.cam.elevation = -35.0;
    r.cam.azimuth = 45.0;
    // The body's top counts too: seen at an angle it rises above its footprint.
    const double top = r.ghost.body_z + r.ghost.body_half[2];
    r.cam.distance = 1.05 * std::sqrt(half_w * half_w + half_h * half_h + top * top) / (tan_half * std::min(1.0, aspect));
  }
  // Scale at the robot: metres per pixel. The ghost's lines are ~1.3 px in radius, the model's
  // tail at least 4 px (visual only: the renderer's own copy of the model).
  const double m_per_px = 2.0 * r.cam.distance * tan_half / r.layout2d.scene.height;
  r.line_r = 1.3 * m_per_px;
  const double tail_r = std::max(r.ghost.tail_radius, 4.0 * m_per_px);
  for (int i = 0; i < m->ngeom; ++i) {
    const int b = m->geom_bodyid[i];
    if (b == r.layout.root_body || m->body_rootid[b] != r.layout.root_body) continue;
    if (m->geom_type[i] != mjGEOM_CAPSULE && m->geom_type[i] != mjGEOM_CYLINDER) continue;
    r.model->geom_size[3 * i] = tail_r;
    r.model->geom_rbound[i] = std::max(r.model->geom_rbound[i], tail_r + r.model->geom_size[3 * i + 1]);
  }
  r.ghost.tail_radius = tail_r;
  r.phi0 = r.mujoco->at(t0).phi;
  r.heading_length = 0.9 * r.ghost.body_half[0];
  r.heading_z = r.ghost.body_z + r.ghost.body_half[2] + 0.01;
  setupFigure(r, t0, t1, s.height);
  r.pixels.resize(static_cast<size_t>(s.width) * s.height * 3);
}

using Clock = std::chrono::steady_clock;
double since(Clock::time_point& t0) {
  const Clock::time_point t1 = Clock::now();
  const double s = std::chrono::duration<double>(t1 - t0).count();
  t0 = t1;
  return s;
}

// Width in pixels of `text` in MuJoCo's normal font (a byte outside its table counts as 'M').
int textWidthPx(const mjrContext& con, const std::string& text) {
  int w = 0;
  for (const char ch : text) {
    const unsigned char u = static_cast<unsigned char>(ch);
    w += con.charWidth[u > 32 && u < 127 ? u : 'M'];
  }
  return w;
}

// `text` cut to fit `width_px` in the normal font, ending in "..." when cut (a long swept case's
// title ran under the slow-motion factor on the same strip).
std::string fitText(const mjrContext& con, const std::string& text, int width_px) {
  if (textWidthPx(con, text) <= width_px) return text;
  std::string cut = text;
  while (!cut.empty() && textWidthPx(con, cut + "...") > width_px) {
    cut.pop_back();
    while (!cut.empty() && (static_cast<unsigned char>(cut.back()) & 0xC0) == 0x80) cut.pop_back();  // whole UTF-8
    if (!cut.empty() && static_cast<unsigned char>(cut.back()) >= 0xC0) cut.pop_back();
  }
  return cut + "...";
}

// The 2-D parts of a frame: title strip, text, colour key and the phi(t) inset with its cursor.
void drawPanel(RenderRig& r, const RenderInputs& in, const RenderSettings& s, double t, const PlanarState& st,
               const std::optional<PlanarState>& ghost) {
  const FrameLayout& L = r.layout2d;
  const mjrContext& con = r.gl->context();
  char buf[256];
  mjr_rectangle(L.panel, 0.10f, 0.10f, 0.12f, 1.0f);
  mjr_rectangle(L.title, 0.10f, 0.10f, 0.12f, 1.0f);
  std::snprintf(buf, sizeof buf, "%gx slow motion", s.slowmo);
  // The title gets the strip less the factor and a gap of four widths of 'M' (the overlay's margins).
  // A title "experiment case" too long for it keeps the case, which tells the frames apart.
  const int title_px = L.title.width - textWidthPx(con, buf) - 4 * con.charWidth['M'];
  const std::size_t space = in.title.find(' ');
  const std::string title =
      fitText(con, textWidthPx(con, in.title) > title_px && space != std::string::npos ? in.title.substr(space + 1) : in.title,
              title_px);
  mjr_overlay(mjFONT_NORMAL, mjGRID_TOPLEFT, L.title, title.c_str(), nullptr, &con);
  mjr_overlay(mjFONT_NORMAL, mjGRID_TOPRIGHT, L.title, buf, nullptr, &con);
  std::string text = "t = ";
  std::snprintf(buf, sizeof buf, "%.3f s", t);
  text += buf;
  // The phases of Eq. 20 exist only for split-cycle strokes (a spline has no t1 or t2).
  if (in.trajectory && splitCycleStrokes(*in.trajectory))
    text += std::string("\ntail ") + tailPhaseName(tailPhase(*in.trajectory, t));
  std::snprintf(buf, sizeof buf, "\nheading change %+.1f deg", (st.phi - r.phi0) * units::kDegPerRad);
  text += buf;
  mjr_overlay(mjFONT_NORMAL, mjGRID_TOPLEFT, L.panel, text.c_str(), nullptr, &con);
  // Colour key: one label per model in its colour, with its phi now.
  std::snprintf(buf, sizeof buf, "%s (solid)  %+.2f deg", in.solid_label.c_str(), st.phi * units::kDegPerRad);
  mjr_label(L.key[0], mjFONT_NORMAL, buf, kMujocoRgb.r, kMujocoRgb.g, kMujocoRgb.b, 1.0f, 1, 1, 1, &con);
  if (ghost) {
    std::snprintf(buf, sizeof buf, "%s (outline)  %+.2f deg", in.outline_label.c_str(), ghost->phi * units::kDegPerRad);
    mjr_label(L.key[1], mjFONT_NORMAL, buf, kAnalyticRgb.r, kAnalyticRgb.g, kAnalyticRgb.b, 1.0f, 1, 1, 1, &con);
  }
  r.figure->selection = static_cast<float>(t);
  mjr_figure(L.inset, r.figure.get(), &con);
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
  r.cam.lookat[0] = st.x + r.look_offset[0];
  r.cam.lookat[1] = st.y + r.look_offset[1];
  r.cam.lookat[2] = r.look_z;
  mjvScene& scn = r.gl->scene();
  mjv_updateScene(m, d, &r.opt, nullptr, &r.cam, mjCAT_ALL, &scn);
  addHeading(scn, st, r.phi0, r.heading_length, r.heading_z, r.line_r * 1.5);
  std::optional<PlanarState> ghost;
  if (r.analytic) {
    ghost = r.analytic->at(t);
    addGhost(scn, r.ghost, *in.robot, *ghost, r.line_r);
  }
  if (stats) stats->pose_s += since(tic);
  const FrameLayout& L = r.layout2d;
  const mjrContext& con = r.gl->context();
  mjr_render(L.scene, &scn, &con);
  drawPanel(r, in, s, t, st, ghost);
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
  if (!mujoco.has(col::kT) || mujoco.numRows() == 0)
    throw std::invalid_argument("rendering: the MuJoCo time series has no t_s rows");
  FrameTimes f;
  f.t_start = mujoco.values(col::kT).front();
  f.t_end = mujoco.values(col::kT).back();
  if (s.duration_s > 0.0) f.t_end = std::min(f.t_end, f.t_start + s.duration_s);
  const double frames = renderFrameCount(f.t_end - f.t_start, s);
  if (!(frames >= 1.0 && frames <= kRenderMaxFrames))
    throw std::runtime_error("render settings: the video would have " + formatG(frames) + " frames, more than " +
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
    mjr_render(rig.layout2d.scene, &scn, &rig.gl->context());
    mjr_readPixels(rig.pixels.data(), nullptr, vp, &rig.gl->context());
  }
  const double sec = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return frames / sec;
}

}  // namespace tailsim
