#pragma once
// What the integrators share: the stable-step factor; how the applied load (prescribed displacements, needle depth)
// grows from 0 to 1 over the loading time, and what a stop while it grows advises. "smooth" is the quintic
// 10x^3 - 15x^4 + 6x^5: zero velocity and acceleration at both ends, so loading starts and stops without exciting the
// high modes (the quintic "smoothstep" ramp).
#include <fmt/format.h>

#include <algorithm>
#include <string>

#include "mtled/errors.hpp"
#include "mtled/parameters.hpp"

namespace mtled {

enum class LoadCurve { linear, smooth };

// The parameters every integrator here declares with the two functions below, read with
// Parameters::read<IntegratorCommon>().
struct IntegratorCommon {
  double time_step_factor = 0.0;
  std::string load_curve;
};

// Declares "time_step_factor", the same for every explicit integrator.
inline void declare_time_step_factor(ComponentDeclaration& d) {
  d.number("time_step_factor")
      .unit("1")
      .positive()
      .defaults(0.9)
      .doc(
          "multiplier on the estimated stable time step; above 1 risks instability, which the stability monitors "
          "then report")
      .to<&IntegratorCommon::time_step_factor>();
}

// Declares "load_curve", the one declaration every integrator that ramps its loads shares; read it back with
// load_curve_from(common).
inline void declare_load_curve(ComponentDeclaration& d) {
  d.string("load_curve")
      .defaults("smooth")
      .choices({"smooth", "linear"})
      .doc(
          "shape of the load ramp: smooth (10x^3 - 15x^4 + 6x^5: no velocity or acceleration jump at either end, so "
          "the "
          "ramp excites no high modes) or linear (constant rate)")
      .to<&IntegratorCommon::load_curve>();
}

inline LoadCurve load_curve_from(const IntegratorCommon& common) {
  return common.load_curve == "linear" ? LoadCurve::linear : LoadCurve::smooth;
}

inline double load_fraction(LoadCurve curve, double x) {
  x = std::clamp(x, 0.0, 1.0);
  if (curve == LoadCurve::linear) return x;
  return x * x * x * (10.0 + x * (-15.0 + 6.0 * x));
}

// Called in a catch block for an instability found while evaluating the forces. When the material inverted in a state
// a loading step made (`loading`), the load may have moved faster than the body can follow (the brain phantom's needle
// over 1,000 load steps inverts the sleeve at step 979 and runs through over 2,000): the error is thrown again with
// `where` the ramp stood and which `setting` to raise (`example`: twice its value). A fold the deformation itself makes
// (docs/validation.md's graded compression, its free side folding onto the platen) does not go away with a slower
// ramp, and the advice says so too. Otherwise the error is rethrown as it was.
[[noreturn]] inline void rethrow_with_ramp_advice(const InstabilityError& error, bool loading, const std::string& where,
                                                  const std::string& setting, const std::string& example) {
  if (!loading || error.diagnostic().what != "inverted_material") throw;
  Diagnostic d = error.diagnostic();
  d.detail += fmt::format(
      "; it happened while applying the load ({}), whose steps may outrun the body: raise {} (for example to {}); if "
      "it inverts again at the same load, the deformation itself folds the material there and no slower ramp helps",
      where, setting, example);
  throw InstabilityError(std::move(d));
}

}  // namespace mtled
