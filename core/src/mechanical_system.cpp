#include "mtled/mechanical_system.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "component_build.hpp"
#include "mtled/cpu_engine.hpp"
#include "mtled/instability.hpp"
#include "mtled/interfaces/material.hpp"
#include "mtled/interfaces/mesh_source.hpp"
#include "mtled/interfaces/shape_functions.hpp"
#include "mtled/interfaces/volumetric_treatment.hpp"
#include "mtled/log.hpp"

namespace mtled {

namespace {

// The scene's needle's planned path, building the needle when called (empty without a needle).
std::function<std::optional<PlannedPath>()> needle_path_of(const Scene& scene, PluginCatalog& catalog) {
  if (!scene.needle) return {};
  return [&scene, &catalog]() { return build_component<NeedleModel>(catalog, *scene.needle)->planned_path(); };
}

// One material per mesh region: a block with "region" fills that region, one without fills every other.
std::vector<std::shared_ptr<const Material>> region_materials(const Scene& scene, PluginCatalog& catalog,
                                                              const TetMesh& mesh) {
  std::vector<std::shared_ptr<const Material>> region_material(mesh.region_names.size());
  std::shared_ptr<const Material> fallback;
  for (const auto& block : scene.materials) {
    std::shared_ptr<const Material> material = build_component<Material>(catalog, block);
    const auto region = block.parameters.read<MaterialRegion>().region;
    if (!region) {
      fallback = material;
      continue;
    }
    const auto it = std::find(mesh.region_names.begin(), mesh.region_names.end(), *region);
    if (it == mesh.region_names.end()) {
      const auto hint = did_you_mean(*region, mesh.region_names);
      throw InputError(
          block.parameters.pointer("region"),
          fmt::format("the mesh ({}) has no region \"{}\"; {}", mesh.source, *region,
                      hint.empty() ? fmt::format("its regions: {}", fmt::join(mesh.region_names, ", ")) : hint));
    }
    const auto r = static_cast<std::size_t>(it - mesh.region_names.begin());
    if (region_material[r])
      throw InputError(block.parameters.pointer("region"),
                       fmt::format("region \"{}\" is given two materials", *region));
    region_material[r] = material;
  }
  for (std::size_t r = 0; r < region_material.size(); ++r) {
    if (region_material[r]) continue;
    if (!fallback)
      throw InputError("/materials", fmt::format("mesh region \"{}\" has no material: add a material with \"region\": "
                                                 "\"{}\", or one without \"region\" to fill every unnamed region",
                                                 mesh.region_names[r], mesh.region_names[r]));
    region_material[r] = fallback;
  }

  return region_material;
}

}  // namespace

TetMesh load_scene_mesh(const Scene& scene, PluginCatalog& catalog, MeshInputs* inputs) {
  auto source = build_component<MeshSource>(catalog, scene.mesh);
  MeshContext context{scene.document.directory(), 1, {}};
  if (const auto needle_path = needle_path_of(scene, catalog)) {
    context.needle_path = [needle_path, inputs]() {
      auto path = needle_path();
      if (inputs) *inputs = {true, path};
      return path;
    };
  }
  TetMesh mesh;
  guarded(scene.mesh.parameters, "reading the mesh", [&] { mesh = source->load(context); });
  if (mesh.source.empty()) mesh.source = scene.mesh.type;
  remove_unused_nodes(mesh);
  check_mesh(mesh);
  return mesh;
}

std::string BasisCache::key(const Scene& scene) {
  const json& root = scene.document.root;
  return json::array({scene.document.directory().string(), root.value("mesh", json()),
                      root.value("shape_function", json()), root.value("discretisation", json())})
      .dump();
}

std::shared_ptr<const MeshlessBasis> BasisCache::find(
    const Scene& scene, const std::function<std::optional<PlannedPath>()>& needle_path) const {
  if (scene.backend) return nullptr;
  const std::lock_guard lock(mutex_);
  std::optional<std::optional<PlannedPath>> path;  // the scene's, once asked
  const auto [first, last] = bases_.equal_range(key(scene));
  for (auto it = first; it != last; ++it) {
    const MeshInputs& inputs = it->second.inputs;
    if (!inputs.asked_needle_path) return it->second.basis;
    if (!path) path = needle_path ? needle_path() : std::nullopt;
    if (*path == inputs.needle_path) return it->second.basis;
  }
  return nullptr;
}

void BasisCache::keep(const Scene& scene, std::shared_ptr<const MeshlessBasis> basis, MeshInputs inputs) {
  if (scene.backend) return;
  const std::lock_guard lock(mutex_);
  bases_.emplace(key(scene), Kept{std::move(inputs), std::move(basis)});
}

std::size_t BasisCache::size() const {
  const std::lock_guard lock(mutex_);
  return bases_.size();
}

MechanicalSystem::MechanicalSystem(const Scene& scene, PluginCatalog& catalog, BasisCache* bases) {
  // The backend first: one that cannot run here (no device) stops the run before the setup's work.
  engine_ = scene.backend ? build_component<StepEngine>(catalog, *scene.backend) : make_cpu_engine();
  build_discretisation(scene, catalog, bases);
  build_drivers(scene, catalog);
  if (scene.backend)
    guarded(scene.backend->parameters, "setting up the backend", [&] { engine_->setup(*kernel_); });
  else
    engine_->setup(*kernel_);
  read_plan_ = ReadPlan({drivers_.begin(), drivers_.end()}, engine_->spreads_nodes());
  // The state: at rest, the constraints applied.
  const std::size_t dofs = 3 * static_cast<std::size_t>(discretisation_->node_count());
  mass_ = discretisation_->lumped_mass();
  engine_->set_mass(mass_);
  const auto& dt = discretisation_->critical_time_steps();
  unscaled_stable_time_step_ = stable_time_step_ = *std::min_element(dt.begin(), dt.end());
  update_drivers();
  std::vector<double> u(dofs, 0.0);
  constraint_system_->enforce(u, 1.0);
  engine_->set_state(u, std::vector<double>(dofs, 0.0));
}

void MechanicalSystem::build_discretisation(const Scene& scene, PluginCatalog& catalog, BasisCache* bases) {
  if (auto basis = bases ? bases->find(scene, needle_path_of(scene, catalog)) : nullptr) {
    auto materials = region_materials(scene, catalog, basis->mesh);
    discretisation_ = std::make_unique<Discretisation>(std::move(basis), std::move(materials), 0);
    log().debug("discretisation: the basis built for an earlier run of this mesh");
  } else {
    MeshInputs inputs;
    TetMesh mesh = load_scene_mesh(scene, catalog, &inputs);
    auto materials = region_materials(scene, catalog, mesh);
    Discretisation::Options options;
    options.cell_groups = engine_->cell_groups(mesh);
    auto shape_functions = build_component<ShapeFunctions>(catalog, scene.shape_function);
    const auto discretisation = scene.discretisation.read<DiscretisationSettings>();
    options.integration_points_per_tet = discretisation.integration_points_per_tet;
    options.consistent_integration = discretisation.consistent_integration;
    options.precision =
        discretisation.precision == "single" ? RowPrecision::single_precision : RowPrecision::double_precision;
    discretisation_ = std::make_unique<Discretisation>(std::move(mesh), shape_functions, std::move(materials), options);
    if (bases) bases->keep(scene, discretisation_->basis(), std::move(inputs));
  }
  kernel_ = std::make_unique<ForceKernel>(
      *discretisation_, scene.volumetric ? build_component<VolumetricTreatment>(catalog, *scene.volumetric) : nullptr);
  const SupportStatistics stats = discretisation_->points().support;
  log().info("discretisation: {} nodes, {} integration points, support size min/mean/max {}/{:.1f}/{}",
             discretisation_->node_count(), discretisation_->points().count(), stats.min, stats.mean, stats.max);
}

void MechanicalSystem::build_drivers(const Scene& scene, PluginCatalog& catalog) {
  for (const auto& block : scene.boundaries) {
    auto boundary = build_component<BoundaryCondition>(catalog, block);
    guarded(block.parameters, "setting up the boundary condition", [&] { boundary->setup(*discretisation_); });
    boundaries_.push_back(boundary);
    drivers_.push_back(boundary.get());
  }
  if (scene.needle) {
    needle_ = build_component<NeedleModel>(catalog, *scene.needle);
    guarded(scene.needle->parameters, "setting up the needle", [&] { needle_->setup(*discretisation_); });
    drivers_.push_back(needle_.get());
  }
  for (Driver* driver : drivers_) {
    for (NodalConstraints* set : driver->constraints()) {
      constraint_sets_.push_back(set);
      constraint_sets_read_only_.push_back(set);
    }
    for (NodalForces* set : driver->forces()) force_sets_.push_back(set);
  }
  for (std::size_t a = 0; a < constraint_sets_.size(); ++a)
    for (std::size_t b = 0; b < a; ++b)
      if (constraint_sets_[a]->name == constraint_sets_[b]->name)
        throw InputError("/boundaries",
                         fmt::format("two constraint sets are named \"{}\" (reactions.csv could not tell "
                                     "them apart): give each boundary a distinct \"name\"",
                                     constraint_sets_[a]->name));
  constraint_system_ = std::make_unique<ConstraintSystem>(*discretisation_);
}

MechanicalSystem::~MechanicalSystem() = default;

void MechanicalSystem::equalise_critical_steps() {
  const auto& dt = discretisation_->critical_time_steps();
  const std::vector<double> scale = scale_masses({});
  double smallest = dt[0] * std::sqrt(scale[0]);
  for (std::size_t i = 0; i < dt.size(); ++i) smallest = std::min(smallest, dt[i] * std::sqrt(scale[i]));
  stable_time_step_ = smallest;
}

void MechanicalSystem::equalise_current_critical_steps() {
  const auto start = std::chrono::steady_clock::now();
  const std::vector<double> stiffening = mtled::stiffening(*discretisation_, displacement());
  scale_masses(stiffening);
  const auto stiffer = std::count_if(stiffening.begin(), stiffening.end(), [](double s) { return s > 1.0; });
  log().debug(
      "step {}: masses scaled to the current stiffness in {:.3f} s: {} of {} integration points stiffer than "
      "at rest, the most by {:.3g}x",
      load_.step, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), stiffer,
      stiffening.size(), *std::max_element(stiffening.begin(), stiffening.end()));
}

