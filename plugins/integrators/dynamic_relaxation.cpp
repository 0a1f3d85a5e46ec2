// `dynamic_relaxation`: adaptive dynamic relaxation for steady (quasi-static) solutions (Joldes, Wittek,
// Miller, "Computation of intra-operative brain shift using dynamic relaxation", CMAME 2009, and "An
// adaptive dynamic relaxation method for solving nonlinear finite element problems", IJNMBE 2011).
//
// The damped central-difference iteration u+ = u + beta (u - u-) + alpha M^-1 (f_ext - f_int) converges
// fastest with beta = rho^2, alpha = ((1 + rho) h / 2)^2, rho = (k - 1)/(k + 1), k = 2 / (h w_min), where
// h is (a safe fraction of) the critical step and w_min the lowest eigenfrequency of M^-1 K. w_min is
// re-estimated every few steps from the last increment: w^2 ~ du.(f(u_n) - f(u_n-1)) / du.M du. That Rayleigh
// quotient lies at or above the lowest eigenvalue, and a damping tuned above w_min slows the lowest mode far more
// than one tuned below it by the same ratio (decay rate w_min (c - sqrt(c^2 - 1)) against c w_min for a damping at
// c w_min), so while a load is held the damping is tuned to a fraction of the estimate (held_damping_factor).
//
// The consistent-integration correction makes the internal forces' Jacobian nonsymmetric (the test gradients are
// not the trial ones), and a nonsymmetric operator can have complex eigenvalue pairs: modes that grow (flutter)
// unless damped faster than they grow. On the default needle scene one near h w = 1.3 grows at about 110 /s; the mass
// damping, tuned to the slowest mode (about 60 rad/s there), is too weak for it, and the estimate then followed the
// growing mode up and damped the slowest mode far above its frequency. While a load is held a little
// stiffness-proportional damping (held_stiffness_damping: the damping ratio gamma h w / 2, nearly nothing at the
// slowest mode) holds those modes down, so the mass damping can stay at the slowest mode.
//
// The distance to the steady state is estimated two ways, and the larger taken: from the increment, the geometric
// series |du| rho / (1 - rho) of a mode decaying at rate rho; and from the residual r = f_ext - f_int, whose part of
// the increment is alpha M^-1 r = du_(n+1) - beta du_n: a mode of frequency w lies |M^-1 r| / w^2 from its rest
// state, and alpha w^2 = (1 - rho)^2 at the damping's frequency. An underdamped mode's increment passes through zero
// at each turning point, where its residual is largest; with the first estimate alone the relaxation stopped there,
// on the default needle scene at 11 times its tolerance.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "integrator_parameters.hpp"
#include "mtled/errors.hpp"
#include "mtled/interfaces/integrator.hpp"
#include "mtled/log.hpp"
#include "mtled/plugin.hpp"

namespace mtled {

class DynamicRelaxationIntegrator final : public TimeIntegrator {
 public:
  static void declare(ComponentDeclaration& d) {
    d.summary(
        "Adaptive dynamic relaxation: loads are applied over `load_steps` steps, then the iteration continues "
        "until the estimated distance to the steady state is below `tolerance`.");
    declare_time_step_factor(d);
    d.integer("load_steps")
        .unit("1")
        .at_least(1)
        .defaults(2000)
        .doc(
            "steps over which the loads grow from 0 to full; more steps follow a path-dependent load (the needle) "
            "more quasi-statically")
        .to<&Settings::load_steps>();
    declare_load_curve(d);
    d.number("tolerance")
        .unit("1")
        .positive()
        .less_than(1.0)
        .defaults(1e-6)
        .doc(
            "stop when the estimated distance to the steady state (max over nodes) is below this fraction of the "
            "largest displacement")
        .to<&Settings::tolerance>();
    d.integer("converged_steps")
        .unit("1")
        .at_least(1)
        .defaults(20)
        .doc("consecutive steps the error estimate must stay under the tolerance")
        .to<&Settings::converged_steps>();
    d.integer("max_steps")
        .unit("1")
        .at_least(1)
        .defaults(2000000)
        .doc("give up (status unstable, what \"not_converged\") after this many steps")
        .to<&Settings::max_steps>();
    d.boolean("mass_scaling")
        .defaults(true)
        .doc(
            "scale the density per integration point so every point has the same critical time step (changes the "
            "path to the steady state, not the steady state)")
        .to<&Settings::mass_scaling>();
    d.boolean("held_mass_scaling")
        .defaults(true)
        .doc(
            "with mass_scaling, scale the masses again as each hold begins, to the body's current stiffness (each "
            "integration point's largest tangent modulus dP/dF against its value at rest), so that the tissue a load "
            "stiffened (the sleeve the needle shears) no longer holds the whole body's stable step down while it "
            "relaxes; with the stable-step monitor's \"follow\" the step then rises to what the rest of the body "
            "allows. Changes the path to the steady state, not the steady state")
        .to<&Settings::held_mass_scaling>();
    d.integer("relaxed_increments")
        .unit("1")
        .at_least(1)
        .defaults(1)
        .doc(
            "relax to the steady state at this many equally spaced loads (1/N, 2/N, ... of the full load, each reached "
            "along the load curve, held while the body relaxes), so that needle.csv and reactions.csv hold the forces "
            "in equilibrium at each; 1 relaxes only at full load. Where the answer depends on the loading path (the "
            "kinematic needle captures tissue as it advances), ramp slowly enough (load_steps) that each row equals a "
            "run "
            "relaxed at that load: on the default scene 8000 (docs/validation.md)")
        .to<&Settings::relaxed_increments>();
    declare_held_damping(d);
    d.example({{"load_steps", 200}, {"tolerance", 1e-5}});
  }

