// SHA-256 (FIPS 180-4) of a byte string, as 64 lowercase hex digits. A stable hash for resume
// keys and folder-name suffixes (std::hash is neither stable across builds nor collision-resistant).
#pragma once

#include <string>

namespace tailsim {

std::string sha256Hex(const std::string& data);

}  // namespace tailsim
