#include "plotting/gnuplot.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/statvfs.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <cstring>
#include <stdexcept>

#include "common/atomic_file.h"

extern char** environ;

namespace tailsim {

namespace fs = std::filesystem;

std::string gpQuote(const std::string& s) {
  std::string out = "'";
  for (const char c : s) {
    const auto u = static_cast<unsigned char>(c);
    if (c == '\'') out += "'.\"'\".'";  // not '': gnuplot 5.4 reads '''x' as '' 'x', 'a''''b' as a'
    else if (c == '\n') out += "'.\"\\n\".'";
    else if (u < 0x20 || u == 0x7f) out += ' ';  // NUL, CR, tab, ESC: a space, never script syntax
    else out += c;
  }
  return out + "'";
}

std::string gpFileName(const std::string& relative_name) { return gpQuote("./" + relative_name); }

namespace {

// Runs `gnuplot SCRIPT` in `dir` without a shell (as ffmpeg is started, rendering/ffmpeg_writer.cc):
// stdin /dev/null, stdout and stderr into `log_path` (absolute). Returns the wait status, or
// throws if gnuplot cannot be started.
int runGnuplot(const fs::path& dir, const std::string& script, const fs::path& log_path) {
  const int log_fd = ::open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (log_fd < 0) throw std::runtime_error("cannot write " + log_path.string() + ": " + std::strerror(errno));
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_adddup2(&fa, log_fd, 1);
  posix_spawn_file_actions_adddup2(&fa, log_fd, 2);
  posix_spawn_file_actions_addchdir_np(&fa, dir.c_str());
  std::string exe = "gnuplot", arg = script;
  char* argv[] = {exe.data(), arg.data(), nullptr};
  pid_t pid = -1;
  const int rc = posix_spawnp(&pid, "gnuplot", &fa, nullptr, argv, environ);
  posix_spawn_file_actions_destroy(&fa);
  ::close(log_fd);
  if (rc != 0)
    throw std::runtime_error("cannot start gnuplot for " + (dir / script).string() + ": " + std::strerror(rc) +
                             (rc == ENOENT ? " (gnuplot not installed? scripts/setup.sh installs gnuplot-nox)" : ""));
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) throw std::runtime_error(std::string("waiting for gnuplot: ") + std::strerror(errno));
  }
  return status;
}

// Whether a figure gnuplot wrote is whole: a PNG ends with its IEND chunk, an SVG with </svg>.
bool wholeFigure(const fs::path& p, bool png) {
  std::optional<std::string> text;
  try {
    text = readResultFile(p.string());
  } catch (const std::exception&) {
    return false;
  }
  if (!text) return false;
  if (png) {
    static const std::string iend("\0\0\0\0IEND\xae\x42\x60\x82", 12);
    return text->size() > iend.size() && text->compare(text->size() - iend.size(), iend.size(), iend) == 0;
  }
  const size_t end = text->rfind("</svg>");
  return end != std::string::npos && text->find_first_not_of(" \r\n", end + 6) == std::string::npos;
}

// Whether the file system holding dir has no room left for a file (the reason a figure is not whole).
bool diskFull(const fs::path& dir) {
  struct statvfs v {};
  return ::statvfs(dir.c_str(), &v) == 0 && static_cast<unsigned long long>(v.f_bavail) * v.f_frsize < (256u << 10);
}

std::string terminalBlock(const GnuplotFigure& f, bool png, const std::string& out_stem) {
  std::ostringstream o;
  char scale[48] = "";
  if (f.font_scale > 0 && f.font_scale != 1.0) std::snprintf(scale, sizeof scale, " fontscale %.3g", f.font_scale);
  if (png)
    o << "set terminal pngcairo enhanced size " << f.width_px << "," << f.height_px
      << " font 'Sans,15'" << scale << " linewidth 2\n"
      << "set output " << gpFileName(out_stem + ".png") << "\n";
  else
    o << "set terminal svg enhanced size " << f.width_px << "," << f.height_px
      << " font 'Sans,15'" << scale << " linewidth 2 background rgb 'white'\n"
      << "set output " << gpFileName(out_stem + ".svg") << "\n";
  o << f.body << "\nunset output\n";
  return o.str();
}

}  // namespace

void writeDataFile(const std::string& path, const std::vector<std::string>& header,
                   const std::vector<std::vector<double>>& rows) {
  std::string out = "#";
  for (const std::string& h : header) out += " " + h;
  out += "\n";
  char buf[40];
  for (const auto& row : rows) {
    for (size_t i = 0; i < row.size(); ++i) {
      if (i) out += ' ';
      if (std::isfinite(row[i])) {
        std::snprintf(buf, sizeof buf, "%.10g", row[i]);
        out += buf;
      } else {
        out += "NaN";
      }
    }
    out += '\n';
  }
  const fs::path p(path);
  writeOwnedFile(p.parent_path().string(), p.filename().string(), out, [](const std::string& text) {
    return text.compare(0, 2, "# ") == 0;  // an earlier tailsim's data file: its header row
  });
}