  explicit DynamicRelaxationIntegrator(const Parameters& p)
      : DynamicRelaxationIntegrator(p.read<IntegratorCommon>(), p.read<Settings>()) {}

  void initialise(DiscreteSystem& system) override {
    unscaled_stable_ = system.stable_time_step();
    if (mass_scaling_) system.equalise_critical_steps();
    stable_in_use_ = system.stable_time_step();
    h_ = factor_ * stable_in_use_;
    // Start heavily damped (k = 20) until the first estimate of the lowest frequency arrives.
    estimated_frequency_ = 0.1 * 2.0 / h_;
    set_frequency(estimated_frequency_);
  }

  void step(DiscreteSystem& system) override {
    // The stable step was lowered (the body stiffened): go on with the smaller step. The last increment, made
    // with the old step, is rescaled to the new one in this update (beta times the ratio of the steps).
    double increment_scale = 1.0;
    if (const double stable = system.stable_time_step(); stable != stable_in_use_) {
      increment_scale = stable / stable_in_use_;
      stable_in_use_ = stable;
      time_origin_ = system.time();
      step_origin_ = system.step();
      h_ = factor_ * stable;
      set_frequency(std::min(damping_frequency_, 2.0 / h_));
    }
    // The lowest frequency is re-estimated from the last increment before this step's coefficients are set.
    const long n = system.step();
    // Held from this step on when the ramp had reached the increment's end before it (the ramp's steps never use it).
    const double gamma = held() ? held_stiffness_damping_ : 0.0;
    if (held() && mass_scaling_ && held_mass_scaling_ && masses_scaled_for_ != relaxed_) {
      system.equalise_current_critical_steps();
      masses_scaled_for_ = relaxed_;
    }
    const bool estimate = n >= 2 && n % update_every_ == 0;
    IncrementSums increment;
    try {
      increment = system.evaluate_forces(estimate);
    } catch (const InstabilityError& e) {
      rethrow_with_ramp_advice(e, load_moved_last_step_,
                               fmt::format("after {} of /integrator/load_steps = {}", ramp_step_, load_steps_),
                               "load_steps", std::to_string(2 * load_steps_));
    }
    if (estimate) estimate_frequency(increment);
    // The ramp advances until the current increment's end, then holds while the body relaxes.
    load_moved_last_step_ = !held();
    if (load_moved_last_step_) ++ramp_step_;
    const double fraction = increment_load_fraction();
    const StepSums sums = system.advance({alpha_, beta_ * increment_scale, gamma},
                                         time_origin_ + static_cast<double>(n + 1 - step_origin_) * h_, fraction);
    if (held()) relax(system, sums);
    // A long relaxation shows nothing else while it runs (--log-level debug).
    if ((n + 1) % 500 == 0)
      log().debug(
          "dynamic relaxation step {}: lowest frequency {:.4g} rad/s (damped at {:.4g}), rate {:.6f}, error "
          "bound {:.3g} m ({:.3g} of the largest displacement)",
          n + 1, estimated_frequency_, damping_frequency_, rho_, error_bound_, relative_error_bound());
    if (!converged_ && system.step() >= max_steps_) {
      Diagnostic d;
      d.step = system.step();
      d.time = system.time();
      d.what = "not_converged";
      // Stopped while still loading, there is no error estimate yet: say how far the load got instead.
      d.detail = ramp_step_ < load_steps_
                     ? fmt::format("dynamic relaxation stopped at /integrator/max_steps = {} while still applying the "
                                   "load (step {} of /integrator/load_steps = {}{}); raise max_steps above load_steps",
                                   max_steps_, ramp_step_, load_steps_,
                                   increments_ > 1 ? fmt::format(", {} of {} relaxed increments done", relaxed_,
                                                                 increments_)
                                                   : "")
                     : fmt::format("dynamic relaxation did not reach the steady state in {} steps: estimated error "
                                   "{:.3g} m against a tolerance of {:.3g} m; raise /integrator/max_steps or "
                                   "/integrator/tolerance",
                                   max_steps_, error_bound_, tolerance_ * largest_displacement_);
      throw InstabilityError(std::move(d));
    }
  }

