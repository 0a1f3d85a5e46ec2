#include "mtled/simulation.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <Eigen/Eigenvalues>
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

// An instability located at one node of `model`.
InstabilityError node_instability(long step, double time, std::string what, std::string detail, const Model& model,
                                  Index node) {
  Diagnostic d;
  d.step = step;
  d.time = time;
  d.what = std::move(what);
  d.detail = std::move(detail);
  d.nodes = {node};
  d.coordinates = {model.nodes()[node]};
  return InstabilityError(std::move(d));
}

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
    for (NodalForces* set : driver->forces()) force_sets_.push_back(set);
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

  stable_step_every_ = scene.monitors.integer("stable_step_every_steps");
  stable_step_iterations_ = static_cast<int>(scene.monitors.integer("stable_step_iterations"));
  if (stable_step_every_ > 0) {
    // 1e-7 of the body's size: far inside the linear range of any element, far above round-off in the forces.
    Vec3 low = model_->nodes()[0], high = low;
    for (const Vec3& x : model_->nodes()) {
      low = low.cwiseMin(x);
      high = high.cwiseMax(x);
    }
    perturbation_length_ = 1e-7 * (high - low).norm();
  }
}

Simulation::~Simulation() = default;

void Simulation::equalise_critical_steps() {
  const auto& dt = model_->ip_critical_time_steps();
  const double target = *std::max_element(dt.begin(), dt.end());
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
  for (const NodalForces* set : force_sets_)
    for (std::size_t k = 0; k < set->nodes.size(); ++k)
      for (int c = 0; c < 3; ++c) f[3 * static_cast<std::size_t>(set->nodes[k]) + c] += set->values[k][c];
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
    throw node_instability(load_.step + 1, new_time, "non_finite",
                           fmt::format("displacement component {} of node {} at {} m became {}", "xyz"[i % 3], node,
                                       point_text(model_->nodes()[node]), u_new[i]),
                           *model_, node);
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
  if (stable_step_every_ > 0 && (load_.step == 1 || load_.step % stable_step_every_ == 0)) check_stable_step(step_size);
}

