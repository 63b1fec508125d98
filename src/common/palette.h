// The Okabe-Ito colour-blind-safe palette (Okabe & Ito 2008, "Color Universal Design") and the
// fixed colour of each model, declared once for every picture tailsim draws: the plots
// (src/plotting/style.h) and the videos (src/rendering/). Lives in the lowest layer so that both
// can use it.
#pragma once

namespace tailsim {

namespace okabe_ito {
inline constexpr const char* kBlack = "#000000";
inline constexpr const char* kOrange = "#E69F00";
inline constexpr const char* kSkyBlue = "#56B4E9";
inline constexpr const char* kGreen = "#009E73";   // bluish green
inline constexpr const char* kYellow = "#F0E442";  // too light for lines on white: not used for lines
inline constexpr const char* kBlue = "#0072B2";
inline constexpr const char* kVermillion = "#D55E00";
inline constexpr const char* kPurple = "#CC79A7";  // reddish purple
}  // namespace okabe_ito

// The models' colours (analytic blue, MuJoCo vermillion) as "#RRGGBB" and as RGB in [0, 1].
inline constexpr const char* kAnalyticColor = okabe_ito::kBlue;
inline constexpr const char* kMujocoColor = okabe_ito::kVermillion;
struct Rgb {
  float r, g, b;
};
// "#RRGGBB" -> RGB in [0, 1] (constexpr: the palette's strings are the single source).
constexpr Rgb rgbOf(const char* hex) {
  auto nib = [](char c) { return c <= '9' ? c - '0' : (c | 0x20) - 'a' + 10; };
  auto byte = [&](int i) { return static_cast<float>(nib(hex[i]) * 16 + nib(hex[i + 1])) / 255.0f; };
  return {byte(1), byte(3), byte(5)};
}

}  // namespace tailsim