  bool finished(const DiscreteSystem&) const override { return converged_; }

  IntegratorReport report() const override {
    IntegratorReport r;
    r.type = "dynamic_relaxation";
    r.time_step = h_;
    r.stable_time_step = unscaled_stable_;
    r.time_step_factor = factor_;
    r.relaxation =
        RelaxationReport{converged_, error_bound_, relative_error_bound(), tolerance_, estimated_frequency_, rho_};
    r.settings = {{"mass_scaling", mass_scaling_},
                  {"held_mass_scaling", held_mass_scaling_},
                  {"load_steps", load_steps_},
                  {"relaxed_increments", increments_},
                  {"held_damping_factor", held_damping_factor_},
                  {"held_stiffness_damping", held_stiffness_damping_}};
    return r;
  }

 private:
  struct Settings {
    long load_steps = 0;
    double tolerance = 0.0;
    long converged_steps = 0;
    long max_steps = 0;
    bool mass_scaling = false;
    bool held_mass_scaling = false;
    long relaxed_increments = 0;
    double held_damping_factor = 0.0;
    double held_stiffness_damping = 0.0;
    long damping_update_steps = 0;
  };

  // The damping while a load is held, and how often it is re-estimated.
  static void declare_held_damping(ComponentDeclaration& d) {
    d.number("held_damping_factor")
        .unit("1")
        .positive()
        .at_most(1.0)
        .defaults(0.8)
        .doc(
            "while a load is held, tune the damping to this fraction of the estimated lowest frequency: the estimate "
            "lies at or above the lowest frequency (it is a Rayleigh quotient, and the body softens as it settles), "
            "and damping tuned above the lowest frequency slows its mode far more than damping tuned as far below it; "
            "1 tunes it to the estimate itself. The ramp always uses the estimate, so the loading path does not depend "
            "on this")
        .to<&Settings::held_damping_factor>();
    d.number("held_stiffness_damping")
        .unit("1")
        .at_least(0.0)
        .at_most(0.1)
        .defaults(0.05)
        .doc(
            "while a load is held, add stiffness-proportional damping b K v with b = this times the time step (from "
            "the last two force evaluations): a mode at h w gets the damping ratio this x h w / 2, so the highest "
            "modes are damped and the slowest is nearly untouched; it holds down modes that the consistent-integration "
            "correction's nonsymmetric forces make grow. It lowers the largest stable step by 1 / sqrt(1 + 2 x this) "
            "(5% at 0.05, inside the step's 0.9 margin); 0 turns it off. The ramp never uses it")
        .to<&Settings::held_stiffness_damping>();
    d.integer("damping_update_steps")
        .unit("1")
        .at_least(1)
        .defaults(10)
        .doc("re-estimate the lowest eigenfrequency (and so the damping) every this many steps")
        .to<&Settings::damping_update_steps>();
  }

  DynamicRelaxationIntegrator(const IntegratorCommon& common, const Settings& s)
      : factor_(common.time_step_factor),
        load_steps_(s.load_steps),
        curve_(load_curve_from(common)),
        tolerance_(s.tolerance),
        converged_steps_(s.converged_steps),
        max_steps_(s.max_steps),
        mass_scaling_(s.mass_scaling),
        held_mass_scaling_(s.held_mass_scaling),
        increments_(s.relaxed_increments),
        update_every_(s.damping_update_steps),
        held_damping_factor_(s.held_damping_factor),
        held_stiffness_damping_(s.held_stiffness_damping) {}

