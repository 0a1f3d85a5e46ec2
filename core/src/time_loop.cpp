#include "mtled/time_loop.hpp"

#include "mtled/instability.hpp"

namespace mtled {

TimeLoop::TimeLoop(MechanicalSystem& system, std::shared_ptr<TimeIntegrator> integrator)
    : system_(system), integrator_(std::move(integrator)) {}

void TimeLoop::add_monitor(std::shared_ptr<StepMonitor> monitor) { monitors_.push_back(std::move(monitor)); }

json TimeLoop::monitor_reports() const {
  json reports = json::object();
  for (const auto& monitor : monitors_)
    if (json report = monitor->report(); !report.is_null()) reports[monitor->name()] = std::move(report);
  return reports;
}

void TimeLoop::run() {
  integrator_->initialise(system_);
  run_context_ = system_.start_run(monitors_);
  run_context_.integrator = integrator_.get();
  const IntegratorReport report = integrator_->report();
  run_context_.time_step_factor = report.time_step_factor;
  run_context_.stable_step_margin = report.stable_step_margin;
  const StepRecord initial = system_.last_step();
  for (const auto& monitor : monitors_) monitor->before_run(run_context_, initial);
  try {
    while (!integrator_->finished(system_)) {
      integrator_->step(system_);
      const StepRecord step = system_.last_step();
      for (const auto& monitor : monitors_) monitor->after_step(step);
    }
  } catch (const InstabilityError&) {
    system_.share_state();  // every process finds an instability alike; the writers then read the last states
    throw;
  }
  system_.share_state();
  if (system_.step() > 0) {
    const StepRecord last = system_.last_step();
    for (const auto& monitor : monitors_) monitor->after_run(last);
  }
}

}  // namespace mtled
