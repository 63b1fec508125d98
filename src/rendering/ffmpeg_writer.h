// ffmpeg child processes fed raw RGB frames on stdin. Outputs are written whole or
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

// What ffmpeg writes from the one stream of frames.
struct FfmpegOutput {
  enum class Kind { kMp4, kPng };
  Kind kind = Kind::kMp4;
  std::string path;    // final path (written under a temporary name until commit())
  long png_frame = 0;  // kPng: index of the frame written (ffmpeg's select filter)
};

struct VideoEncoding {
  int fps = 30;
  int crf = 20;                     // libx264 constant rate factor
  std::string preset = "ultrafast";  // libx264 preset
};

// Frames (video packets) in the container at `path` as ffprobe counts them; -1 when it cannot
// read the file (a truncated MP4 has no index).
long countVideoFrames(const std::string& ffprobe_exe, const std::string& path);

// One ffmpeg process reading rgb24 frames of a fixed size on stdin and writing one or more
// outputs (an H.264 MP4 and a PNG still from the same stream: one process start, not two).
class FfmpegSink {
 public:
  // Starts `ffmpeg_exe` (a full path).
  FfmpegSink(const std::string& ffmpeg_exe, int width, int height, const VideoEncoding& enc,
             const std::vector<FfmpegOutput>& outputs);
  ~FfmpegSink();  // not committed: kill the child, remove the temporary files
  FfmpegSink(const FfmpegSink&) = delete;
  FfmpegSink& operator=(const FfmpegSink&) = delete;

  // One frame, rows top to bottom, width*height*3 bytes. Throws std::runtime_error (with
  // ffmpeg's own message) when ffmpeg has died.
  void writeFrame(const uint8_t* rgb);
  // Closes stdin and waits for ffmpeg. Throws std::runtime_error with ffmpeg's message on
  // failure (and removes the temporary files), also when an output was not produced, when ffmpeg
  // logged a write error (it exits 0 when writing the MP4 trailer fails) or when an MP4 does not
  // hold every frame written (checked with ffprobe, from the same package as ffmpeg). A full
  // disk throws std::system_error with ENOSPC, so a sweep can stop at once.
  void finish();
  // After finish(): renames the temporary files to the final names, in output order.
  void commit();

  const std::vector<std::string>& tempPaths() const { return tmp_paths_; }
  long framesWritten() const { return frames_; }

 private:
  void abort() noexcept;
  [[noreturn]] void fail(const std::string& msg);  // abort(), then throw
  std::string errorLog() const;

  pid_t pid_ = -1;
  int stdin_fd_ = -1;
  std::vector<FfmpegOutput> outputs_;
  std::string ffprobe_;  // verifies each MP4 before commit ("" when there is no ffprobe)
  std::vector<std::string> tmp_paths_;
  int log_fd_ = -1;  // ffmpeg's stderr (an unlinked temporary file)
  size_t frame_bytes_ = 0;
  long frames_ = 0;
  bool finished_ = false;
};

}  // namespace tailsim
