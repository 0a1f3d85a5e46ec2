#include "mtled/cpu_engine.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "mtled/constraints.hpp"
#include "mtled/explicit_update.hpp"
#include "mtled/force_kernel.hpp"

namespace mtled {

namespace {

// Nodes below which a per-node pass runs on one thread: waking the team costs more than a few thousand nodes'
// arithmetic (and every meeting of the threads is a chance to wait for one another run holds off its core).
constexpr std::int64_t kNodesWorthAThread = 8192;

}  // namespace

void HostState::size_for(Index nodes) {
  for (auto* v : {&u, &u_previous, &prediction, &free, &f, &f_previous})
    v->assign(3 * static_cast<std::size_t>(nodes), 0.0);
}

void HostState::set_state(std::span<const double> u_now, std::span<const double> u_before) {
  std::copy(u_now.begin(), u_now.end(), u.begin());
  std::copy(u_before.begin(), u_before.end(), u_previous.begin());
}

void HostState::set_prediction(std::span<const double> u_predicted) {
  std::copy(u_predicted.begin(), u_predicted.end(), prediction.begin());
  std::copy(u_predicted.begin(), u_predicted.end(), free.begin());
}

std::int64_t HostState::predict(const UpdateCoefficients& update, const double* f_ext, std::size_t begin,
                                std::size_t end) {
  explicit_update(u.data(), u_previous.data(), f_ext, f.data(), f_previous.data(), mass.data(), update,
                  prediction.data(), begin, end);
  std::int64_t first_bad = -1;
  for (std::size_t d = 3 * begin; d < 3 * end; ++d) {
    free[d] = prediction[d];
    if (!std::isfinite(prediction[d]) && first_bad < 0) first_bad = static_cast<std::int64_t>(d);
  }
  return first_bad;
}

void HostState::add_step_sums(std::size_t i, double beta, StepSums& sums, double& fastest_energy) const {
  mtled::add_step_sums(i, u.data(), u_previous.data(), prediction.data(), free.data(), mass.data(), beta, sums,
                       fastest_energy);
}

void HostState::advance() {
  u_previous.swap(u);
  u.swap(prediction);
}

void ForceEvaluationClock::describe(const ForceKernel& kernel, json& out) const {
  out["force_evaluations"] = evaluations_;
  if (evaluations_ == 0) return;
  const double seconds = seconds_ / static_cast<double>(evaluations_);
  const auto bytes = static_cast<double>(kernel.streamed_bytes_per_force_evaluation());
  out["force_kernel_s"] = seconds;
  out["force_kernel_bytes"] = bytes;
  out["force_kernel_GB_per_s"] = bytes / seconds / 1e9;
}

void CpuEngine::setup(const ForceKernel& kernel) {
  kernel_ = &kernel;
  const Discretisation& discretisation = kernel.discretisation();
  state_.size_for(discretisation.node_count());
  first_bad_.assign(static_cast<std::size_t>(discretisation.team().size()), -1);
  partial_.assign(static_cast<std::size_t>(discretisation.team().size()), Partial{});
}

json CpuEngine::describe() const {
  json out = {{"type", "cpu"}, {"threads", kernel_->discretisation().team().size()}};
  clock_.describe(*kernel_, out);
  out["update_s"] = update_s_;
  return out;
}

void CpuEngine::set_mass(std::span<const double> mass) { state_.mass.assign(mass.begin(), mass.end()); }

void CpuEngine::set_state(std::span<const double> u, std::span<const double> u_previous) {
  state_.set_state(u, u_previous);
}

Index CpuEngine::evaluate_forces(IncrementSums* sums) {
  state_.f_previous.swap(state_.f);
  const Index bad = clock_.timed([&] { return kernel_->internal_forces(state_.u, state_.f); });
  const HostState& s = state_;
  if (bad < 0 && sums != nullptr) *sums = increment_sums(s.u, s.u_previous, s.f, s.f_previous, s.mass);
  return bad;
}

std::int64_t CpuEngine::predict(const UpdateCoefficients& update, std::span<const double> f_ext) {
  const ScopeTimer timer(update_s_);
  const double* external = f_ext.empty() ? nullptr : f_ext.data();
  std::fill(first_bad_.begin(), first_bad_.end(), -1);
  for_each_node_share(
      [&](std::size_t begin, std::size_t end, int part) {
        first_bad_[static_cast<std::size_t>(part)] = state_.predict(update, external, begin, end);
      },
      parts_for(kernel_->discretisation().node_count()));
  for (const std::int64_t bad : first_bad_)
    if (bad >= 0) return bad;  // the shares are in node order: the first share's is the lowest
  return -1;
}

void CpuEngine::set_prediction(std::span<const double> u) { state_.set_prediction(u); }

void CpuEngine::prediction(std::span<double> out) {
  std::copy(state_.prediction.begin(), state_.prediction.end(), out.begin());
}

void CpuEngine::constrained_values(const ConstraintBlock& block, std::vector<double>& out) {
  const ScopeTimer timer(update_s_);
  mtled::constrained_values(block, state_.prediction, out, kernel_->discretisation().team());
}

void CpuEngine::add_correction(const ConstraintBlock& block, const std::vector<double>& y) {
  const ScopeTimer timer(update_s_);
  mtled::add_correction(block, y, state_.prediction, kernel_->discretisation().team());
}

StepSums CpuEngine::commit(bool, double beta) {
  const ScopeTimer timer(update_s_);
  const int parts = parts_for(kernel_->discretisation().node_count());
  std::fill(partial_.begin(), partial_.begin() + parts, Partial{});
  for_each_node_share([&](std::size_t begin, std::size_t end, int part) {
    Partial& mine = partial_[static_cast<std::size_t>(part)];
    for (std::size_t i = begin; i < end; ++i) state_.add_step_sums(i, beta, mine.sums, mine.fastest_energy);
  }, parts);
  StepSums sums;
  double fastest_energy = 0.0;
  for (int part = 0; part < parts; ++part) {
    const Partial& p = partial_[static_cast<std::size_t>(part)];
    combine_step_sums(p.sums, p.fastest_energy, sums, fastest_energy);
  }
  state_.advance();
  return sums;
}

// Counted with the step's own evaluations: the monitors' extra ones (the stable step's Lanczos iterations) are
// force-kernel work too.
Index CpuEngine::internal_forces(std::span<const double> u, std::span<double> f) {
  return clock_.timed([&] { return kernel_->internal_forces(u, f); });
}

int CpuEngine::parts_for(Index nodes) const {
  const int team = kernel_->discretisation().team().size();
  return nodes >= kNodesWorthAThread * team ? team : 1;
}

template <class Body>
void CpuEngine::for_each_node_share(Body&& body, int parts) {
  const Index nodes = kernel_->discretisation().node_count();
  const auto share = [&](int part) {
    const auto [begin, end] = ThreadTeam::share(nodes, part, parts);
    body(static_cast<std::size_t>(begin), static_cast<std::size_t>(end), part);
  };
  if (parts == 1)
    share(0);
  else
    kernel_->discretisation().team().run(share);
}

std::unique_ptr<StepEngine> make_cpu_engine() { return std::make_unique<CpuEngine>(); }

}  // namespace mtled
