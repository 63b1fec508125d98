// Headless video renders. Checks the replay kinematics against MuJoCo's own
// kinematics, the encoded files against ffprobe, and the error paths (no file under the final
// name on any failure).
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "models/mujoco/mjcf_generator.h"
#include "models/analytic/analytic_simulation.h"
#include "models/mujoco/mujoco_handles.h"
#include "models/mujoco/mujoco_simulation.h"
#include "rendering/ffmpeg_writer.h"
#include "rendering/replay.h"
#include "rendering/video_renderer.h"

namespace tailsim {
namespace {

namespace fs = std::filesystem;
constexpr double kDeg = M_PI / 180.0;

// A fresh, empty folder under the build tree's temp area, removed at the end of the test.
class TempDir {
 public:
  TempDir() {
    std::string tmpl = (fs::temp_directory_path() / "tailsim-render-test-XXXXXX").string();
    std::vector<char> buf(tmpl.begin(), tmpl.end());
    buf.push_back('\0');
    if (!::mkdtemp(buf.data())) throw std::runtime_error("mkdtemp failed");
    path_ = buf.data();
  }
  ~TempDir() {
    if (std::getenv("TAILSIM_KEEP_TEST_DIRS")) return;
    std::error_code ec;
    fs::permissions(path_, fs::perms::owner_all, fs::perm_options::add, ec);
    fs::remove_all(path_, ec);
  }
  std::string operator/(const std::string& name) const { return (fs::path(path_) / name).string(); }
  const std::string& str() const { return path_; }
  std::vector<std::string> files() const {
    std::vector<std::string> out;
    for (const auto& e : fs::directory_iterator(path_)) out.push_back(e.path().filename().string());
    return out;
  }

