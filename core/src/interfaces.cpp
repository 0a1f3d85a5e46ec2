// What the interfaces in mtled/interfaces/ define beyond their declarations.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "mtled/explicit_update.hpp"
#include "mtled/force_kernel.hpp"
#include "mtled/interfaces/backend.hpp"
#include "mtled/interfaces/driver.hpp"
#include "mtled/interfaces/integrator.hpp"
#include "mtled/interfaces/material.hpp"
#include "mtled/interfaces/mesh_source.hpp"
#include "mtled/interfaces/shape_functions.hpp"
#include "mtled/interfaces/volumetric_treatment.hpp"
#include "mtled/monitor.hpp"

namespace mtled {

// Key functions: the interfaces' type information lives in libmtled_core only.
MeshSource::~MeshSource() = default;
ShapeFunctions::~ShapeFunctions() = default;
ShapeFunctionFit ShapeFunctions::interpolate(const Vec3& x, std::span<const Vec3> nodes, std::span<const double> radii,
                                             std::span<const Vec3> node_values, Vec3& value, Mat3* gradient) const {
  thread_local std::vector<double> values;
  thread_local std::vector<Vec3> gradients;
  values.resize(nodes.size());
  gradients.resize(gradient != nullptr ? nodes.size() : 0);
  value.setZero();
  if (gradient != nullptr) gradient->setZero();
  const ShapeFunctionFit fit = evaluate(x, nodes, radii, values, gradients);
  if (!fit.ok) return fit;
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    value += values[i] * node_values[i];
    if (gradient != nullptr) gradient->noalias() += node_values[i] * gradients[i].transpose();
  }
  return fit;
}
Material::~Material() = default;
Driver::~Driver() = default;
bool Driver::nodes_read(const LoadState&, const Discretisation&, std::vector<Index>&) const { return false; }
BoundaryCondition::~BoundaryCondition() = default;
NeedleModel::~NeedleModel() = default;
TimeIntegrator::~TimeIntegrator() = default;
VolumetricTreatment::~VolumetricTreatment() = default;
Index VolumetricTreatment::stress_deformation_gradients(const ForceKernel& kernel, std::span<const double> u,
                                                        std::span<Mat3> F) {
  return kernel.deformation_gradients(u, F);
}
Index VolumetricTreatment::internal_forces(const ForceKernel&, std::span<const double>, std::span<double>,
                                           std::span<const PointRange>) {
  throw std::logic_error("this volumetric treatment sums only over every integration point");
}
std::vector<PointRange> VolumetricTreatment::points_read(const ForceKernel& kernel, std::span<const PointRange>) {
  const std::span<const PointRange> every = kernel.discretisation().points().every();
  return {every.begin(), every.end()};
}
StepMonitor::~StepMonitor() = default;
bool StepMonitor::reads_displacement(long) const { return true; }
StepControl::~StepControl() = default;
DiscreteSystem::~DiscreteSystem() = default;
StepEngine::~StepEngine() = default;
std::vector<int> StepEngine::cell_groups(const TetMesh&) { return {}; }
std::span<const double> StepEngine::displacement_at(std::span<const Index>) { return displacement(); }
bool StepEngine::spreads_nodes() const { return false; }

IncrementSums DiscreteSystem::evaluate_forces(bool increment_sums) {
  const auto u = displacement();
  f_int_previous_.swap(f_int_);
  f_int_.resize(u.size());
  f_int_previous_.resize(u.size());
  internal_forces(u, f_int_);
  if (!increment_sums) return {};
  return mtled::increment_sums(u, previous_displacement(), f_int_, f_int_previous_, mass());
}

