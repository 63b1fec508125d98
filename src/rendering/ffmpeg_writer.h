// ffmpeg child processes fed raw RGB frames on stdin (issue 5). Outputs are written whole or
// not at all: ffmpeg writes to a temporary name beside the target, which is renamed over the
// target only when ffmpeg exits cleanly; on any failure or exception the child is killed and
// the temporary file removed.
#pragma once

#include <sys/types.h>

#include <cstdint>
#include <string>
#include <vector>

namespace tailsim {

// Full path of an executable: `name` itself if it contains '/', else the first match on PATH.
// Returns "" when there is none.
std::string findExecutable(const std::string& name);

// Runs `ffmpeg_exe` on a one-frame test encode with libx264 (and png). Returns "" when it works,
// else ffmpeg's message.
std::string probeFfmpeg(const std::string& ffmpeg_exe);

// One ffmpeg process encoding rgb24 frames of a fixed size into one output file.
class FfmpegSink {
 public:
  enum class Kind { kMp4, kPng };
  // Starts `ffmpeg_exe` (a full path). For kPng exactly one frame is expected.
  FfmpegSink(const std::string& ffmpeg_exe, Kind kind, int width, int height, int fps, int crf,
             const std::string& preset, const std::string& final_path);
  ~FfmpegSink();  // not finished: kill the child, remove the temporary file
  FfmpegSink(const FfmpegSink&) = delete;
  FfmpegSink& operator=(const FfmpegSink&) = delete;

  // One frame, rows top to bottom, width*height*3 bytes. Throws std::runtime_error (with
  // ffmpeg's own message) when ffmpeg has died.
  void writeFrame(const uint8_t* rgb);
  // Closes stdin and waits for ffmpeg. Throws std::runtime_error with ffmpeg's message on
  // failure (and removes the temporary file).
  void finish();
  // After finish(): renames the temporary file to the final name.
  void commit();

  const std::string& tempPath() const { return tmp_path_; }
  const std::string& finalPath() const { return final_path_; }
  long framesWritten() const { return frames_; }

 private:
  void abort() noexcept;
  std::string errorLog() const;

  pid_t pid_ = -1;
  int stdin_fd_ = -1;
  std::string tmp_path_, final_path_, log_path_;
  size_t frame_bytes_ = 0;
  long frames_ = 0;
  bool finished_ = false;
};

}  // namespace tailsim
