#pragma once
// Who reads the displacement u_n, said in one place: the drivers before their update (Driver::nodes_read) and the
// monitors after a step (StepMonitor::reads_displacement). The mechanical system hands the plan's answers to its step
// engine: an engine that spreads the nodes over processes or keeps them on a device (StepEngine::spreads_nodes)
// brings just the drivers' nodes before an update, and the whole field only after the steps some monitor reads.
#include <memory>
#include <span>
#include <vector>

#include "mtled/interfaces/driver.hpp"
#include "mtled/monitor.hpp"

namespace mtled {

class ReadPlan {
 public:
  // `selective`: the engine brings only what it is asked for; otherwise every read is of the whole field.
  ReadPlan(std::vector<const Driver*> drivers, bool selective);
  // The monitors the time loop calls after each step (set before the run).
  void set_monitors(std::span<const std::shared_ptr<StepMonitor>> monitors);
  // The nodes the drivers' coming update(load, ...) reads, sorted and unique; false: all of them.
  bool driver_nodes(const LoadState& load, const Discretisation& discretisation, std::vector<Index>& nodes) const;
  // Whether some monitor reads the whole of u_(n+1) after step n -> n + 1 (`step` = n + 1).
  bool monitors_read(long step) const;

 private:
  std::vector<const Driver*> drivers_;
  std::vector<const StepMonitor*> monitors_;
  bool selective_ = false;
};

}  // namespace mtled