StepSums DiscreteSystem::advance(const UpdateCoefficients& update, double time, double load_fraction) {
  const auto u = displacement();
  u_next_.resize(u.size());
  const double* f_ext = nullptr;
  if (has_external_forces()) {
    f_ext_.resize(u.size());
    external_forces(f_ext_);
    f_ext = f_ext_.data();
  }
  explicit_update(u.data(), previous_displacement().data(), f_ext, f_int_.data(), f_int_previous_.data(), mass().data(),
                  update, u_next_.data(), 0, mass().size());
  // beta (u_n - u_(n-1)), before complete_step moves the states on.
  carried_.resize(u.size());
  for (std::size_t i = 0; i < u.size(); ++i) carried_[i] = update.beta * (u[i] - previous_displacement()[i]);
  complete_step(u_next_, time, load_fraction, update.alpha);
  StepSums sums;
  const auto after = displacement(), before = previous_displacement();
  for (std::size_t i = 0; i < after.size(); ++i) {
    sums.largest_increment = std::max(sums.largest_increment, std::abs(after[i] - before[i]));
    sums.largest_displacement = std::max(sums.largest_displacement, std::abs(after[i]));
    sums.largest_residual_step = std::max(sums.largest_residual_step, std::abs(after[i] - before[i] - carried_[i]));
  }
  return sums;
}

void Material::stress_batch(StressBatch& batch) const noexcept {
  for (int p = 0; p < batch.count; ++p) {
    Mat3 S;
    batch.admissible[p] = stress(batch.deformation_gradient(p), S);
    batch.set_stress(p, batch.admissible[p] ? S : Mat3::Zero());
  }
}

DeviceLaw Material::device_law() const { return {}; }

std::string_view to_string(NeedlePhase phase) {
  return phase == NeedlePhase::penetration ? "penetration" : "indentation";
}

Vec3 NodalConstraints::total_reaction() const {
  Vec3 sum = Vec3::Zero();
  for (const auto& r : reactions) sum += r;
  return sum;
}

void NodalConstraints::set_components(const std::array<bool, 3>& components) {
  components_ = components;
  ++revision_;
}

void NodalConstraints::assign_nodes(std::vector<Index> nodes, const Vec3& value) {
  nodes_ = std::move(nodes);
  points_.clear();
  values.assign(nodes_.size(), value);
  ++revision_;
}

void NodalConstraints::add_node(Index node, const Vec3& value) {
  nodes_.push_back(node);
  values.push_back(value);
  ++revision_;
}

void NodalConstraints::add_point(const Vec3& point, const Vec3& value) {
  points_.push_back(point);
  values.push_back(value);
  ++revision_;
}

void NodalConstraints::keep_entries(const std::vector<char>& keep) {
  std::size_t kept = 0;
  for (std::size_t k = 0; k < keep.size(); ++k) {
    if (!keep[k]) continue;
    if (!nodes_.empty()) nodes_[kept] = nodes_[k];
    if (!points_.empty()) points_[kept] = points_[k];
    if (k < values.size()) values[kept] = values[k];
    if (k < reactions.size()) reactions[kept] = reactions[k];
    ++kept;
  }
  if (!nodes_.empty()) nodes_.resize(kept);
  if (!points_.empty()) points_.resize(kept);
  values.resize(std::min(values.size(), kept));
  reactions.resize(std::min(reactions.size(), kept));
  ++revision_;
}

void NodalConstraints::clear() {
  nodes_.clear();
  points_.clear();
  values.clear();
  ++revision_;
}

json to_json(const IntegratorReport& report) {
  json out = {{"type", report.type},
              {"time_step_s", report.time_step},
              {"stable_time_step_s", report.stable_time_step},
              {"time_step_factor", report.time_step_factor},
              {"stable_step_margin", report.stable_step_margin}};
  if (const auto& r = report.relaxation) {
    out["converged"] = r->converged;
    out["error_bound_m"] = std::isfinite(r->error_bound) ? json(r->error_bound) : json(nullptr);
    out["relative_error_bound"] = r->relative_error_bound;
    out["tolerance"] = r->tolerance;
    out["lowest_frequency_rad_per_s"] = r->lowest_frequency;
    out["convergence_rate"] = r->convergence_rate;
  }
  out.update(report.settings);
  return out;
}

}  // namespace mtled
