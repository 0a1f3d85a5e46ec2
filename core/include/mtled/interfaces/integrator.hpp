#pragma once
// Time integrators and the narrow view of the simulation they work on.
#include <cmath>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "mtled/json.hpp"
#include "mtled/parameters.hpp"
#include "mtled/types.hpp"

namespace mtled {

// du.(f_n - f_(n-1)) and du.M du with du = u_n - u_(n-1): dynamic relaxation's estimate of the lowest frequency.
struct IncrementSums {
  double stiffness = 0.0;  // N m
  double inertia = 0.0;    // kg m^2
};

// What a completed step u_n -> u_(n+1) leaves for the integrator and the monitors, reduced over the unknowns where
// they live. u~ is the step's prediction before the constraint projection.
struct StepSums {
  double largest_increment = 0.0;     // max |u_(n+1) - u_n| over the unknowns (m)
  double largest_displacement = 0.0;  // max |u_(n+1)| (m)
  // sum over the unknowns d of m max(0, (u_(n+1) - u_n)_d^2 - (u~ - u_n)_d^2): what the projection added to the
  // squared increments (kg m^2; the energy monitor's work of the prescribed motion).
  double projection_energy = 0.0;
  // sum_I m_I (u_n - u_(n-1)).(u_(n+1) - u_n): the product of the half-step velocities around step n (kg m^2).
  double kinetic_product = 0.0;
  Index fastest_node = 0;  // the node with the largest |m_I (u_n - u_(n-1)).(u_(n+1) - u_n)|
  // max |(u_(n+1) - u_n) - beta (u_n - u_(n-1))| over the unknowns (m): alpha M^-1 times the residual after the
  // projection, the part of the increment the forces made this step.
  double largest_residual_step = 0.0;
};

// The coefficients of one damped central-difference step (explicit_update.hpp):
//   u_(n+1) = u_n + beta (u_n - u_(n-1)) + alpha M^-1 (f_ext - f_int(u_n) - gamma (f_int(u_n) - f_int(u_(n-1)))).
// beta < 1 is mass-proportional damping; gamma > 0 stiffness-proportional damping (b K v with b = gamma h: a mode at
// h w has the damping ratio gamma h w / 2), which damps the highest modes and leaves the lowest nearly alone.
struct UpdateCoefficients {
  double alpha = 0.0;
  double beta = 1.0;
  double gamma = 0.0;
};

// The semi-discrete equations of motion M u'' + f_int(u) = f_ext(t), M lumped (one mass per node, three
// unknowns per node), and the one call that completes a step. The kernel implements it for a scene; the
// integrator conformance suite implements it for linear oscillators. An integrator sees nothing else.
class DiscreteSystem {
 public:
  virtual ~DiscreteSystem();

  virtual std::span<const double> displacement() const = 0;           // u_n, 3 per node
  virtual std::span<const double> previous_displacement() const = 0;  // u_(n-1)
  virtual std::span<const double> mass() const = 0;                   // per node (kg)
  virtual long step() const = 0;                                      // n
  virtual double time() const = 0;                                    // s (pseudo-time for relaxation)

  // Critical time step of the explicit update for the masses in use, before any safety factor.
  virtual double stable_time_step() const = 0;
  // Mass scaling, valid for steady-state solutions only: raises the masses so that every part of the body has
  // the critical step of its slowest part; stable_time_step() then returns that step.
  virtual void equalise_critical_steps() = 0;
  // Mass scaling again at the current state, after equalise_critical_steps(): raises the masses where the body has
  // stiffened since the setup, so that each part regains the critical step that call gave it (stable_time_step()
  // unchanged). For a steady-state integrator while it holds its loads. The default does nothing (a system whose
  // stiffness does not change with its state).
  virtual void equalise_current_critical_steps() {}

  // f = f_int(u). Throws InstabilityError when u is inadmissible (inverted material).
  virtual void internal_forces(std::span<const double> u, std::span<double> f) = 0;
  virtual bool has_external_forces() const = 0;
  // f = f_ext at the current load.
  virtual void external_forces(std::span<double> f) = 0;
  // Makes u_new the state of step n + 1 at `time` with the loads at `load_fraction`: the drivers move, the
  // constraints correct u_new in place. `alpha` is the integrator's factor on M^-1 f in its update, so that the
  // constraint forces (reactions) are the correction over alpha.
  virtual void complete_step(std::span<double> u_new, double time, double load_fraction, double alpha) = 0;
  // Called by a steady-state integrator right after complete_step when the state just completed is at rest at its
  // load (a relaxed load increment): what the outputs record as an equilibrium.
  virtual void steady_state_reached() {}

  // The damped central-difference family (UpdateCoefficients) in two calls, so that the kernel can keep the vectors
  // where it computes them (a GPU backend) and fuse the passes: evaluate_forces() computes f_int(u_n) (and, when
  // asked, IncrementSums, before the coefficients are chosen); advance() makes the update and completes the step as
  // complete_step() does, and returns the step's sums. Both shipped integrators step this way. The defaults go
  // through the calls above (and fill only largest_increment, largest_displacement and largest_residual_step); the
  // kernel overrides them.
  virtual IncrementSums evaluate_forces(bool increment_sums);
  virtual StepSums advance(const UpdateCoefficients& update, double time, double load_fraction);

 private:
  std::vector<double> f_int_, f_int_previous_, f_ext_, u_next_, carried_;  // the defaults' vectors
};

// A steady-state integrator's account of how far it is from the steady state.
struct RelaxationReport {
  bool converged = false;
  double error_bound = INFINITY;      // m: bound on the distance to the steady state, largest over the unknowns
  double relative_error_bound = 0.0;  // error_bound over the largest displacement (0 before any)
  double tolerance = 0.0;             // on relative_error_bound
  double lowest_frequency = 0.0;      // rad/s: the last estimate (the damping is tuned to it or a fraction of it)
  double convergence_rate = 0.0;      // per step
};

struct IntegratorReport {
  std::string type;
  double time_step = 0.0;         // s
  double stable_time_step = 0.0;  // s, of the unscaled masses, before the factor
  double time_step_factor = 1.0;
  // The largest fraction of the current body's stable step the integrator should take: the stable-step monitor
  // lowers the step to it when a re-estimate shows the step above it.
  double stable_step_margin = 0.9;
  std::optional<RelaxationReport> relaxation;  // steady-state integrators only
  json settings = json::object();              // the integrator's other settings and counts
};

// The "integrator" object of summary.json.
json to_json(const IntegratorReport& report);

// Advances a DiscreteSystem in time: initialise once, then step until finished.
class TimeIntegrator {
 public:
  static constexpr Category category = Category::integrator;
  virtual ~TimeIntegrator();

  virtual void initialise(DiscreteSystem& system) = 0;
  // One step, ending with system.complete_step(...). Throws InstabilityError when it must give up.
  virtual void step(DiscreteSystem& system) = 0;
  virtual bool finished(const DiscreteSystem& system) const = 0;
  virtual IntegratorReport report() const = 0;
};

}  // namespace mtled