  // The ramp step at which increment k (0-based) begins; increment_end() is where the current one ends.
  long increment_start(long k) const {
    return static_cast<long>(std::llround(static_cast<double>(load_steps_) * static_cast<double>(k) /
                                          static_cast<double>(increments_)));
  }
  long increment_end() const { return increment_start(std::min(relaxed_ + 1, increments_)); }
  // The ramp has reached the current increment's load and holds it while the body relaxes.
  bool held() const { return ramp_step_ >= increment_end(); }

  // Each increment carries the load from k / N to (k + 1) / N along the load curve (so the relaxed states sit at
  // exactly k / N of the load, and a smooth curve starts and stops each increment without a jolt); one increment
  // is the whole ramp.
  double increment_load_fraction() const {
    const long k = std::min(relaxed_, increments_ - 1);
    const long begin = increment_start(k), end = increment_start(k + 1);
    const double local = end > begin ? static_cast<double>(ramp_step_ - begin) / static_cast<double>(end - begin) : 1.0;
    return (static_cast<double>(k) + load_fraction(curve_, local)) / static_cast<double>(increments_);
  }

  // Held at an increment's load: when the body is at rest there, count the equilibrium and go on loading (or
  // finish at the last).
  void relax(DiscreteSystem& system, const StepSums& sums) {
    if (!steady(sums)) return;
    system.steady_state_reached();
    ++relaxed_;
    if (relaxed_ >= increments_) {
      converged_ = true;
      return;
    }
    below_ = 0;
  }

  // The error bound as a fraction of the largest displacement (0 before there is any displacement).
  double relative_error_bound() const {
    return largest_displacement_ > 0 ? error_bound_ / largest_displacement_ : 0.0;
  }

  void set_frequency(double omega) {
    damping_frequency_ = omega;
    const double k = std::max(2.0 / (h_ * omega), 1.0 + 1e-12);
    rho_ = (k - 1.0) / (k + 1.0);
    beta_ = rho_ * rho_;
    alpha_ = 0.25 * (1.0 + rho_) * (1.0 + rho_) * h_ * h_;
  }

  // w^2 ~ du.(f(u_n) - f(u_n-1)) / du.M du from the last increment; the damping's frequency from it.
  void estimate_frequency(const IncrementSums& increment) {
    if (!(increment.inertia > 0.0) || !(increment.stiffness > 0.0) || !std::isfinite(increment.stiffness / increment.inertia))
      return;
    estimated_frequency_ = std::sqrt(increment.stiffness / increment.inertia);
    set_frequency(std::min((held() ? held_damping_factor_ : 1.0) * estimated_frequency_, 2.0 / h_));
  }

  // Updates the error estimate from the step just completed (the header: from the increment and from the residual);
  // true once it has stayed under the tolerance for converged_steps steps.
  bool steady(const StepSums& sums) {
    largest_displacement_ = sums.largest_displacement;
    const double from_increment = sums.largest_increment * rho_ / (1.0 - rho_);
    const double from_residual = sums.largest_residual_step / ((1.0 - rho_) * (1.0 - rho_));
    error_bound_ = rho_ < 1.0 ? std::max(from_increment, from_residual) : INFINITY;
    below_ = error_bound_ <= tolerance_ * largest_displacement_ ? below_ + 1 : 0;
    return below_ >= converged_steps_;
  }

  double factor_;
  long load_steps_;
  LoadCurve curve_;
  double tolerance_;
  long converged_steps_, max_steps_;
  bool mass_scaling_;
  bool held_mass_scaling_;
  long increments_;
  long update_every_;
  double held_damping_factor_;
  double held_stiffness_damping_;

  double unscaled_stable_ = 0.0, stable_in_use_ = 0.0, h_ = 0.0;
  double time_origin_ = 0.0;  // pseudo-time and step at which the step size last changed
  long step_origin_ = 0;
  double estimated_frequency_ = 0.0, damping_frequency_ = 0.0;  // rad/s: the last estimate; the damping's
  double rho_ = 0.0, alpha_ = 0.0, beta_ = 0.0;
  double error_bound_ = INFINITY, largest_displacement_ = 0.0;
  long below_ = 0;
  long ramp_step_ = 0;  // steps of the load ramp taken (the ramp holds while an increment relaxes)
  bool load_moved_last_step_ = false;  // the state the next forces are evaluated in was made by a ramp step
  long relaxed_ = 0;    // increments relaxed to the steady state
  long masses_scaled_for_ = -1;  // the increment whose hold last scaled the masses to the current stiffness
  bool converged_ = false;
};

}  // namespace mtled

MTLED_PLUGIN(mtled::TimeIntegrator, mtled::DynamicRelaxationIntegrator)
