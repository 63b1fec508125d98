// Outputs are written whole or not at all: write to a temporary file beside the target,
// flush, then rename over it (rename is atomic within one filesystem).
#pragma once

#include <functional>
#include <optional>
#include <string>


namespace tailsim {

// Writes `contents` to `path` atomically; throws std::system_error (errno, e.g. ENOSPC when the
// disk is full) naming the path on failure.
void writeFileAtomic(const std::string& path, const std::string& contents);

// True when no process `pid` runs any more: none exists, or it has exited and waits to be reaped (a
// zombie: a killed run's helper process whose new parent has not reaped it yet). Temporary files
// and staging folders named with such a pid are left over.
bool processGone(long pid);

// Writes a file the user named on the command line (e.g. `tailsim mjcf --out PATH`) without ever
// replacing what is at PATH with something else:
//  - "-" is stdout; /dev/stdout, /dev/stderr, /dev/fd/N and /proc/self/fd/N are written to this
//    process's descriptor N directly (never reopened: `>> log` keeps appending);
//  - an existing symlink is written through to its target (the link stays a link), and an existing
//    device, FIFO or socket is opened and written (nothing is renamed over it);
//  - anything else (a regular file or a new name) atomically, as writeFileAtomic.
// Returns true when the contents went to a stream (descriptor, device, FIFO, socket) rather than
// to a file, so callers can keep their messages off stdout. Throws std::runtime_error naming PATH.
// `own_marker`: a non-empty regular file at PATH (a symlink's target included) is replaced only when
// its first 4 KiB hold this text, i.e. tailsim wrote it (e.g. "# Written by `tailsim robot`");
// anything else, the user's model file among them, is refused with std::runtime_error and left as it is.
bool writeUserFile(const std::string& path, const std::string& contents, const std::string& own_marker = "");

// Reads a file tailsim wrote into a result folder (cases.jsonl, result.json, summary.json, ...)
// only if it is what it should be: std::nullopt when absent; std::runtime_error naming the path
// when it is a symbolic link (never followed out of the folder), not a regular file (a FIFO never
// blocks, a device is never read) or larger than max_bytes (never read into memory unbounded).
constexpr long long kMaxResultFileBytes = 1LL << 30;
std::optional<std::string> readResultFile(const std::string& path, long long max_bytes = kMaxResultFileBytes);

// Reads a result-folder file as readResultFile does (the same checks), line by line: calls fn with
// each complete line (without its '\n') and its number (1-based) until fn returns false, holding at
// most max_line bytes in memory; std::nullopt when absent. A line longer than max_line:
// std::runtime_error naming the file.
struct LinesRead {
  long long lines = 0;  // complete lines
  long long whole = 0;  // their bytes, newlines included
  long long size = 0;   // all bytes read
  std::string tail;     // the bytes after the last newline (a torn last line)
};
std::optional<LinesRead> readResultFileLines(const std::string& path, size_t max_line,
                                             const std::function<bool(const std::string& line, long long number)>& fn);

// Creates DIR (and its parents) when absent; std::runtime_error naming DIR when it is a symbolic
// link or not a directory (tailsim writes only into real folders of a result folder, never through
// a link out of it).
void makeResultDir(const std::string& dir);

// DIR/.tailsim-manifest: the files tailsim wrote in DIR, one "<sha256>  <name>" line each
// (sha256sum's format: `sha256sum -c .tailsim-manifest` checks them), so it replaces or deletes
// only its own files, unchanged since it wrote them.
// Whether DIR has a manifest at all.
bool hasManifest(const std::string& dir);
// Whether the manifest names `name` (relative to DIR) with exactly this content.
bool manifestNames(const std::string& dir, const std::string& name, const std::string& content);
// Appends "<sha256(content)>  <name>" unless there (before the file is written: whatever stops the
// writer in between, the file holds a content the manifest names). Throws std::runtime_error.
void recordInManifest(const std::string& dir, const std::string& name, const std::string& content);
// The same, by the content's SHA-256 (64 hex digits): for files too large to hold in memory.
bool manifestNamesHash(const std::string& dir, const std::string& name, const std::string& sha256_hex);
void recordHashInManifest(const std::string& dir, const std::string& name, const std::string& sha256_hex);
// Rewrites the manifest with one line per file that still has the content it names.
void compactManifest(const std::string& dir);
// Recognises a file an earlier tailsim (before manifests) wrote, by its content.
using EarlierOwnFile = std::function<bool(const std::string& text)>;
// Whether DIR/name is tailsim's to replace: absent, named in DIR's manifest with its current
// content, byte-identical to `content` (when given), or, when the manifest does not name `name`
// at all, recognised by `earlier` (when given). Throws std::runtime_error naming DIR/name when it
// is not a regular file.
bool ownedFile(const std::string& dir, const std::string& name, const std::optional<std::string>& content = std::nullopt,
               const EarlierOwnFile& earlier = {});
// Throws std::runtime_error naming DIR/name unless ownedFile(...).
void checkOwnedFile(const std::string& dir, const std::string& name, const std::optional<std::string>& content = std::nullopt,
                    const EarlierOwnFile& earlier = {});
// Writes DIR/name (name relative to DIR, no '/') when it is tailsim's (checkOwnedFile), after
// recording `content` in DIR's manifest; atomically, as writeFileAtomic.
void writeOwnedFile(const std::string& dir, const std::string& name, const std::string& content,
                    const EarlierOwnFile& earlier = {});
// Records DIR/name's current content in the manifest (a file a program tailsim ran wrote).
void recordWrittenFile(const std::string& dir, const std::string& name);

}  // namespace tailsim
