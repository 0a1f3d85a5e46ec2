#include "mtled/simulation.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>

#include "mtled/log.hpp"

namespace mtled {

StepObserver::~StepObserver() = default;

namespace {

template <class Interface>
std::shared_ptr<Interface> build(PluginCatalog& catalog, const ComponentBlock& block) {
  try {
    return catalog.create<Interface>(block.type, block.parameters);
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    throw InputError(block.parameters.pointer(), fmt::format("{} \"{}\" failed while being built: {}",
                                                             to_string(Interface::category), block.type, e.what()));
  }
}

template <class Call>
void guarded(const Parameters& parameters, const std::string& what, Call call) {
  try {
    call();
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    throw InputError(parameters.pointer(), fmt::format("{} failed: {}", what, e.what()));
  }
}

std::string point_text(const Vec3& x) { return fmt::format("({:.6g}, {:.6g}, {:.6g})", x[0], x[1], x[2]); }

}  // namespace

Simulation::Simulation(const Scene& scene, PluginCatalog& catalog) {
  // Mesh
  auto source = build<MeshSource>(catalog, scene.mesh);
  MeshContext context{scene.document.directory(), 1};
  TetMesh mesh;
  guarded(scene.mesh.parameters, "reading the mesh", [&] { mesh = source->load(context); });
  if (mesh.source.empty()) mesh.source = scene.mesh.type;
  remove_unused_nodes(mesh);
  check_mesh(mesh);

  // Materials by region
  std::vector<std::shared_ptr<const Material>> region_material(mesh.region_names.size());
  std::shared_ptr<const Material> fallback;
  for (const auto& block : scene.materials) {
    std::shared_ptr<const Material> material = build<Material>(catalog, block);
    const auto region = block.parameters.optional_string("region");
    if (!region) {
      fallback = material;
      continue;
    }
    const auto it = std::find(mesh.region_names.begin(), mesh.region_names.end(), *region);
    if (it == mesh.region_names.end()) {
      const auto hint = did_you_mean(*region, mesh.region_names);
      throw InputError(block.parameters.pointer("region"),
                       fmt::format("the mesh ({}) has no region \"{}\"; {}", mesh.source, *region,
                                   hint.empty() ? fmt::format("its regions: {}", fmt::join(mesh.region_names, ", "))
                                                : hint));
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

  // Discretisation
  auto shape_functions = build<ShapeFunctions>(catalog, scene.shape_function);
  Model::Options options;
  options.integration_points_per_tet = static_cast<int>(scene.discretisation.integer("integration_points_per_tet"));
  options.consistent_integration = scene.discretisation.boolean("consistent_integration");
  options.nodal_volumetric_averaging = scene.discretisation.string("volumetric") == "nodal_average";
  model_ = std::make_unique<Model>(std::move(mesh), shape_functions, std::move(region_material), options);
  const SupportStatistics stats = model_->ip_support_statistics();
  log().info("model: {} nodes, {} integration points, support size min/mean/max {}/{:.1f}/{}", model_->node_count(),
             model_->integration_point_count(), stats.min, stats.mean, stats.max);

  // Drivers
  for (const auto& block : scene.boundaries) {
    auto boundary = build<BoundaryCondition>(catalog, block);
    guarded(block.parameters, "setting up the boundary condition", [&] { boundary->setup(*model_); });
    boundaries_.push_back(boundary);
    drivers_.push_back(boundary.get());
  }
  if (scene.needle) {
    needle_ = build<NeedleModel>(catalog, *scene.needle);
    guarded(scene.needle->parameters, "setting up the needle", [&] { needle_->setup(*model_); });
    drivers_.push_back(needle_.get());
  }
  for (Driver* driver : drivers_) {
    for (NodalConstraints* set : driver->constraints()) constraint_sets_.push_back(set);
    force_drivers_ += driver->applies_forces() ? 1 : 0;
  }
  for (std::size_t a = 0; a < constraint_sets_.size(); ++a)
    for (std::size_t b = 0; b < a; ++b)
      if (constraint_sets_[a]->name == constraint_sets_[b]->name)
        throw InputError("/boundaries", fmt::format("two constraint sets are named \"{}\" (reactions.csv could not tell "
                                                    "them apart): give each boundary a distinct \"name\"",
                                                    constraint_sets_[a]->name));
  constraint_system_ = std::make_unique<ConstraintSystem>(*model_);

  // State
  const std::size_t dofs = 3 * static_cast<std::size_t>(model_->node_count());
  u_.assign(dofs, 0.0);
  u_previous_.assign(dofs, 0.0);
  mass_ = model_->lumped_mass();
  const auto& dt = model_->ip_critical_time_steps();
  unscaled_stable_time_step_ = stable_time_step_ = *std::min_element(dt.begin(), dt.end());
  update_drivers();
  constraint_system_->enforce(u_, 1.0);

  integrator_ = build<TimeIntegrator>(catalog, scene.integrator);
}

Simulation::~Simulation() = default;

void Simulation::scale_masses(double target) {
  const auto& dt = model_->ip_critical_time_steps();
  std::vector<double> scale(dt.size());
  for (std::size_t i = 0; i < dt.size(); ++i) scale[i] = dt[i] < target ? (target / dt[i]) * (target / dt[i]) : 1.0;
  mass_ = model_->lumped_mass(scale);
  double smallest = dt[0] * std::sqrt(scale[0]);
  for (std::size_t i = 0; i < dt.size(); ++i) smallest = std::min(smallest, dt[i] * std::sqrt(scale[i]));
  stable_time_step_ = smallest;
  mass_changed_ = true;
}

void Simulation::internal_forces(std::span<const double> u, std::span<double> f) {
  ++force_evaluations_;
  const Index bad = model_->internal_forces(u, f);
  if (bad < 0) return;
  const Mat3 F = model_->deformation_gradient(bad, u);
  Diagnostic d;
  d.step = load_.step;
  d.time = load_.time;
  d.what = std::isfinite(F.sum()) ? "inverted_material" : "non_finite";
  d.detail = std::isfinite(F.sum())
                 ? fmt::format("J = det F = {:.4g} <= 0 at integration point {} (tet {}) at {} m: the material is "
                               "inverted; reduce the time-step factor or the load rate",
                               F.determinant(), bad, model_->ip_tets()[bad], point_text(model_->ip_positions()[bad]))
                 : fmt::format("non-finite deformation gradient at integration point {} at {} m", bad,
                               point_text(model_->ip_positions()[bad]));
  d.integration_points = {bad};
  d.coordinates = {model_->ip_positions()[bad]};
  throw InstabilityError(std::move(d));
}

void Simulation::external_forces(std::span<double> f) {
  std::fill(f.begin(), f.end(), 0.0);
  for (Driver* driver : drivers_)
    if (driver->applies_forces()) driver->add_forces(load_, *model_, u_, f);
}

void Simulation::update_drivers() {
  for (Driver* driver : drivers_) driver->update(load_, *model_, u_);
  constraint_system_->update(constraint_sets_, mass_, mass_changed_);
  mass_changed_ = false;
}

void Simulation::check_finite(std::span<const double> u_new, double new_time) const {
  for (std::size_t i = 0; i < u_new.size(); ++i) {
    if (std::isfinite(u_new[i])) continue;
    const auto node = static_cast<Index>(i / 3);
    Diagnostic d;
    d.step = load_.step + 1;
    d.time = new_time;
    d.what = "non_finite";
    d.detail = fmt::format("displacement component {} of node {} at {} m became {}", "xyz"[i % 3], node,
                           point_text(model_->nodes()[node]), u_new[i]);
    d.nodes = {node};
    d.coordinates = {model_->nodes()[node]};
    throw InstabilityError(std::move(d));
  }
}

void Simulation::complete_step(std::span<double> u_new, double new_time, double new_load_fraction, double alpha) {
  check_finite(u_new, new_time);
  const double step_size = new_time - load_.time;
  // The prescribed values before the drivers move them: their change times the reactions is the work the
  // constraints put in (energy monitor).
  previous_values_.resize(constraint_sets_.size());
  for (std::size_t s = 0; s < constraint_sets_.size(); ++s) previous_values_[s] = constraint_sets_[s]->values;
  load_.time = new_time;
  load_.load_fraction = new_load_fraction;
  load_.step += 1;
  update_drivers();
  u_free_.assign(u_new.begin(), u_new.end());
  constraint_system_->enforce(u_new, alpha);
  check_energy(u_new, step_size);
  previous_step_size_ = step_size;
  u_previous_.swap(u_);
  std::copy(u_new.begin(), u_new.end(), u_.begin());
}

void Simulation::check_energy(std::span<const double> u_new, double step_size) {
  for (std::size_t s = 0; s < constraint_sets_.size(); ++s) {
    const NodalConstraints& set = *constraint_sets_[s];
    const std::size_t n = std::min({previous_values_[s].size(), set.values.size(), set.reactions.size()});
    for (std::size_t k = 0; k < n; ++k)
      for (int c = 0; c < 3; ++c)
        if (set.components[c]) work_bound_ += std::abs(set.reactions[k][c] * (set.values[k][c] - previous_values_[s][k][c]));
  }
  // The projection onto the constraints also changes the velocities it touches: the kinetic energy it adds is
  // work the prescribed motion does on the nodes it drives directly. Only additions count: the energy it takes
  // out of a growing mode (at fixed nodes) must not raise the bound that mode is measured against.
  if (step_size > 0.0) {
    double added = 0.0;
    for (std::size_t d = 0; d < u_new.size(); ++d) {
      const double after = u_new[d] - u_[d], before = u_free_[d] - u_[d];
      added += mass_[d / 3] * std::max(0.0, after * after - before * before);
    }
    work_bound_ += 0.5 * added / (step_size * step_size);
  }
  // External force drivers would need their own work; none of the shipped plugins has one.
  if (force_drivers_ > 0 || !(step_size > 0.0) || !(previous_step_size_ > 0.0)) return;
  // The kinetic energy central differences conserve: 1/2 v(n-1/2) M v(n+1/2), the product of the two half-step
  // velocities around step n. (The square of one half-step velocity overstates the energy of modes near the
  // stability limit by 1 / (1 - (h omega / 2)^2), which would flag stable runs at large time-step factors.)
  // For a mode that grows, it grows too (in magnitude).
  const double scale = 0.5 / (step_size * previous_step_size_);
  double kinetic = 0.0;
  Index fastest = 0;
  double fastest_energy = 0.0;
  for (Index i = 0; i < model_->node_count(); ++i) {
    double product = 0.0;
    for (std::size_t d = 3 * static_cast<std::size_t>(i); d < 3 * static_cast<std::size_t>(i) + 3; ++d)
      product += (u_[d] - u_previous_[d]) * (u_new[d] - u_[d]);
    const double e = scale * mass_[i] * product;
    kinetic += e;
    if (std::abs(e) > fastest_energy) {
      fastest_energy = std::abs(e);
      fastest = i;
    }
  }
  kinetic = std::abs(kinetic);
  // Kinetic plus strain energy never exceed the work put in (damping only removes energy), and the work is
  // bounded by the sum of |reaction x increment| accumulated above. A factor of 10 leaves room for the
  // one-sided quadrature of that work and for mass scaling; a growing instability passes it within a few
  // dozen steps.
  constexpr double kMargin = 10.0;
  if (!(kinetic > kMargin * work_bound_) || kinetic <= 0.0) return;
  Diagnostic d;
  d.step = load_.step;
  d.time = load_.time;
  d.what = "energy_growth";
  d.detail = fmt::format("kinetic energy {:.4g} J exceeds {:g} times the work the loads have put in ({:.4g} J): the "
                         "solution is growing without bound (the fastest node is {} at {} m); reduce the time-step "
                         "factor",
                         kinetic, kMargin, work_bound_, fastest, point_text(model_->nodes()[fastest]));
  d.nodes = {fastest};
  d.coordinates = {model_->nodes()[fastest]};
  throw InstabilityError(std::move(d));
}

void Simulation::run(StepObserver* observer) {
  integrator_->initialise(*this);
  if (observer != nullptr) observer->on_step(*this);
  while (!integrator_->finished(*this)) {
    integrator_->step(*this);
    if (observer != nullptr) observer->on_step(*this);
  }
}

std::vector<double> Simulation::interpolated_displacement() const {
  std::vector<double> out(u_.size());
  model_->interpolate(u_, out);
  return out;
}

}  // namespace mtled
