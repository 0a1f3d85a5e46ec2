#pragma once
// Copies of a scene's needle beside the running loop, after every step: one updated with the whole u, two with u
// right only where their nodes_read() says they read: NaN elsewhere in one (a NaN propagates, unless a comparison
// drops it), u shifted by up to 6 micrometres elsewhere in the other (by node and component; any read changes some
// prescribed value's bits). Were a node they read left out, they would prescribe other values or take other entries
// than the first.
#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <memory>
#include <vector>

#include "mtled/interfaces/driver.hpp"
#include "mtled/monitor.hpp"
#include "mtled/simulation.hpp"
#include "test_support.hpp"

namespace mtled::test {

class TwinNeedles final : public StepMonitor {
 public:
  // Three needles made alike: the one given the whole u first.
  explicit TwinNeedles(std::vector<std::shared_ptr<NeedleModel>> needles) : needles_(std::move(needles)) {}
  std::string name() const override { return "twin_needles"; }
  void before_run(const RunContext& run, const StepRecord&) override { run_ = &run; }
  void after_step(const StepRecord& step) override {
    ASSERT_EQ(needles_.size(), 3u);
    const LoadState& load = step.load;
    std::vector<Index> nodes;
    ASSERT_TRUE(needles_[1]->nodes_read(load, *run_->discretisation, nodes));
    std::vector<double> not_a_number(step.u.size(), std::numeric_limits<double>::quiet_NaN()), shifted(step.u.size());
    for (std::size_t i = 0; i < shifted.size(); ++i)  // by node and component, so that no gradient is left alone
      shifted[i] = step.u[i] + 1e-6 * static_cast<double>(i % 7);
    for (const Index n : nodes)
      for (std::size_t d = 3 * static_cast<std::size_t>(n); d < 3 * static_cast<std::size_t>(n) + 3; ++d)
        not_a_number[d] = shifted[d] = step.u[d];
    needles_[0]->update(load, *run_->discretisation, step.u);
    needles_[1]->update(load, *run_->discretisation, not_a_number);
    needles_[2]->update(load, *run_->discretisation, shifted);
    std::sort(nodes.begin(), nodes.end());
    largest_read = std::max(largest_read, static_cast<std::size_t>(std::unique(nodes.begin(), nodes.end()) - nodes.begin()));
    const auto a = needles_[0]->constraints();
    for (std::size_t twin = 1; twin < needles_.size(); ++twin) {
      const auto b = needles_[twin]->constraints();
      ASSERT_EQ(a.size(), b.size());
      for (std::size_t s = 0; s < a.size(); ++s) {
        ASSERT_EQ(a[s]->nodes(), b[s]->nodes()) << "step " << step.load.step << ", twin " << twin;
        ASSERT_EQ(a[s]->points().size(), b[s]->points().size()) << "step " << step.load.step << ", twin " << twin;
        for (std::size_t k = 0; k < a[s]->values.size(); ++k)
          ASSERT_EQ(a[s]->values[k], b[s]->values[k])
              << "step " << step.load.step << ", twin " << twin << ", set " << a[s]->name << ", entry " << k;
      }
    }
    punctured = needles_[0]->status().phase == NeedlePhase::penetration;
    driven = needles_[0]->status().driven_nodes;
  }
  std::size_t largest_read = 0;  // the most distinct nodes read at one step
  bool punctured = false;
  Index driven = 0;

 private:
  const RunContext* run_ = nullptr;
  std::vector<std::shared_ptr<NeedleModel>> needles_;
};

// Runs the scene `document` (validated) with three copies of its needle beside the loop, and checks what they saw:
// the needle punctured and drove entries, and read some nodes but not all of them.
inline void expect_needle_reads_only_what_it_declares(const json& document) {
  const Scene scene = validate_scene(parse_scene(document.dump(), "twin_needles.json"), catalog());
  Simulation simulation(scene, catalog());
  const auto twin = [&] {
    auto needle = make<NeedleModel>(document["needle"]["type"], document["needle"]);
    needle->setup(simulation.system().discretisation());
    return needle;
  };
  auto monitor = std::make_shared<TwinNeedles>(std::vector{twin(), twin(), twin()});
  simulation.loop().add_monitor(monitor);
  simulation.loop().run();
  EXPECT_TRUE(monitor->punctured);
  EXPECT_GT(monitor->driven, 0);
  EXPECT_GT(monitor->largest_read, 0u);
  EXPECT_LT(monitor->largest_read, static_cast<std::size_t>(simulation.system().discretisation().node_count()));
}

}  // namespace mtled::test