std::vector<double> MechanicalSystem::scale_masses(std::span<const double> stiffening) {
  const auto& dt = discretisation_->critical_time_steps();
  const double target = *std::max_element(dt.begin(), dt.end());
  std::vector<double> scale(dt.size());
  for (std::size_t i = 0; i < dt.size(); ++i) {
    // A point's critical step at its current stiffness is dt / sqrt(stiffening): its density rises by the square of
    // what brings that step up to the target.
    const double now = stiffening.empty() ? dt[i] : dt[i] / std::sqrt(stiffening[i]);
    scale[i] = now < target ? (target / now) * (target / now) : 1.0;
  }
  mass_ = discretisation_->lumped_mass(scale);
  engine_->set_mass(mass_);
  mass_changed_ = true;
  return scale;
}

void MechanicalSystem::inadmissible(Index bad, std::span<const double> u) const {
  const Mat3 F = discretisation_->deformation_gradient(bad, u);
  Diagnostic d;
  d.step = load_.step;
  d.time = load_.time;
  d.what = std::isfinite(F.sum()) ? "inverted_material" : "non_finite";
  d.detail = std::isfinite(F.sum())
                 ? fmt::format(
                       "J = det F = {:.4g} <= 0 at integration point {} (tet {}) at {} m: the material is "
                       "inverted; reduce the time-step factor or the load rate",
                       F.determinant(), bad, discretisation_->points().tets[bad],
                       point_text(discretisation_->points().positions[bad]))
                 : fmt::format("non-finite deformation gradient at integration point {} at {} m", bad,
                               point_text(discretisation_->points().positions[bad]));
  d.integration_points = {bad};
  d.coordinates = {discretisation_->points().positions[bad]};
  throw InstabilityError(std::move(d));
}

