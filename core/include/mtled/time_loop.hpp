#pragma once
// The loop that advances a mechanical system: its integrator steps it to the end, and the monitors and writers
// (StepMonitor) are called around every step, in the order added.
#include <memory>
#include <vector>

#include "mtled/interfaces/integrator.hpp"
#include "mtled/json.hpp"
#include "mtled/mechanical_system.hpp"
#include "mtled/monitor.hpp"

namespace mtled {

class TimeLoop {
 public:
  TimeLoop(MechanicalSystem& system, std::shared_ptr<TimeIntegrator> integrator);
  TimeLoop(const TimeLoop&) = delete;
  TimeLoop& operator=(const TimeLoop&) = delete;

  // mtled/monitors/scene_monitors.hpp adds a scene's checks, mtled/io/run_outputs.hpp its writers; a writer the caller
  // keeps is added by shared pointer.
  void add_monitor(std::shared_ptr<StepMonitor> monitor);
  // Runs the integrator to its end, calling every monitor (and writer) around each step. Throws InstabilityError
  // when the integrator or a monitor stops the run; the system's state is then whole for the writers.
  void run();
  TimeIntegrator& integrator() { return *integrator_; }
  const TimeIntegrator& integrator() const { return *integrator_; }
  // Every monitor's record for summary.json, by name (writers have none).
  json monitor_reports() const;

 private:
  MechanicalSystem& system_;
  std::shared_ptr<TimeIntegrator> integrator_;
  std::vector<std::shared_ptr<StepMonitor>> monitors_;
  RunContext run_context_;  // what the monitors use, valid for the run
};

}  // namespace mtled
