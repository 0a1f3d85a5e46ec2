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

void CpuEngine::setup(const ForceKernel& kernel) {
  kernel_ = &kernel;
  const Discretisation& discretisation = kernel.discretisation();
  const std::size_t dofs = 3 * static_cast<std::size_t>(discretisation.node_count());
  for (auto* v : {&u_, &u_previous_, &prediction_, &free_, &f_, &f_previous_}) v->assign(dofs, 0.0);
  first_bad_.assign(static_cast<std::size_t>(discretisation.team().size()), -1);
  partial_.assign(static_cast<std::size_t>(discretisation.team().size()), Partial{});
}

json CpuEngine::describe() const {
  json out = {
      {"type", "cpu"}, {"threads", kernel_->discretisation().team().size()}, {"force_evaluations", evaluations_}};
  if (evaluations_ > 0) {
    const double seconds = kernel_s_ / static_cast<double>(evaluations_);
    const auto bytes = static_cast<double>(kernel_->streamed_bytes_per_force_evaluation());
    out["force_kernel_s"] = seconds;
    out["force_kernel_bytes"] = bytes;
    out["force_kernel_GB_per_s"] = bytes / seconds / 1e9;
  }
  out["update_s"] = update_s_;
  return out;
}

void CpuEngine::set_mass(std::span<const double> mass) { mass_.assign(mass.begin(), mass.end()); }

void CpuEngine::set_state(std::span<const double> u, std::span<const double> u_previous) {
  std::copy(u.begin(), u.end(), u_.begin());
  std::copy(u_previous.begin(), u_previous.end(), u_previous_.begin());
}

Index CpuEngine::evaluate_forces(IncrementSums* sums) {
  f_previous_.swap(f_);
  const Index bad = timed([&] { return forces(u_, f_); });
  if (bad < 0 && sums != nullptr) *sums = increment_sums(u_, u_previous_, f_, f_previous_, mass_);
  return bad;
}

std::int64_t CpuEngine::predict(const UpdateCoefficients& update, std::span<const double> f_ext) {
  const ScopeTimer timer(update_s_);
  const double* external = f_ext.empty() ? nullptr : f_ext.data();
  std::fill(first_bad_.begin(), first_bad_.end(), -1);
  for_each_node_share(
      [&](std::size_t begin, std::size_t end, int part) {
        explicit_update(u_.data(), u_previous_.data(), external, f_.data(), f_previous_.data(), mass_.data(), update,
                        prediction_.data(), begin, end);
        for (std::size_t d = 3 * begin; d < 3 * end; ++d) {
          free_[d] = prediction_[d];
          if (!std::isfinite(prediction_[d]) && first_bad_[static_cast<std::size_t>(part)] < 0)
            first_bad_[static_cast<std::size_t>(part)] = static_cast<std::int64_t>(d);
        }
      },
      parts_for(kernel_->discretisation().node_count()));
  for (const std::int64_t bad : first_bad_)
    if (bad >= 0) return bad;  // the shares are in node order: the first share's is the lowest
  return -1;
}

void CpuEngine::set_prediction(std::span<const double> u) {
  std::copy(u.begin(), u.end(), prediction_.begin());
  std::copy(u.begin(), u.end(), free_.begin());
}

void CpuEngine::prediction(std::span<double> out) { std::copy(prediction_.begin(), prediction_.end(), out.begin()); }

void CpuEngine::constrained_values(const ConstraintBlock& block, std::vector<double>& out) {
  const ScopeTimer timer(update_s_);
  mtled::constrained_values(block, prediction_, out, kernel_->discretisation().team());
}

void CpuEngine::add_correction(const ConstraintBlock& block, const std::vector<double>& y) {
  const ScopeTimer timer(update_s_);
  mtled::add_correction(block, y, prediction_, kernel_->discretisation().team());
}

StepSums CpuEngine::commit(bool, double beta) {
  const ScopeTimer timer(update_s_);
  const int parts = parts_for(kernel_->discretisation().node_count());
  std::fill(partial_.begin(), partial_.begin() + parts, Partial{});
  for_each_node_share([&](std::size_t begin, std::size_t end, int part) {
    Partial& mine = partial_[static_cast<std::size_t>(part)];
    for (std::size_t i = begin; i < end; ++i)
      add_step_sums(i, u_.data(), u_previous_.data(), prediction_.data(), free_.data(), mass_.data(), beta, mine.sums,
                    mine.fastest_energy);
  }, parts);
  StepSums sums;
  double fastest_energy = 0.0;
  for (int part = 0; part < parts; ++part) {
    const Partial& p = partial_[static_cast<std::size_t>(part)];
    combine_step_sums(p.sums, p.fastest_energy, sums, fastest_energy);
  }
  u_previous_.swap(u_);
  u_.swap(prediction_);
  return sums;
}

// Counted with the step's own evaluations: the monitors' extra ones (the stable step's Lanczos iterations) are
// force-kernel work too.
Index CpuEngine::internal_forces(std::span<const double> u, std::span<double> f) {
  return timed([&] { return forces(u, f); });
}

Index CpuEngine::forces(std::span<const double> u, std::span<double> f) { return kernel_->internal_forces(u, f); }

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