void MechanicalSystem::internal_forces(std::span<const double> u, std::span<double> f) {
  ++force_evaluations_;
  const Index bad = engine_->internal_forces(u, f);
  if (bad >= 0) inadmissible(bad, u);
}

IncrementSums MechanicalSystem::evaluate_forces(bool increment_sums) {
  ++force_evaluations_;
  IncrementSums sums;
  const Index bad = engine_->evaluate_forces(increment_sums ? &sums : nullptr);
  if (bad >= 0) inadmissible(bad, displacement());
  return sums;
}

void MechanicalSystem::external_forces(std::span<double> f) {
  std::fill(f.begin(), f.end(), 0.0);
  for (const NodalForces* set : force_sets_)
    for (std::size_t k = 0; k < set->nodes.size(); ++k)
      for (int c = 0; c < 3; ++c) f[3 * static_cast<std::size_t>(set->nodes[k]) + c] += set->values[k][c];
}

void MechanicalSystem::update_drivers() {
  const std::span<const double> u = read_plan_.driver_nodes(load_, *discretisation_, nodes_read_)
                                        ? engine_->displacement_at(nodes_read_)
                                        : displacement();
  for (Driver* driver : drivers_) driver->update(load_, *discretisation_, u);
  constraint_system_->update(constraint_sets_, mass_, mass_changed_);
  mass_changed_ = false;
}

void MechanicalSystem::not_finite(std::int64_t unknown, double value, double new_time) const {
  const auto node = static_cast<Index>(unknown / 3);
  throw node_instability(load_.step + 1, new_time, "non_finite",
                         fmt::format("displacement component {} of node {} at {} m became {}", "xyz"[unknown % 3], node,
                                     point_text(discretisation_->nodes()[node]), value),
                         *discretisation_, node);
}

