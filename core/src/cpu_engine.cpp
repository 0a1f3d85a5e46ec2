#include "mtled/cpu_engine.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "explicit_update.hpp"
#include "mtled/constraints.hpp"
#include "mtled/model.hpp"

namespace mtled {

namespace {

// Nodes below which a per-node pass runs on one thread: waking the team costs more than a few thousand nodes'
// arithmetic (and every meeting of the threads is a chance to wait for one another run holds off its core).
constexpr std::int64_t kNodesWorthAThread = 8192;

class CpuEngine final : public StepEngine {
 public:
  void setup(const Model& model) override {
    model_ = &model;
    const std::size_t dofs = 3 * static_cast<std::size_t>(model.node_count());
    for (auto* v : {&u_, &u_previous_, &prediction_, &free_, &f_, &f_previous_}) v->assign(dofs, 0.0);
    first_bad_.assign(static_cast<std::size_t>(model.team().size()), -1);
  }
  // With the force kernel's mean time per evaluation and the memory bandwidth it reached (the bytes it must move,
  // Model::streamed_bytes_per_force_evaluation, over that time): how close the run came to the machine.
  json describe() const override {
    json out = {{"type", "cpu"}, {"threads", model_->team().size()}, {"force_evaluations", evaluations_}};
    if (evaluations_ > 0) {
      const double seconds = kernel_s_ / static_cast<double>(evaluations_);
      const auto bytes = static_cast<double>(model_->streamed_bytes_per_force_evaluation());
      out["force_kernel_s"] = seconds;
      out["force_kernel_bytes"] = bytes;
      out["force_kernel_GB_per_s"] = bytes / seconds / 1e9;
    }
    return out;
  }

  void set_mass(std::span<const double> mass) override { mass_.assign(mass.begin(), mass.end()); }
  void set_state(std::span<const double> u, std::span<const double> u_previous) override {
    std::copy(u.begin(), u.end(), u_.begin());
    std::copy(u_previous.begin(), u_previous.end(), u_previous_.begin());
  }
  std::span<const double> displacement() override { return u_; }
  std::span<const double> previous_displacement() override { return u_previous_; }

  Index evaluate_forces(IncrementSums* sums) override {
    f_previous_.swap(f_);
    const auto start = std::chrono::steady_clock::now();
    const Index bad = model_->internal_forces(u_, f_);
    kernel_s_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    ++evaluations_;
    if (bad >= 0 || sums == nullptr) return bad;
    // In unknown order, on one thread: every ten steps, and the order of the sums is the answer's.
    *sums = {};
    for (std::size_t i = 0; i < u_.size(); ++i) {
      const double du = u_[i] - u_previous_[i];
      sums->stiffness += du * (f_[i] - f_previous_[i]);
      sums->inertia += du * du * mass_[i / 3];
    }
    return bad;
  }

  std::int64_t predict(double alpha, double beta, std::span<const double> f_ext) override {
    const double* external = f_ext.empty() ? nullptr : f_ext.data();
    std::fill(first_bad_.begin(), first_bad_.end(), -1);
    for_each_node_share([&](std::size_t begin, std::size_t end, int part) {
      explicit_update(u_.data(), u_previous_.data(), external, f_.data(), mass_.data(), alpha, beta, prediction_.data(),
                      begin, end);
      for (std::size_t d = 3 * begin; d < 3 * end; ++d) {
        free_[d] = prediction_[d];
        if (!std::isfinite(prediction_[d]) && first_bad_[static_cast<std::size_t>(part)] < 0)
          first_bad_[static_cast<std::size_t>(part)] = static_cast<std::int64_t>(d);
      }
    });
    for (const std::int64_t bad : first_bad_)
      if (bad >= 0) return bad;  // the shares are in node order: the first share's is the lowest
    return -1;
  }
  void set_prediction(std::span<const double> u) override {
    std::copy(u.begin(), u.end(), prediction_.begin());
    std::copy(u.begin(), u.end(), free_.begin());
  }
  void prediction(std::span<double> out) override { std::copy(prediction_.begin(), prediction_.end(), out.begin()); }