void Simulation::check_stable_step(double step_size) {
  // The largest eigenvalue of K v = lambda M v at the current state by Lanczos iteration on
  // A = M^-1/2 K M^-1/2 (full reorthogonalisation; a few dozen vectors), with A q from a forward difference of
  // the internal forces. Were K symmetric, the Ritz values would approach lambda_max from below and the estimate
  // could only overstate the stable step; variationally consistent integration makes K slightly unsymmetric,
  // and the estimate then lands within a few percent of 2 / sqrt(spectral radius) on either side
  // (tests/solver/stable_step_test.cpp). A run is stopped only when its step exceeds the estimate by 5%, so a
  // run that would finish is not stopped; beyond that margin the central-difference update (and dynamic
  // relaxation's, whose limit is the same as its damping vanishes) is unstable. The iteration runs in the
  // constrained subspace (every vector projected as the constraint correction projects each step's update,
  // ConstraintSystem::project_out): a mode that the constraints hold still, such as the tissue between the
  // driven points around a needle, cannot grow. The next check starts from this one's Ritz vector; the first,
  // from a random vector, uses three times as many.
  const std::size_t dofs = u_.size();
  if (mode_.empty()) {
    // A fixed pseudo-random start (reproducible runs) with a component along every mode.
    mode_.resize(dofs);
    std::uint64_t state = 0x9E3779B97F4A7C15ULL;
    for (double& x : mode_) {
      state ^= state << 13, state ^= state >> 7, state ^= state << 17;
      x = static_cast<double>(state >> 11) / 9007199254740992.0 - 0.5;
    }
  }
  std::vector<double> f0(dofs), f1(dofs), perturbed(dofs), root_mass(dofs);
  for (std::size_t d = 0; d < dofs; ++d) root_mass[d] = std::sqrt(mass_[d / 3]);
  if (model_->internal_forces(u_, f0) >= 0) return;  // an inadmissible state is the other monitors' business
  ++monitor_force_evaluations_;

  // A random start needs more vectors than a warm one to resolve the top of the spectrum.
  const int size = stable_step_checks_ == 0 ? 3 * stable_step_iterations_ : stable_step_iterations_;
  Eigen::MatrixXd q(static_cast<Eigen::Index>(dofs), size);
  Eigen::VectorXd alpha(size), beta(size);
  Eigen::VectorXd w(static_cast<Eigen::Index>(dofs));
  std::vector<double> increment(mode_);  // a displacement increment, projected into the constrained subspace
  constraint_system_->project_out(increment);
  for (std::size_t d = 0; d < dofs; ++d) w[static_cast<Eigen::Index>(d)] = root_mass[d] * increment[d];
  if (!(w.norm() > 0.0)) return;
  q.col(0) = w / w.norm();
  int built = 0;
  for (int j = 0; j < size; ++j) {
    // w = A q_j = M^-1/2 K M^-1/2 q_j, K x ~ (f(u + epsilon x) - f(u)) / epsilon
    double largest = 0.0;
    for (std::size_t d = 0; d < dofs; ++d) largest = std::max(largest, std::abs(q(static_cast<Eigen::Index>(d), j) / root_mass[d]));
    const double epsilon = perturbation_length_ / largest;
    for (std::size_t d = 0; d < dofs; ++d)
      perturbed[d] = u_[d] + epsilon * q(static_cast<Eigen::Index>(d), j) / root_mass[d];
    ++monitor_force_evaluations_;
    if (model_->internal_forces(perturbed, f1) >= 0) return;
    // M^-1 K x, projected, then back to the symmetric form: w = M^1/2 P M^-1 K x.
    for (std::size_t d = 0; d < dofs; ++d) increment[d] = (f1[d] - f0[d]) / (epsilon * mass_[d / 3]);
    constraint_system_->project_out(increment);
    for (std::size_t d = 0; d < dofs; ++d) w[static_cast<Eigen::Index>(d)] = root_mass[d] * increment[d];
    alpha[j] = q.col(j).dot(w);
    built = j + 1;
    // Full reorthogonalisation, twice (the forward difference makes A slightly unsymmetric).
    for (int pass = 0; pass < 2; ++pass) w -= q.leftCols(built) * (q.leftCols(built).transpose() * w);
    beta[j] = w.norm();
    if (j + 1 == size || !(beta[j] > 1e-10 * std::abs(alpha[j]))) break;
    q.col(j + 1) = w / beta[j];
  }
  Eigen::MatrixXd t = Eigen::MatrixXd::Zero(built, built);
  for (int j = 0; j < built; ++j) {
    t(j, j) = alpha[j];
    if (j + 1 < built) t(j, j + 1) = t(j + 1, j) = beta[j];
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> ritz(t);
  const double lambda = ritz.eigenvalues()[built - 1];
  if (!(lambda > 0.0) || !std::isfinite(lambda)) return;
  const Eigen::VectorXd vector = q.leftCols(built) * ritz.eigenvectors().col(built - 1);
  for (std::size_t d = 0; d < dofs; ++d) mode_[d] = vector[static_cast<Eigen::Index>(d)] / root_mass[d];

  ++stable_step_checks_;
  last_stable_step_ = 2.0 / std::sqrt(lambda);
  if (last_stable_step_ < smallest_stable_step_) {
    smallest_stable_step_ = last_stable_step_;
    smallest_stable_step_at_ = load_.step;
  }
  log().debug("step {}: stable step re-estimated {:.4g} s (time step {:.4g} s)", load_.step, last_stable_step_,
              step_size);
  constexpr double kMargin = 1.05;
  if (!(step_size > kMargin * last_stable_step_)) return;
  // Where the fastest mode lives: the node with the largest share of it.
  Index where = 0;
  double share = 0.0;
  for (std::size_t d = 0; d < dofs; ++d)
    if (std::abs(mode_[d]) > share) {
      share = std::abs(mode_[d]);
      where = static_cast<Index>(d / 3);
    }
  throw node_instability(
      load_.step, load_.time, "time_step_above_stable",
      fmt::format("the time step {:.4g} s exceeds the stable step of the current state, {:.4g} s = "
                  "2 / sqrt(lambda_max(M^-1 K)) re-estimated at step {} ({:.3g} times the setup estimate {:.4g} s); "
                  "its fastest mode is largest at node {} at {} m; reduce /integrator/time_step_factor to {:.2g} or "
                  "less",
                  step_size, last_stable_step_, load_.step, last_stable_step_ / stable_time_step_, stable_time_step_,
                  where, point_text(model_->nodes()[where]),
                  0.9 * last_stable_step_ / step_size * integrator_->report().time_step_factor),
      *model_, where);
}

json Simulation::stable_step_report() const {
  if (stable_step_every_ <= 0) return nullptr;
  json j = {{"every_steps", stable_step_every_},
            {"checks", stable_step_checks_},
            {"force_evaluations", monitor_force_evaluations_},
            {"setup_estimate_s", stable_time_step_}};
  if (stable_step_checks_ > 0) {
    j["last_estimate_s"] = last_stable_step_;
    j["smallest_estimate_s"] = smallest_stable_step_;
    j["smallest_estimate_step"] = smallest_stable_step_at_;
  }
  return j;
}

void Simulation::check_energy(std::span<const double> u_new, double step_size) {
  for (std::size_t s = 0; s < constraint_sets_.size(); ++s) {
    const NodalConstraints& set = *constraint_sets_[s];
    const std::size_t n = std::min({previous_values_[s].size(), set.values.size(), set.reactions.size()});
    for (std::size_t k = 0; k < n; ++k)
      for (int c = 0; c < 3; ++c)
        if (set.components()[c]) work_bound_ += std::abs(set.reactions[k][c] * (set.values[k][c] - previous_values_[s][k][c]));
  }
  // The projection onto the constraints also changes the velocities it touches: the kinetic energy it adds is
  // work the prescribed motion does on the nodes it drives directly. Only additions count: the energy it takes
  // out of a growing mode (at fixed nodes) must not raise the bound that mode is measured against.
  // The kinetic energy central differences conserve: 1/2 v(n-1/2) M v(n+1/2), the product of the two half-step
  // velocities around step n. (The square of one half-step velocity overstates the energy of modes near the
  // stability limit by 1 / (1 - (h omega / 2)^2), which would flag stable runs at large time-step factors.)
  // For a mode that grows, it grows too (in magnitude). Both in one pass over the nodes, shared by the team and
  // summed in thread order.
  if (!(step_size > 0.0)) return;
  const double scale = previous_step_size_ > 0.0 ? 0.5 / (step_size * previous_step_size_) : 0.0;
  ThreadTeam& team = model_->team();
  // A pass of a few operations per node: worth the team only on large clouds.
  const int parts = model_->node_count() >= 8192 * team.size() ? team.size() : 1;
  std::vector<EnergySums>& sums = energy_sums_;
  sums.assign(static_cast<std::size_t>(parts), EnergySums{});
  const auto pass = [&](int thread) {
    EnergySums& mine = sums[static_cast<std::size_t>(thread)];
    const auto [begin, end] = ThreadTeam::share(model_->node_count(), thread, parts);
    for (auto i = static_cast<std::size_t>(begin); i < static_cast<std::size_t>(end); ++i) {
      double added = 0.0, product = 0.0;
      for (std::size_t d = 3 * i; d < 3 * i + 3; ++d) {
        const double after = u_new[d] - u_[d], before = u_free_[d] - u_[d];
        added += std::max(0.0, after * after - before * before);
        product += (u_[d] - u_previous_[d]) * after;
      }
      mine.added += mass_[i] * added;
      const double e = scale * mass_[i] * product;
      mine.kinetic += e;
      if (std::abs(e) > mine.fastest_energy) {
        mine.fastest_energy = std::abs(e);
        mine.fastest = static_cast<Index>(i);
      }
    }
  };
  if (parts == 1)
    pass(0);
  else
    team.run(pass);
  double added = 0.0, kinetic = 0.0, fastest_energy = 0.0;
  Index fastest = 0;
  for (const EnergySums& part : sums) {
    added += part.added;
    kinetic += part.kinetic;
    if (part.fastest_energy > fastest_energy) {
      fastest_energy = part.fastest_energy;
      fastest = part.fastest;
    }
  }
  work_bound_ += 0.5 * added / (step_size * step_size);
  kinetic_energy_ = std::abs(kinetic);
  // External force drivers would need their own work; none of the shipped plugins has one.
  if (!force_sets_.empty() || !(previous_step_size_ > 0.0)) return;
  kinetic = std::abs(kinetic);
  // Kinetic plus strain energy never exceed the work put in (damping only removes energy), and the work is
  // bounded by the sum of |reaction x increment| accumulated above. A factor of 10 leaves room for the
  // one-sided quadrature of that work and for mass scaling; a growing instability passes it within a few
  // dozen steps.
  constexpr double kMargin = 10.0;
  if (!(kinetic > kMargin * work_bound_) || kinetic <= 0.0) return;
  throw node_instability(
      load_.step, load_.time, "energy_growth",
      fmt::format("kinetic energy {:.4g} J exceeds {:g} times the work the loads have put in ({:.4g} J): the solution "
                  "is growing without bound (the fastest node is {} at {} m); reduce the time-step factor",
                  kinetic, kMargin, work_bound_, fastest, point_text(model_->nodes()[fastest])),
      *model_, fastest);
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