std::string renderFigure(const std::string& plots_dir, const GnuplotFigure& fig) {
  makeResultDir(plots_dir);
  const fs::path user_dir(plots_dir);              // paths as the user gave them, for messages
  const fs::path dir = fs::absolute(plots_dir);  // gnuplot's working directory: any cwd works
  std::string comment_stem = fig.stem;  // a line break in the comment would start a command
  for (char& c : comment_stem)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f || c == '\\') c = '_';
  const std::string preamble = "# " + comment_stem + ": written by tailsim plot; rerun with `gnuplot " + comment_stem +
                               ".gp` in this folder\nset encoding utf8\nset datafile missing 'NaN'\n";
  const std::string script = preamble + terminalBlock(fig, true, fig.stem) + terminalBlock(fig, false, fig.stem);
  // gnuplot runs a copy that writes the figures under temporary names; each is renamed into place
  // when whole, so a full disk or a killed gnuplot never leaves a partial figure.
  const std::string temp_stem = fig.stem + ".tailsim-tmp." + std::to_string(::getpid());
  // The script, its log and figures are replaced only when tailsim wrote them (DIR's manifest);
  // beside a script of an earlier tailsim (no manifest line for it), its figures are taken as tailsim's.
  const std::string header = "# " + comment_stem + ": written by tailsim plot";
  bool earlier = false;
  try {
    const std::optional<std::string> gp = readResultFile((dir / (fig.stem + ".gp")).string());
    earlier = gp && gp->compare(0, header.size(), header) == 0 && ownedFile(dir.string(), fig.stem + ".gp", std::nullopt,
                                                                            [](const std::string&) { return true; });
  } catch (const std::exception&) {  // not a regular file: refused below
  }
  const EarlierOwnFile ours = [earlier](const std::string&) { return earlier; };
  for (const char* ext : {".png", ".svg", ".log"}) checkOwnedFile(dir.string(), fig.stem + ext, std::nullopt, ours);
  writeOwnedFile(dir.string(), fig.stem + ".gp", script, ours);
  const fs::path log = dir / (fig.stem + ".log");
  writeFileAtomic((dir / (temp_stem + ".gp")).string(),
                  preamble + terminalBlock(fig, true, temp_stem) + terminalBlock(fig, false, temp_stem));
  const auto removeTemps = [&dir, &temp_stem]() {
    std::error_code ec;
    for (const char* ext : {".gp", ".png", ".svg"}) fs::remove(dir / (temp_stem + ext), ec);
  };
  int status = 0;
  try {
    status = runGnuplot(dir, "./" + temp_stem + ".gp", log);  // "./": gnuplot runs an argument starting with '<' as a command
  } catch (...) {
    removeTemps();
    throw;
  }
  std::string err;
  {
    std::ifstream in(log);
    std::stringstream ss;
    ss << in.rdbuf();
    err = ss.str();
  }
  // Only a log with something in it is kept, so only that one is named in the manifest (an empty one
  // is removed below; a stray one beside this script is taken as tailsim's, as `ours` says).
  if (!err.empty()) recordWrittenFile(dir.string(), fig.stem + ".log");
  std::string missing;  // the first figure that is not whole
  for (const char* ext : {".png", ".svg"})
    if (missing.empty() && !wholeFigure(dir / (temp_stem + ext), ext[1] == 'p')) missing = (user_dir / (fig.stem + ext)).string();
  const bool failed = !WIFEXITED(status) || WEXITSTATUS(status) != 0;
  if (!missing.empty() || failed) {
    removeTemps();
    std::error_code ec;
    if (err.empty()) fs::remove(log, ec);  // nothing to read in it
    if (!missing.empty() && diskFull(dir))
      throw std::runtime_error("cannot write " + missing + ": No space left on device (the figure is not whole; nothing kept)");
    if (failed)
      throw std::runtime_error("gnuplot failed on " + (user_dir / (fig.stem + ".gp")).string() +
                               (WIFEXITED(status) ? " (exit " + std::to_string(WEXITSTATUS(status)) + ")"
                                                  : std::string(" (killed by a signal)")) +
                               ":\n" + err);
    throw std::runtime_error("gnuplot wrote no whole " + missing + ":\n" + err);
  }
  for (const char* ext : {".png", ".svg"}) {  // named in the manifest before it is there
    const std::optional<std::string> text = readResultFile((dir / (temp_stem + ext)).string());
    if (text) recordInManifest(dir.string(), fig.stem + ext, *text);
    fs::rename(dir / (temp_stem + ext), dir / (fig.stem + ext));
  }
  removeTemps();
  if (err.empty()) fs::remove(log);
  return (user_dir / (fig.stem + ".png")).string();
}

}  // namespace tailsim