  void constrained_values(const ConstraintBlock& block, std::vector<double>& out) override {
    mtled::constrained_values(block, prediction_, out, model_->team());
  }
  void add_correction(const ConstraintBlock& block, const std::vector<double>& y) override {
    mtled::add_correction(block, y, prediction_, model_->team());
  }

  StepSums commit() override {
    const int parts = parts_for(model_->node_count());
    partial_.assign(static_cast<std::size_t>(parts), StepSums{});
    std::vector<double> fastest(static_cast<std::size_t>(parts), 0.0);
    for_each_node_share([&](std::size_t begin, std::size_t end, int part) {
      StepSums& mine = partial_[static_cast<std::size_t>(part)];
      double& fastest_energy = fastest[static_cast<std::size_t>(part)];
      for (std::size_t i = begin; i < end; ++i) {
        double added = 0.0, product = 0.0;
        for (std::size_t d = 3 * i; d < 3 * i + 3; ++d) {
          const double after = prediction_[d] - u_[d], before = free_[d] - u_[d];
          added += std::max(0.0, after * after - before * before);
          product += (u_[d] - u_previous_[d]) * after;
          mine.largest_increment = std::max(mine.largest_increment, std::abs(after));
          mine.largest_displacement = std::max(mine.largest_displacement, std::abs(prediction_[d]));
        }
        mine.projection_energy += mass_[i] * added;
        const double e = mass_[i] * product;
        mine.kinetic_product += e;
        if (std::abs(e) > fastest_energy) {
          fastest_energy = std::abs(e);
          mine.fastest_node = static_cast<Index>(i);
        }
      }
    }, parts);
    StepSums sums;
    double fastest_energy = 0.0;
    for (std::size_t part = 0; part < partial_.size(); ++part) {
      const StepSums& p = partial_[part];
      sums.largest_increment = std::max(sums.largest_increment, p.largest_increment);
      sums.largest_displacement = std::max(sums.largest_displacement, p.largest_displacement);
      sums.projection_energy += p.projection_energy;
      sums.kinetic_product += p.kinetic_product;
      if (fastest[part] > fastest_energy) {
        fastest_energy = fastest[part];
        sums.fastest_node = p.fastest_node;
      }
    }
    u_previous_.swap(u_);
    u_.swap(prediction_);
    return sums;
  }

  Index internal_forces(std::span<const double> u, std::span<double> f) override {
    return model_->internal_forces(u, f);
  }

 private:
  int parts_for(Index nodes) const {
    const int team = model_->team().size();
    return nodes >= kNodesWorthAThread * team ? team : 1;
  }
  // body(begin, end, part) over `parts` contiguous shares of the nodes, on the team when there are several.
  template <class Body>
  void for_each_node_share(Body&& body, int parts = 0) {
    const Index nodes = model_->node_count();
    if (parts == 0) parts = parts_for(nodes);
    const auto share = [&](int part) {
      const auto [begin, end] = ThreadTeam::share(nodes, part, parts);
      body(static_cast<std::size_t>(begin), static_cast<std::size_t>(end), part);
    };
    if (parts == 1)
      share(0);
    else
      model_->team().run(share);
  }

  const Model* model_ = nullptr;
  std::vector<double> u_, u_previous_, prediction_, free_, f_, f_previous_, mass_;
  std::vector<std::int64_t> first_bad_;
  std::vector<StepSums> partial_;
  long evaluations_ = 0;  // of the step's forces (evaluate_forces), and their time
  double kernel_s_ = 0.0;
};

}  // namespace

std::unique_ptr<StepEngine> make_cpu_engine() { return std::make_unique<CpuEngine>(); }

}  // namespace mtled