 private:
  std::string path_;
};

std::string run(const std::string& cmd) {
  std::unique_ptr<FILE, int (*)(FILE*)> p(popen(cmd.c_str(), "r"), pclose);
  std::string out;
  char buf[4096];
  size_t n;
  while ((n = fread(buf, 1, sizeof(buf), p.get())) > 0) out.append(buf, n);
  return out;
}

// A synthetic replay: the tail follows its trajectory exactly, the body yaws and drifts along
// smooth curves. The renderer replays series and runs no physics, so any series will do.
TimeSeries syntheticSeries(const TailTrajectory& traj, int n, double duration, double dt, double phi_scale_deg,
                           double x_drift_m) {
  TimeSeries ts;
  ts.addColumn("t_s");
  ts.addColumn("x_m");
  ts.addColumn("y_m");
  ts.addColumn("phi_deg");
  for (int i = 1; i <= n; ++i) ts.addColumn("theta" + std::to_string(i) + "_deg");
  std::vector<JointState> js;
  for (int k = 0; k * dt <= duration + 1e-12; ++k) {
    const double t = k * dt, u = t / duration;
    traj.evaluate(t, js);
    std::vector<double> row = {t, x_drift_m * u, 0.3 * x_drift_m * u * u, phi_scale_deg * (3 * u * u - 2 * u * u * u)};
    for (const JointState& j : js) row.push_back(j.theta / kDeg);
    ts.appendRow(row);
  }
  return ts;
}

struct Case {
  RobotParams robot;
  TailTrajectory traj;
  TimeSeries mujoco, analytic;
  std::string xml;
};

// Paper Fig. 7 trajectory (Sec. 4.3) on an n-link tail, split by Eq. 25 for n > 1.
Case makeCase(int n, double duration = 0.4) {
  Case c;
  c.robot = paperRobot(n);
  for (int i = 0; i < n; ++i) {
    SplitCycleParams p;
    p.theta0_rad = n == 1 ? 0.0 : 180.0 / (n + 1) * kDeg;
    p.dtheta_rad = n == 1 ? -90 * kDeg : -360.0 / (n + 1) * kDeg;
    p.dT_s = 0.25;
    p.w_ss = 0.25;
    c.traj.joints.emplace_back(p);
  }
  c.mujoco = syntheticSeries(c.traj, n, duration, 1e-3, 20.0, 0.05);
  c.analytic = syntheticSeries(c.traj, n, duration, 1e-3, 60.0, -0.05);
  c.xml = generateMjcf(c.robot, MujocoSettings{}, Effects{});
  return c;
}

RenderSettings smallSettings() {
  RenderSettings s;
  s.enabled = true;
  s.width = 320;
  s.height = 240;
  s.fps = 10;
  s.slowmo = 1.0;
  s.msaa = 0;
  return s;
}

// Decodes an image or video frame to raw RGB with ffmpeg (independent of our encoder path).
std::vector<uint8_t> decodeRgb(const std::string& path, int frame = 0) {
  const std::string cmd = "ffmpeg -v error -i '" + path + "' -vf 'select=eq(n\\," + std::to_string(frame) +
                          ")' -frames:v 1 -f rawvideo -pix_fmt rgb24 - 2>/dev/null";
  const std::string s = run(cmd);
  return std::vector<uint8_t>(s.begin(), s.end());
}

void expectNoMujocoWarnings(const mjData* d) {
  for (int i = 0; i < mjNWARNING; ++i) EXPECT_EQ(d->warning[i].number, 0) << "MuJoCo warning " << i;
}

// ---------------------------------------------------------------- kinematics

TEST(PlanarTailPose, OneLinkClosedForm) {
  RobotParams r = paperRobot(1);
  PlanarState s{0.3, -0.2, 40 * kDeg, {25 * kDeg}};
  const PlanarTailPose p = planarTailPose(r, s);
  ASSERT_EQ(p.joints.size(), 2u);
  // Eq. (2) and Eq. (24)'s geometry: base behind the COM, link at phi + 180 deg + theta.
  const double bx = 0.3 - 0.125 * std::cos(40 * kDeg), by = -0.2 - 0.125 * std::sin(40 * kDeg);
  EXPECT_NEAR(p.joints[0][0], bx, 1e-12);
  EXPECT_NEAR(p.joints[0][1], by, 1e-12);
  EXPECT_NEAR(p.joints[1][0], bx + 0.3 * std::cos(245 * kDeg), 1e-12);
  EXPECT_NEAR(p.joints[1][1], by + 0.3 * std::sin(245 * kDeg), 1e-12);
}

TEST(PlanarTailPose, StraightTailLiesBehindTheBody) {
  RobotParams r = paperRobot(6);
  PlanarState s{0, 0, 90 * kDeg, std::vector<double>(6, 0.0)};
  const PlanarTailPose p = planarTailPose(r, s);
  // Body x along world +y: the straight tail points to -y, tip at d_Q2B + 6 * 0.05 m.
  EXPECT_NEAR(p.joints.back()[0], 0.0, 1e-12);
  EXPECT_NEAR(p.joints.back()[1], -(0.125 + 0.3), 1e-12);
}

// The ghost's paper kinematics and the MuJoCo model posed by setReplayQpos must agree: MuJoCo's
// own forward kinematics is the independent check of both the qpos mapping and Eqs. (1)-(3).
void checkReplayMatchesMujoco(int n, bool translation) {
  RobotParams robot = paperRobot(n);
  Effects e;
  e.translation = translation;
  ModelPtr m = loadModelFromXml(generateMjcf(robot, MujocoSettings{}, e));
  DataPtr d = makeData(m.get());
  const MujocoReplayLayout L = findReplayLayout(m.get(), n);
  EXPECT_EQ(L.free_root, translation);
  PlanarState s{translation ? 0.42 : 0.0, translation ? -0.17 : 0.0, -130 * kDeg, {}};
  for (int i = 0; i < n; ++i) s.theta.push_back((35.0 - 17.0 * i) * kDeg);
  setReplayQpos(m.get(), L, s, d->qpos);
  mj_kinematics(m.get(), d.get());
  expectNoMujocoWarnings(d.get());
  const int qb = bodyId(m.get(), mjcf::kQuadrupedBody);
  EXPECT_NEAR(d->xipos[3 * qb], s.x, 1e-9);
  EXPECT_NEAR(d->xipos[3 * qb + 1], s.y, 1e-9);
  EXPECT_NEAR(std::atan2(d->xmat[9 * qb + 3], d->xmat[9 * qb]), s.phi, 1e-9);
  const PlanarTailPose p = planarTailPose(robot, s);
  for (int i = 1; i <= n; ++i) {
    const int b = bodyId(m.get(), mjcf::tailBodyName(i));
    EXPECT_NEAR(d->xpos[3 * b], p.joints[i - 1][0], 1e-9) << "joint " << i;
    EXPECT_NEAR(d->xpos[3 * b + 1], p.joints[i - 1][1], 1e-9) << "joint " << i;
    EXPECT_NEAR(std::atan2(d->xmat[9 * b + 3], d->xmat[9 * b]), std::remainder(p.link_yaw[i - 1], 2 * M_PI), 1e-9);
  }
}

TEST(Replay, QposMatchesPaperKinematicsFreeRoot1Link) { checkReplayMatchesMujoco(1, true); }
TEST(Replay, QposMatchesPaperKinematicsFreeRoot4Links) { checkReplayMatchesMujoco(4, true); }
TEST(Replay, QposMatchesPaperKinematicsBallRoot3Links) { checkReplayMatchesMujoco(3, false); }

TEST(Replay, SamplerInterpolatesLinearlyAndClamps) {
  TimeSeries ts;
  for (const char* c : {"t_s", "x_m", "y_m", "phi_deg", "theta1_deg"}) ts.addColumn(c);
  ts.appendRow({0.0, 0.0, 1.0, 0.0, 10.0});
  ts.appendRow({0.1, 1.0, 1.0, 90.0, 20.0});
  ts.appendRow({0.3, 3.0, 0.0, 90.0, 20.0});
  PlanarStateSampler s(ts, 1, "test");
  PlanarState a = s.at(0.05);
  EXPECT_NEAR(a.x, 0.5, 1e-12);
  EXPECT_NEAR(a.phi, 45 * kDeg, 1e-12);
  EXPECT_NEAR(a.theta[0], 15 * kDeg, 1e-12);
  a = s.at(0.2);
  EXPECT_NEAR(a.x, 2.0, 1e-12);
  EXPECT_NEAR(a.y, 0.5, 1e-12);
  EXPECT_NEAR(s.at(-1).x, 0.0, 0);
  EXPECT_NEAR(s.at(9).x, 3.0, 0);
  EXPECT_THROW(PlanarStateSampler(ts, 2, "test"), std::invalid_argument);  // no theta2_deg
}

TEST(Replay, TailPhaseFollowsSplitCycleBreakpoints) {
  SplitCycleParams p;
  p.t0_s = 0.1;
  p.dT_s = 0.2;
  p.w_ss = 0.25;  // t1 = 0.15, t2 = 0.3
  TailTrajectory tr;
  tr.joints.emplace_back(p);
  EXPECT_EQ(tailPhase(tr, 0.05), TailPhase::kAtRest);
  EXPECT_EQ(tailPhase(tr, 0.1), TailPhase::kAccelerating);
  EXPECT_EQ(tailPhase(tr, 0.15), TailPhase::kAccelerating);
  EXPECT_EQ(tailPhase(tr, 0.1501), TailPhase::kDecelerating);
  EXPECT_EQ(tailPhase(tr, 0.3), TailPhase::kDecelerating);
  EXPECT_EQ(tailPhase(tr, 0.3001), TailPhase::kAtRest);
}

// The tail phases belong to split-cycle strokes (Eq. 20): a spline has no t1 or t2, so the video
// says nothing about accelerating for it, nor for a tail without strokes.
TEST(Replay, TailPhaseOnlyForSplitCycleStrokes) {
  TailTrajectory split;
  split.joints.emplace_back(SplitCycleParams{});
  EXPECT_TRUE(splitCycleStrokes(split));
  SplineParams sp;
  sp.knots_rad = {0.0, -0.5, -1.0};
  TailTrajectory mixed = split;
  mixed.joints.emplace_back(sp);
  EXPECT_FALSE(splitCycleStrokes(mixed));
  TailTrajectory spline;
  spline.joints.emplace_back(sp);
  EXPECT_FALSE(splitCycleStrokes(spline));
  EXPECT_FALSE(splitCycleStrokes(TailTrajectory{}));
}

// The phi(t) inset's ticks: its range runs from round tick to round tick (1, 2, 2.5, 5 x 10^k),
// one grid line per tick, labels printed with the digits the step needs.
TEST(RenderOverlay, InsetTicksAtRoundNumbers) {
  const RoundTicks t = roundTicks(0.0, 0.75, 4);  // the Fig. 6a video: 0 .. 0.75 s
  EXPECT_DOUBLE_EQ(t.step, 0.2);
  EXPECT_DOUBLE_EQ(t.lo, 0.0);
  EXPECT_NEAR(t.hi, 0.8, 1e-12);
  EXPECT_EQ(t.count, 5);
  EXPECT_EQ(t.decimals, 1);
  const RoundTicks y = roundTicks(-1.0, 12.0, 3);  // phi -1 .. 12 deg
  EXPECT_DOUBLE_EQ(y.step, 5.0);
  EXPECT_DOUBLE_EQ(y.lo, -5.0);
  EXPECT_DOUBLE_EQ(y.hi, 15.0);
  EXPECT_EQ(y.count, 5);
  EXPECT_EQ(y.decimals, 0);
  const RoundTicks q = roundTicks(0.0, 1.0, 4);  // a range that ends on a tick keeps it
  EXPECT_DOUBLE_EQ(q.step, 0.25);
  EXPECT_DOUBLE_EQ(q.hi, 1.0);
  EXPECT_EQ(q.count, 5);
  EXPECT_EQ(q.decimals, 2);
  for (const auto& [lo, hi] : std::vector<std::pair<double, double>>{{0.013, 0.377}, {-7.1, 0.2}, {3, 1234}}) {
    const RoundTicks r = roundTicks(lo, hi, 4);
    EXPECT_LE(r.lo, lo);
    EXPECT_GE(r.hi, hi);
    const double k = r.step / std::pow(10.0, std::floor(std::log10(r.step)));
    EXPECT_TRUE(std::abs(k - 1) < 1e-9 || std::abs(k - 2) < 1e-9 || std::abs(k - 2.5) < 1e-9 || std::abs(k - 5) < 1e-9) << r.step;
    EXPECT_NEAR(r.lo / r.step, std::round(r.lo / r.step), 1e-9);
    EXPECT_NEAR(r.hi / r.step, std::round(r.hi / r.step), 1e-9);
    EXPECT_LE(r.count, 9);
  }
}

// ---------------------------------------------------------------- videos

struct Probe {
  int frames = -1, width = -1, height = -1;
  std::string codec, pix_fmt;
};

Probe ffprobe(const std::string& path) {
  const std::string out = run("ffprobe -v error -count_frames -select_streams v:0 -show_entries "
                              "stream=codec_name,width,height,pix_fmt,nb_read_frames -of default=nw=1 '" +
                              path + "'");
  Probe p;
  std::istringstream in(out);
  std::string line;
  while (std::getline(in, line)) {
    const size_t eq = line.find('=');
    if (eq == std::string::npos) continue;
    const std::string k = line.substr(0, eq), v = line.substr(eq + 1);
    if (k == "codec_name") p.codec = v;
    if (k == "width") p.width = std::stoi(v);
    if (k == "height") p.height = std::stoi(v);
    if (k == "pix_fmt") p.pix_fmt = v;
    if (k == "nb_read_frames") p.frames = std::stoi(v);
  }
  return p;
}

// What a frame shows (docs/rendering.md "What a video shows"): the 3-D scene on the left on a
// grey checker floor, a dark panel on the right (text, colour key, phi(t) inset).
const uint8_t* px(const std::vector<uint8_t>& rgb, int w, int x, int y) { return &rgb[3 * (y * w + x)]; }
bool dark(const uint8_t* p) { return p[0] < 45 && p[1] < 45 && p[2] < 50; }
// The MuJoCo model: vermillion shades (floor grey: r = g = b; ghost blue: b > r).
bool robotColoured(const uint8_t* p) { return int(p[0]) - int(p[2]) > 50 && p[0] > 90; }
// The key and inset colours: Okabe-Ito vermillion #D55E00, blue #0072B2 (with encoder slack).
bool vermillion(const uint8_t* p) { return p[0] > 170 && p[1] > 50 && p[1] < 130 && p[2] < 60; }
bool blue(const uint8_t* p) { return p[0] < 60 && p[1] > 70 && p[1] < 160 && p[2] > 120; }
bool white(const uint8_t* p) { return p[0] > 210 && p[1] > 210 && p[2] > 210; }

// Width of the scene: the panel is the dark run at the right end of the bottom row.
int sceneWidth(const std::vector<uint8_t>& rgb, int w, int h) {
  int x = w;
  while (x > 0 && dark(px(rgb, w, x - 1, h - 1))) --x;
  return x;
}

// Rows between the topmost and the bottommost row with robot pixels in the scene (at least 2 per
// row, against encoder noise): how much of the frame height the robot fills.
int robotRowExtent(const std::vector<uint8_t>& rgb, int w, int h) {
  const int sw = sceneWidth(rgb, w, h);
  int top = -1, bottom = -1;
  for (int y = 0; y < h; ++y) {
    int n = 0;
    for (int x = 0; x < sw; ++x) n += robotColoured(px(rgb, w, x, y));
    if (n >= 2) bottom = y, top = top < 0 ? y : top;
  }
  return top < 0 ? 0 : bottom - top + 1;
}

int countIn(const std::vector<uint8_t>& rgb, int w, int x0, int x1, int y0, int y1, bool (*pred)(const uint8_t*)) {
  int n = 0;
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) n += pred(px(rgb, w, x, y));
  return n;
}

TEST(RenderVideo, Mp4AndPosterAreReadableAndShowTheRobot) {
  TempDir dir;
  Case c = makeCase(3, 0.4);
  RenderSettings s = smallSettings();
  ASSERT_NO_THROW(checkRenderPrerequisites(s, dir.str()));
  RenderInputs in{&c.robot, &c.traj, &c.mujoco, nullptr, c.xml, "test case"};
  const RenderStats st = renderVideo(in, s, dir / "case.mp4", dir / "case.png");
  // 0.4 s at 10 fps, slowmo 1: frames at t = 0, 0.1, .., 0.4.
  EXPECT_EQ(st.frames, 5);
  EXPECT_NEAR(st.sim_end_s, 0.4, 1e-9);
  const Probe p = ffprobe(dir / "case.mp4");
  EXPECT_EQ(p.frames, 5);
  EXPECT_EQ(p.width, 320);
  EXPECT_EQ(p.height, 240);
  EXPECT_EQ(p.codec, "h264");
  EXPECT_EQ(p.pix_fmt, "yuv420p");
  // Only the two final files: no temporaries or probes left behind.
  std::vector<std::string> files = dir.files();
  std::sort(files.begin(), files.end());
  EXPECT_EQ(files, (std::vector<std::string>{"case.mp4", "case.png"}));

  const std::vector<uint8_t> poster = decodeRgb(dir / "case.png");
  ASSERT_EQ(poster.size(), 320u * 240u * 3u);
  // The tracking camera frames the robot: it fills at least half the frame height.
  EXPECT_GE(robotRowExtent(poster, 320, 240), 120);
  // Not blank: the picture has contrast.
  double mean = 0, var = 0;
  for (uint8_t v : poster) mean += v;
  mean /= poster.size();
  for (uint8_t v : poster) var += (v - mean) * (v - mean);
  EXPECT_GT(std::sqrt(var / poster.size()), 15.0);
  // The poster is the video's frame at the tail's peak speed t1 = 0.0625 s -> frame 1 (10 fps).
  EXPECT_NEAR(st.poster_time_s, 0.1, 1e-12);
  const std::vector<uint8_t> frame1 = decodeRgb(dir / "case.mp4", 1);
  ASSERT_EQ(frame1.size(), poster.size());
  double mad = 0;
  for (size_t i = 0; i < poster.size(); ++i) mad += std::abs(int(poster[i]) - int(frame1[i]));
  EXPECT_LT(mad / poster.size(), 3.0);  // H.264 at crf 20 vs lossless PNG of the same frame
  // The video's frames are not blank either.
  const std::vector<uint8_t> last = decodeRgb(dir / "case.mp4", 4);
  ASSERT_EQ(last.size(), 320u * 240u * 3u);
  EXPECT_GE(robotRowExtent(last, 320, 240), 120);
}

TEST(RenderVideo, GhostAndCameraChangeThePicture) {
  TempDir dir;
  Case c = makeCase(1, 0.3);
  RenderSettings s = smallSettings();
  s.fps = 10;
  RenderInputs with{&c.robot, &c.traj, &c.mujoco, &c.analytic, c.xml, ""};
  RenderInputs without{&c.robot, &c.traj, &c.mujoco, nullptr, c.xml, ""};
  renderVideo(with, s, dir / "a.mp4", dir / "a.png");
  renderVideo(without, s, dir / "b.mp4", dir / "b.png");
  s.camera = RenderCamera::kPerspective;
  renderVideo(with, s, dir / "c.mp4", dir / "c.png");
  const auto a = decodeRgb(dir / "a.png"), b = decodeRgb(dir / "b.png"), cp = decodeRgb(dir / "c.png");
  ASSERT_EQ(a.size(), b.size());
  ASSERT_EQ(a.size(), cp.size());
  auto differing = [](const std::vector<uint8_t>& x, const std::vector<uint8_t>& y) {
    int n = 0;
    for (size_t i = 0; i < x.size(); i += 3)
      n += std::abs(x[i] - y[i]) + std::abs(x[i + 1] - y[i + 1]) + std::abs(x[i + 2] - y[i + 2]) > 30;
    return n;
  };
  // The analytic ghost (phi 3x the MuJoCo one) sits elsewhere: a visible set of pixels changes.
  EXPECT_GT(differing(a, b), 800);
  EXPECT_GT(differing(a, cp), 8000);
}

// End to end with the real models: the columns both simulations write are what the renderer
// replays (paper Fig. 7 case, both models, the analytic one as the ghost).
TEST(RenderVideo, ReplaysBothModelsOfFig7) {
  TempDir dir;
  Case c = makeCase(1);
  OutputSettings out;
  out.sample_dt_s = 2e-3;
  out.duration_s = 0.5;
  const RunResult mj = simulateMujoco(c.robot, c.traj, MujocoSettings{}, Effects{}, out);
  const RunResult an = simulateAnalytic(c.robot, c.traj, AnalyticSettings{}, Effects{}, out);
  ASSERT_TRUE(mj.summary.ok) << mj.summary.error;
  ASSERT_TRUE(an.summary.ok) << an.summary.error;
  RenderSettings s = smallSettings();
  s.fps = 20;
  RenderInputs in{&c.robot, &c.traj, &mj.series, &an.series, c.xml, "fig07"};
  const RenderStats st = renderVideo(in, s, dir / "fig7.mp4", dir / "fig7.png");
  EXPECT_EQ(st.frames, 11);
  EXPECT_EQ(ffprobe(dir / "fig7.mp4").frames, 11);
  const std::vector<uint8_t> last = decodeRgb(dir / "fig7.mp4", 10);
  ASSERT_EQ(last.size(), 320u * 240u * 3u);
  EXPECT_GE(robotRowExtent(last, 320, 240), 120);
}

// The default 640x480 frame as a reader sees it: the robot fills at least half the
// frame height, the analytic model is a blue outline, the colour key names each model in its
// colour, and the phi(t) inset shows both curves with a time cursor that moves.
TEST(RenderVideo, DefaultFrameHasTheRobotLargeTheKeyAndTheInset) {
  TempDir dir;
  Case c = makeCase(1, 0.3);
  RenderSettings s;  // defaults: 640x480, msaa 4, top camera
  s.enabled = true;
  s.fps = 10;
  s.slowmo = 1.0;
  RenderInputs in{&c.robot, &c.traj, &c.mujoco, &c.analytic, c.xml, "fig07"};
  renderVideo(in, s, dir / "a.mp4", "");
  const int w = 640, h = 480;
  const std::vector<uint8_t> first = decodeRgb(dir / "a.mp4", 0), last = decodeRgb(dir / "a.mp4", 3);
  ASSERT_EQ(first.size(), size_t(w) * h * 3);
  ASSERT_EQ(last.size(), first.size());
  const int sw = sceneWidth(first, w, h);
  ASSERT_GT(sw, w / 2);   // the scene takes most of the width,
  ASSERT_LT(sw, w - 150);  // the panel the rest
  for (const auto* f : {&first, &last}) {
    EXPECT_GE(robotRowExtent(*f, w, h), h / 2);
    EXPECT_GT(countIn(*f, w, 0, sw, 0, h, blue), 300);  // the ghost's outline
    // Key: the top 40 % of the panel holds a vermillion and a blue label (~200 x 25 px each).
    EXPECT_GT(countIn(*f, w, sw, w, 0, h * 2 / 5, vermillion), 2000);
    EXPECT_GT(countIn(*f, w, sw, w, 0, h * 2 / 5, blue), 2000);
    // Inset: both curves in the lower half of the panel.
    EXPECT_GT(countIn(*f, w, sw, w, h / 2, h, vermillion), 40);
    EXPECT_GT(countIn(*f, w, sw, w, h / 2, h, blue), 40);
  }
  // The time cursor: the column of the inset with the most white pixels moves right.
  auto cursor = [&](const std::vector<uint8_t>& f) {
    int best = -1, best_n = 0;
    for (int x = sw; x < w; ++x) {
      const int n = countIn(f, w, x, x + 1, h / 2, h, white);
      if (n > best_n) best = x, best_n = n;
    }
    EXPECT_GT(best_n, 40) << "no vertical cursor line";
    return best;
  };
  EXPECT_GT(cursor(last), cursor(first) + 50);
  // Without the analytic run: no blue outline in the scene, no blue label.
  RenderInputs solo{&c.robot, &c.traj, &c.mujoco, nullptr, c.xml, "fig07"};
  renderVideo(solo, s, dir / "b.mp4", "");
  const std::vector<uint8_t> b = decodeRgb(dir / "b.mp4", 0);
  ASSERT_EQ(b.size(), first.size());
  EXPECT_LT(countIn(b, w, 0, sw, 0, h, blue), 20);
  EXPECT_LT(countIn(b, w, sw, w, 0, h * 2 / 5, blue), 20);
}

// The 1280x720 preset (render.size) renders at that size, with the robot as large.
TEST(RenderVideo, Preset1280x720GivesThatSize) {
  TempDir dir;
  Case c = makeCase(1, 0.2);
  RenderSettings s;
  s.enabled = true;
  s.width = kRenderSizePresets[1].width;
  s.height = kRenderSizePresets[1].height;
  s.fps = 10;
  s.slowmo = 1.0;
  s.msaa = 0;
  RenderInputs in{&c.robot, &c.traj, &c.mujoco, &c.analytic, c.xml, "fig07"};
  renderVideo(in, s, dir / "hd.mp4", dir / "hd.png");
  const Probe p = ffprobe(dir / "hd.mp4");
  EXPECT_EQ(p.width, 1280);
  EXPECT_EQ(p.height, 720);
  const std::vector<uint8_t> f = decodeRgb(dir / "hd.png");
  ASSERT_EQ(f.size(), 1280u * 720u * 3u);
  EXPECT_GE(robotRowExtent(f, 1280, 720), 360);
}

// Cases render on the experiment runner's worker threads: two renders at once, each in its
// own OSMesa context, give the same pictures as one at a time.
TEST(RenderVideo, ConcurrentRendersOnTwoThreads) {
  TempDir dir;
  Case c1 = makeCase(1, 0.3), c2 = makeCase(2, 0.3);
  RenderSettings s = smallSettings();
  RenderInputs in1{&c1.robot, &c1.traj, &c1.mujoco, &c1.analytic, c1.xml, ""};
  RenderInputs in2{&c2.robot, &c2.traj, &c2.mujoco, &c2.analytic, c2.xml, ""};
  renderVideo(in1, s, dir / "ref1.mp4", dir / "ref1.png");
  renderVideo(in2, s, dir / "ref2.mp4", dir / "ref2.png");
  std::string err1, err2;
  std::thread t1([&] {
    try {
      renderVideo(in1, s, dir / "a1.mp4", dir / "a1.png");
    } catch (const std::exception& e) {
      err1 = e.what();
    }
  });
  std::thread t2([&] {
    try {
      renderVideo(in2, s, dir / "a2.mp4", dir / "a2.png");
    } catch (const std::exception& e) {
      err2 = e.what();
    }
  });
  t1.join();
  t2.join();
  EXPECT_EQ(err1, "");
  EXPECT_EQ(err2, "");
  EXPECT_EQ(decodeRgb(dir / "a1.png"), decodeRgb(dir / "ref1.png"));
  EXPECT_EQ(decodeRgb(dir / "a2.png"), decodeRgb(dir / "ref2.png"));
  EXPECT_EQ(ffprobe(dir / "a2.mp4").frames, 4);
}

// ---------------------------------------------------------------- errors

TEST(RenderErrors, MissingFfmpegIsReportedBeforeWork) {
  TempDir dir;
  Case c = makeCase(1, 0.2);
  RenderSettings s = smallSettings();
  s.ffmpeg = "tailsim-no-such-ffmpeg";
  try {
    checkRenderPrerequisites(s, dir.str());
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("not found on PATH"), std::string::npos) << e.what();
  }
  RenderInputs in{&c.robot, &c.traj, &c.mujoco, nullptr, c.xml, ""};
  EXPECT_THROW(renderVideo(in, s, dir / "x.mp4", dir / "x.png"), std::runtime_error);
  EXPECT_TRUE(dir.files().empty());

