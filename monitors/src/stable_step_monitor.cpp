#include "stable_step_monitor.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <iterator>

#include "mtled/discretisation.hpp"
#include "mtled/instability.hpp"
#include "mtled/log.hpp"
#include "mtled/monitors/reorthogonalise.hpp"

namespace mtled {
namespace {
// /monitors/stable_step's choices, in the order of StableStepMonitor::Response.
constexpr const char* kResponseNames[] = {"stop", "adapt", "follow"};
}  // namespace

void StableStepMonitor::declare(ComponentDeclaration& d) {
  d.integer("stable_step_every_steps")
      .defaults(2000)
      .non_negative()
      .unit("1")
      .doc(
          "re-estimate the stable time step 2 / sqrt(lambda_max(M^-1 K)) of the current, deformed body at step 1 and "
          "then every this many steps, by Lanczos iteration on finite differences of the internal forces (see "
          "stable_step for what follows); 0 turns the re-estimate off")
      .to<&Settings::stable_step_every_steps>();
  d.string("stable_step")
      .defaults("follow")
      .choices({"follow", "adapt", "stop"})
      .doc(
          "what a re-estimate does: \"adapt\" lowers the integrator's step to its margin of the estimate (0.9 for "
          "dynamic_relaxation, 0.5 for central_difference) when the step exceeds that (the margin covers the "
          "estimate's few percent, stiffening until the next re-estimate and, for central differences, the "
          "unsymmetric stiffness); \"follow\" also raises a steady-state integrator's step to that margin while "
          "its loads are held (re-estimated once as each hold begins, put back when the loads move again): the "
          "relaxation then takes fewer steps to the same steady state; \"stop\" ends the run (status "
          "\"unstable\", what \"time_step_above_stable\") when the step exceeds the estimate by more than 5%")
      .to<&Settings::stable_step>();
  d.integer("stable_step_iterations")
      .defaults(20)
      .between(2, 200)
      .unit("1")
      .doc(
          "Lanczos vectors per re-estimate (each one internal-force evaluation and one vector of memory); each "
          "estimate starts from the previous one's Ritz vector; the first, from a random one, uses three times as many")
      .to<&Settings::stable_step_iterations>();
}

std::unique_ptr<StableStepMonitor> StableStepMonitor::from_section(const Parameters& monitors,
                                                                   const Discretisation& model) {
  const auto settings = monitors.read<Settings>();
  if (settings.stable_step_every_steps == 0) return nullptr;
  // 1e-7 of the body's size: far inside the linear range of any element, far above round-off in the forces.
  const auto named = std::find(std::begin(kResponseNames), std::end(kResponseNames), settings.stable_step);
  return std::make_unique<StableStepMonitor>(settings.stable_step_every_steps, settings.stable_step_iterations,
                                             1e-7 * model.cloud().length_scale,
                                             static_cast<Response>(named - std::begin(kResponseNames)));
}

double StableStepMonitor::largest_eigenvalue(const StepRecord& step) {
  const auto mass = step.mass;
  // The largest eigenvalue of K v = lambda M v at the current state by Lanczos iteration on
  // A = M^-1/2 K M^-1/2 (full reorthogonalisation; a few dozen vectors), with A q from a forward difference of
  // the internal forces. Were K symmetric, the Ritz values would approach lambda_max from below and the estimate
  // could only overstate the stable step; variationally consistent integration makes K slightly unsymmetric,
  // and the estimate then lands within a few percent of 2 / sqrt(spectral radius) on either side
  // (tests/solver/stable_step_test.cpp). Hence the margins in check(): "stop" ends a run only when its step exceeds
  // the estimate by 5%, so a run that would finish is not stopped (beyond that the central-difference update, and
  // dynamic relaxation's, whose limit is the same as its damping vanishes, is unstable); "adapt" keeps the step
  // at the integrator's margin below the estimate. The iteration runs in the
  // constrained subspace (every vector projected as the constraint correction projects each step's update,
  // StepRecord::project_out): a mode that the constraints hold still, such as the tissue between the
  // driven points around a needle, cannot grow. The next check starts from this one's Ritz vector; the first,
  // from a random vector, uses three times as many.
  const std::size_t dofs = step.u.size();
  if (mode_.empty()) {
    // A fixed pseudo-random start (reproducible runs) with a component along every mode.
    mode_.resize(dofs);
    std::uint64_t state = 0x9E3779B97F4A7C15ULL;
    for (double& x : mode_) {
      state ^= state << 13, state ^= state >> 7, state ^= state << 17;
      x = static_cast<double>(state >> 11) / 9007199254740992.0 - 0.5;
    }
  }
  std::vector<double> f0(dofs), f1(dofs), perturbed(dofs), root_mass(dofs);
  for (std::size_t d = 0; d < dofs; ++d) root_mass[d] = std::sqrt(mass[d / 3]);
  if (run_->internal_forces(step.u, f0) >= 0) return 0.0;  // an inadmissible state is the other monitors' business
  ++force_evaluations_;

  // A random start needs more vectors than a warm one to resolve the top of the spectrum.
  const int size = checks_ == 0 ? 3 * iterations_ : iterations_;
  Eigen::MatrixXd q(static_cast<Eigen::Index>(dofs), size);
  Eigen::VectorXd alpha(size), beta(size);
  Eigen::VectorXd w(static_cast<Eigen::Index>(dofs));
  std::vector<double> increment(mode_);  // a displacement increment, projected into the constrained subspace
  run_->project_out(increment);
  for (std::size_t d = 0; d < dofs; ++d) w[static_cast<Eigen::Index>(d)] = root_mass[d] * increment[d];
  if (!(w.norm() > 0.0)) return 0.0;
  q.col(0) = w / w.norm();
  int built = 0;
  for (int j = 0; j < size; ++j) {
    // w = A q_j = M^-1/2 K M^-1/2 q_j, K x ~ (f(u + epsilon x) - f(u)) / epsilon
    double largest = 0.0;
    for (std::size_t d = 0; d < dofs; ++d) largest = std::max(largest, std::abs(q(static_cast<Eigen::Index>(d), j) / root_mass[d]));
    const double epsilon = perturbation_length_ / largest;
    for (std::size_t d = 0; d < dofs; ++d)
      perturbed[d] = step.u[d] + epsilon * q(static_cast<Eigen::Index>(d), j) / root_mass[d];
    ++force_evaluations_;
    if (run_->internal_forces(perturbed, f1) >= 0) return 0.0;
    // M^-1 K x, projected, then back to the symmetric form: w = M^1/2 P M^-1 K x.
    for (std::size_t d = 0; d < dofs; ++d) increment[d] = (f1[d] - f0[d]) / (epsilon * mass[d / 3]);
    run_->project_out(increment);
    for (std::size_t d = 0; d < dofs; ++d) w[static_cast<Eigen::Index>(d)] = root_mass[d] * increment[d];
    alpha[j] = q.col(j).dot(w);
    built = j + 1;
    // Full reorthogonalisation, twice (the forward difference makes A slightly unsymmetric).
    for (int pass = 0; pass < 2; ++pass) reorthogonalise(q, built, w, run_->for_each_share);
    beta[j] = w.norm();
    if (j + 1 == size || !(beta[j] > 1e-10 * std::abs(alpha[j]))) break;
    q.col(j + 1) = w / beta[j];
  }
  Eigen::MatrixXd t = Eigen::MatrixXd::Zero(built, built);
  for (int j = 0; j < built; ++j) {
    t(j, j) = alpha[j];
    if (j + 1 < built) t(j, j + 1) = t(j + 1, j) = beta[j];
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> ritz(t);
  const double lambda = ritz.eigenvalues()[built - 1];
  if (!(lambda > 0.0) || !std::isfinite(lambda)) return 0.0;
  const Eigen::VectorXd vector = q.leftCols(built) * ritz.eigenvectors().col(built - 1);
  for (std::size_t d = 0; d < dofs; ++d) mode_[d] = vector[static_cast<Eigen::Index>(d)] / root_mass[d];
  return lambda;
}

void StableStepMonitor::check(const StepRecord& step) {
  if (checks_ == 0) setup_estimate_ = step.stable_time_step;
  const double lambda = largest_eigenvalue(step);
  if (!(lambda > 0.0)) return;
  ++checks_;
  last_stable_step_ = 2.0 / std::sqrt(lambda);
  if (last_stable_step_ < smallest_stable_step_) {
    smallest_stable_step_ = last_stable_step_;
    smallest_stable_step_at_ = step.load.step;
  }
  log().debug("step {}: stable step re-estimated {:.4g} s (time step {:.4g} s)", step.load.step, last_stable_step_,
              step.step_size);
  if (response_ != Response::stop) {
    // The integrator's own margin (IntegratorReport::stable_step_margin): the estimate lands within a few percent
    // of the true limit on either side (tests/solver), the body may stiffen further until the next check, and
    // central differences lose accuracy well before the limit (docs/stability.md).
    const double margin = run_->stable_step_margin;
    if (run_->step_control == nullptr) return;
    const double target = margin * last_stable_step_;
    if (step.step_size > target) {
      run_->step_control->set_stable_time_step(target / run_->time_step_factor);
      ++lowered_;
      lowest_step_ = std::min(lowest_step_, target);
      return;
    }
    // Raised only while a steady-state integrator holds its loads: at a held load the body settles and its stiffness
    // with it, where a moving load may stiffen it any amount between two checks (fourfold over the brain phantom's
    // insertion). Dynamic relaxation's time is fictitious, so its step changes the path, not the steady state.
    // Not for less than 5%: each change re-tunes the relaxation's damping. Never above 4 times the setup's
    // per-point bound: the bound undercuts the undeformed body's stable step by 3 to 4 on the shipped clouds, so a
    // larger estimate is of a subspace the constraints nearly fill (a fully prescribed body's is empty, its estimate
    // arbitrary), where the step would be limited by the constraint correction's round-off, not by the dynamics.
    constexpr double kWorthRaising = 1.05, kMostOverSetupBound = 4.0;
    const double raised = std::min(target, kMostOverSetupBound * setup_estimate_);
    if (!raises_ || !held_ || !(raised > kWorthRaising * step.step_size)) return;
    if (stable_before_raise_ == 0.0) stable_before_raise_ = step.stable_time_step;
    run_->step_control->set_stable_time_step(raised / run_->time_step_factor);
    ++raised_;
    highest_step_ = std::max(highest_step_, raised);
    return;
  }
  constexpr double kMargin = 1.05;
  if (!(step.step_size > kMargin * last_stable_step_)) return;
  refuse(step);
}

void StableStepMonitor::follow_loads(const StepRecord& step) {
  const bool held = step.load.load_fraction == previous_load_fraction_;
  previous_load_fraction_ = step.load.load_fraction;
  if (held && !held_) hold_check_at_ = step.load.step + 1;  // the displacement is read then (reads_displacement)
  if (!held && held_ && stable_before_raise_ > 0.0) {
    // The loads move again: back to the step the ramp had (or the lowered one, if a check lowered it since). One
    // step of the new ramp was taken with the raised step, from the settled state it was estimated for.
    if (run_->step_control != nullptr)
      run_->step_control->set_stable_time_step(std::min(step.stable_time_step, stable_before_raise_));
    stable_before_raise_ = 0.0;
  }
  held_ = held;
}

void StableStepMonitor::refuse(const StepRecord& step) const {
  const Discretisation& model = *run_->discretisation;
  const double step_size = step.step_size;
  // Where the fastest mode lives: the node with the largest share of it.
  Index where = 0;
  double share = 0.0;
  for (std::size_t d = 0; d < mode_.size(); ++d)
    if (std::abs(mode_[d]) > share) {
      share = std::abs(mode_[d]);
      where = static_cast<Index>(d / 3);
    }
  throw node_instability(
      step.load.step, step.load.time, "time_step_above_stable",
      fmt::format("the time step {:.4g} s exceeds the stable step of the current state, {:.4g} s = "
                  "2 / sqrt(lambda_max(M^-1 K)) re-estimated at step {} ({:.3g} times the setup estimate {:.4g} s); "
                  "its fastest mode is largest at node {} at {} m; reduce /integrator/time_step_factor to {:.2g} or "
                  "less",
                  step_size, last_stable_step_, step.load.step, last_stable_step_ / step.stable_time_step,
                  step.stable_time_step, where, point_text(model.nodes()[where]),
                  0.9 * last_stable_step_ / step_size * run_->time_step_factor),
      model, where);
}

json StableStepMonitor::report() const {
  json j = {{"every_steps", every_},
            {"on_step_above_estimate", kResponseNames[static_cast<int>(response_)]},
            {"checks", checks_},
            {"force_evaluations", force_evaluations_},
            {"setup_estimate_s", setup_estimate_}};
  if (checks_ > 0) {
    j["last_estimate_s"] = last_stable_step_;
    j["smallest_estimate_s"] = smallest_stable_step_;
    j["smallest_estimate_step"] = smallest_stable_step_at_;
  }
  if (response_ != Response::stop) {
    j["time_step_lowered"] = lowered_;
    if (lowered_ > 0) j["lowest_time_step_s"] = lowest_step_;
  }
  if (response_ == Response::follow) {
    j["time_step_raised"] = raised_;
    if (raised_ > 0) j["highest_time_step_s"] = highest_step_;
  }
  return j;
}

}  // namespace mtled