namespace {
// The engine's prediction as the constraint projection's target.
class Prediction final : public ConstrainedVector {
 public:
  explicit Prediction(StepEngine& engine) : engine_(engine) {}
  void values(const ConstraintBlock& block, std::vector<double>& out) override {
    engine_.constrained_values(block, out);
  }
  void correct(const ConstraintBlock& block, const std::vector<double>& y) override {
    engine_.add_correction(block, y);
  }

 private:
  StepEngine& engine_;
};
}  // namespace

void MechanicalSystem::project(double new_time, double new_load_fraction, double alpha) {
  previous_step_size_ = step_size_;
  step_size_ = new_time - load_.time;
  // The prescribed values before the drivers move them: their change times the reactions is the work the
  // constraints put in (the energy monitor).
  previous_values_.resize(constraint_sets_.size());
  for (std::size_t s = 0; s < constraint_sets_.size(); ++s) previous_values_[s] = constraint_sets_[s]->values;
  load_.time = new_time;
  load_.load_fraction = new_load_fraction;
  load_.step += 1;
  update_drivers();
  Prediction prediction(*engine_);
  constraint_system_->enforce(prediction, alpha);
}

StepSums MechanicalSystem::advance(const UpdateCoefficients& update, double new_time, double new_load_fraction) {
  std::span<const double> f_ext;
  if (has_external_forces()) {
    f_ext_.resize(3 * static_cast<std::size_t>(discretisation_->node_count()));
    external_forces(f_ext_);
    f_ext = f_ext_;
  }
  if (const std::int64_t bad = engine_->predict(update, f_ext); bad >= 0) {
    std::vector<double> u(3 * static_cast<std::size_t>(discretisation_->node_count()));
    engine_->prediction(u);
    not_finite(bad, u[static_cast<std::size_t>(bad)], new_time);
  }
  project(new_time, new_load_fraction, update.alpha);
  displacement_whole_ = read_plan_.monitors_read(load_.step);
  sums_ = engine_->commit(displacement_whole_, update.beta);
  return sums_;
}

void MechanicalSystem::complete_step(std::span<double> u_new, double new_time, double new_load_fraction, double alpha) {
  for (std::size_t i = 0; i < u_new.size(); ++i)
    if (!std::isfinite(u_new[i])) not_finite(static_cast<std::int64_t>(i), u_new[i], new_time);
  engine_->set_prediction(u_new);
  project(new_time, new_load_fraction, alpha);
  engine_->prediction(u_new);  // handed back corrected
  displacement_whole_ = read_plan_.monitors_read(load_.step);
  sums_ = engine_->commit(displacement_whole_, 1.0);
}

StepRecord MechanicalSystem::last_step() const {
  StepRecord r;
  r.load = load_;
  r.step_size = step_size_;
  r.steady_states = steady_states_;
  if (displacement_whole_) r.u = displacement();
  r.mass = mass_;
  r.sums = sums_;
  if (step_size_ > 0.0 && previous_step_size_ > 0.0)
    r.kinetic_energy = std::abs(0.5 / (step_size_ * previous_step_size_) * sums_.kinetic_product);
  r.previous_values = previous_values_;
  if (needle_) r.needle = needle_->status();
  r.stable_time_step = stable_time_step_;
  return r;
}

RunContext MechanicalSystem::start_run(std::span<const std::shared_ptr<StepMonitor>> monitors) {
  read_plan_.set_monitors(monitors);
  RunContext c;
  c.discretisation = discretisation_.get();
  c.constraint_sets = constraint_sets_read_only_;
  c.external_forces = !force_sets_.empty();
  c.internal_forces = [engine = engine_.get()](std::span<const double> u, std::span<double> f) {
    return engine->internal_forces(u, f);
  };
  c.project_out = [constraints = constraint_system_.get()](std::span<double> v) { constraints->project_out(v); };
  c.for_each_share = [team = &discretisation_->team()](std::int64_t n, const auto& body) {
    team->for_each_share(n, body);
  };
  c.step_control = this;
  return c;
}

void MechanicalSystem::share_state() {
  engine_->displacement();
  engine_->previous_displacement();
  displacement_whole_ = true;
}

// The integrators read stable_time_step() before every step and re-plan theirs when it changed.
void MechanicalSystem::set_stable_time_step(double stable_time_step) {
  if (!(stable_time_step > 0.0) || stable_time_step == stable_time_step_) return;
  log().info("step {}: stable time step {} from {:.4g} s to {:.4g} s", load_.step,
             stable_time_step < stable_time_step_ ? "lowered" : "raised", stable_time_step_, stable_time_step);
  stable_time_step_ = stable_time_step;
}

}  // namespace mtled