  // The same through PATH: the default name "ffmpeg" on an empty PATH.
  const std::string old_path = std::getenv("PATH") ? std::getenv("PATH") : "";
  ::setenv("PATH", dir.str().c_str(), 1);
  RenderSettings d = smallSettings();
  EXPECT_THROW(checkRenderPrerequisites(d, dir.str()), std::runtime_error);
  ::setenv("PATH", old_path.c_str(), 1);
  s.ffmpeg = dir / "missing/ffmpeg";
  try {
    checkRenderPrerequisites(s, dir.str());
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("not found at"), std::string::npos) << e.what();
  }
}

TEST(RenderErrors, UnwritableOutputFolderIsReported) {
  TempDir dir;
  {
    std::ofstream f(dir / "plain_file");
    f << "x";
  }
  // A folder below a regular file can never be created (even as root).
  try {
    checkRenderPrerequisites(smallSettings(), dir / "plain_file/videos");
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("output folder"), std::string::npos) << e.what();
  }
  if (::geteuid() != 0) {  // permission bits do not stop root
    fs::create_directory(dir / "ro");
    fs::permissions(dir / "ro", fs::perms::owner_read | fs::perms::owner_exec);
    EXPECT_THROW(checkRenderPrerequisites(smallSettings(), dir / "ro"), std::runtime_error);
  }
  Case c = makeCase(1, 0.2);
  RenderInputs in{&c.robot, &c.traj, &c.mujoco, nullptr, c.xml, ""};
  EXPECT_THROW(renderVideo(in, smallSettings(), dir / "plain_file/x.mp4", ""), std::runtime_error);
  EXPECT_FALSE(fs::exists(dir / "plain_file/x.mp4"));
}

