#include "processes.hpp"

#include <cstdlib>
#include <stdexcept>
#include <string>

#include "mtled/plugin_catalog.hpp"

namespace mtled::app {

namespace {

std::shared_ptr<ProcessGroup> group;

class InjectedFailure final : public StepMonitor {
 public:
  explicit InjectedFailure(long step) : step_(step) {}
  std::string name() const override { return "injected_failure"; }
  void after_step(const StepRecord& step) override {
    if (step.load.step >= step_)
      throw std::runtime_error("failure injected at step " + std::to_string(step.load.step) +
                               " (MTLED_TEST_FAIL_RANK)");
  }
  bool reads_displacement(long) const override { return false; }

 private:
  long step_;
};

}  // namespace

void join_processes(const std::vector<std::filesystem::path>& plugin_paths) {
  group = join_process_group(plugin_search_path(plugin_paths, {}));
}

ProcessGroup& processes() {
  if (!group) throw std::logic_error("the process group is read before main joined it");
  return *group;
}

std::shared_ptr<StepMonitor> injected_failure() {
  const char* value = std::getenv("MTLED_TEST_FAIL_RANK");
  if (value == nullptr) return nullptr;
  const std::string text = value;
  const auto colon = text.find(':');
  if (colon == std::string::npos || std::stoi(text.substr(0, colon)) != processes().rank()) return nullptr;
  return std::make_shared<InjectedFailure>(std::stol(text.substr(colon + 1)));
}

}  // namespace mtled::app
