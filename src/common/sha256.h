// SHA-256 (FIPS 180-4) of a byte string, as 64 lowercase hex digits. A stable hash for resume
// keys and folder-name suffixes (std::hash is neither stable across builds nor collision-resistant).
#pragma once

#include <optional>
#include <string>

namespace tailsim {

std::string sha256Hex(const std::string& data);

// The SHA-256 of a file's bytes, read in blocks (any size); std::nullopt when it cannot be opened
// or read (a symlink is not followed).
std::optional<std::string> sha256OfFile(const std::string& path);

}  // namespace tailsim