TEST(RenderErrors, BadSettingsAreReported) {
  TempDir dir;
  RenderSettings s = smallSettings();
  s.width = 161;
  EXPECT_THROW(checkRenderPrerequisites(s, dir.str()), std::runtime_error);
  s = smallSettings();
  s.camera = static_cast<RenderCamera>(7);  // not a declared camera
  EXPECT_THROW(checkRenderPrerequisites(s, dir.str()), std::runtime_error);
  s = smallSettings();
  s.slowmo = 0;
  EXPECT_THROW(checkRenderPrerequisites(s, dir.str()), std::runtime_error);
}

// An encoder that dies mid-video: the error carries its message and nothing appears under the
// final names (the temporary file is removed too).
TEST(RenderErrors, EncoderFailureLeavesNoFile) {
  TempDir dir;
  const std::string fake = dir / "fake-ffmpeg";
  {
    std::ofstream f(fake);
    f << "#!/bin/sh\n"
         "case \"$*\" in *testsrc*) exit 0;; esac\n"  // pass the prerequisite probe
         "head -c 100000 >/dev/null\necho 'fake encoder gave up' >&2\nexit 3\n";
  }
  fs::permissions(fake, fs::perms::owner_all);
  RenderSettings s = smallSettings();
  s.ffmpeg = fake;
  ASSERT_NO_THROW(checkRenderPrerequisites(s, dir.str()));
  Case c = makeCase(1, 0.4);
  RenderInputs in{&c.robot, &c.traj, &c.mujoco, nullptr, c.xml, ""};
  fs::create_directory(dir / "out");
  try {
    renderVideo(in, s, dir / "out/v.mp4", dir / "out/v.png");
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("fake encoder gave up"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(fs::is_empty(dir / "out"));
}

// RAII: a sink dropped without finish() (an exception between frames) kills ffmpeg and leaves
// neither the final nor the temporary file.
TEST(RenderErrors, AbandonedSinkRemovesItsTemporary) {
  TempDir dir;
  const std::string exe = findExecutable("ffmpeg");
  ASSERT_FALSE(exe.empty());
  std::vector<uint8_t> frame(64 * 48 * 3, 128);
  std::string tmp;
  {
    FfmpegSink sink(exe, 64, 48, VideoEncoding{}, {{FfmpegOutput::Kind::kMp4, dir / "v.mp4", 0},
                                                   {FfmpegOutput::Kind::kPng, dir / "v.png", 2}});
    tmp = sink.tempPaths()[0];
    for (int k = 0; k < 20; ++k) sink.writeFrame(frame.data());
  }
  EXPECT_FALSE(fs::exists(dir / "v.mp4"));
  EXPECT_FALSE(fs::exists(tmp));
  EXPECT_TRUE(dir.files().empty());
  // finish() without commit() publishes nothing either.
  {
    FfmpegSink sink(exe, 64, 48, VideoEncoding{}, {{FfmpegOutput::Kind::kMp4, dir / "w.mp4", 0}});
    for (int k = 0; k < 3; ++k) sink.writeFrame(frame.data());
    sink.finish();
  }
  EXPECT_TRUE(dir.files().empty());
  // A poster frame beyond the end of the stream is an error, and nothing is published.
  {
    FfmpegSink sink(exe, 64, 48, VideoEncoding{}, {{FfmpegOutput::Kind::kMp4, dir / "x.mp4", 0},
                                                   {FfmpegOutput::Kind::kPng, dir / "x.png", 5}});
    for (int k = 0; k < 3; ++k) sink.writeFrame(frame.data());
    EXPECT_THROW(sink.finish(), std::runtime_error);
  }
  EXPECT_TRUE(dir.files().empty());
}

}  // namespace
}  // namespace tailsim
