#include "mtled/read_plan.hpp"

#include <algorithm>

namespace mtled {

ReadPlan::ReadPlan(std::vector<const Driver*> drivers, bool selective)
    : drivers_(std::move(drivers)), selective_(selective) {}

void ReadPlan::set_monitors(std::span<const std::shared_ptr<StepMonitor>> monitors) {
  monitors_.clear();
  for (const auto& monitor : monitors) monitors_.push_back(monitor.get());
}

bool ReadPlan::driver_nodes(const LoadState& load, const Discretisation& discretisation,
                            std::vector<Index>& nodes) const {
  if (!selective_) return false;
  nodes.clear();
  for (const Driver* driver : drivers_)
    if (!driver->nodes_read(load, discretisation, nodes)) return false;
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  return true;
}

bool ReadPlan::monitors_read(long step) const {
  return std::any_of(monitors_.begin(), monitors_.end(),
                     [step](const StepMonitor* monitor) { return monitor->reads_displacement(step); });
}

}  // namespace mtled
