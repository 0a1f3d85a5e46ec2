#pragma once
// How the applied load (prescribed displacements, needle depth) grows from 0 to 1 over the loading time.
// "smooth" is the quintic 10x^3 - 15x^4 + 6x^5: zero velocity and acceleration at both ends, so loading
// starts and stops without exciting the high modes (the quintic "smoothstep" ramp).
#include <algorithm>
#include <string>

namespace mtled {

enum class LoadCurve { linear, smooth };

inline LoadCurve load_curve_from_string(const std::string& name) {
  return name == "linear" ? LoadCurve::linear : LoadCurve::smooth;
}

inline double load_fraction(LoadCurve curve, double x) {
  x = std::clamp(x, 0.0, 1.0);
  if (curve == LoadCurve::linear) return x;
  return x * x * x * (10.0 + x * (-15.0 + 6.0 * x));
}

}  // namespace mtled
