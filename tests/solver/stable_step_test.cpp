// The stable-step monitor (monitors/src/stable_step_monitor.cpp, scene section "monitors"): its Lanczos estimate of
// 2 / sqrt(lambda_max(M^-1 K)) against the exact value from a K assembled column by column, the setup's
// per-point bound against the same, detection of a time step above it, and no effect on the results.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <algorithm>
#include <cstdlib>
#include <span>

#include "mtled/errors.hpp"
#include "mtled/monitors/reorthogonalise.hpp"
#include "mtled/monitors/scene_monitors.hpp"
#include "mtled/scene.hpp"
#include "mtled/simulation.hpp"
#include "mtled/thread_team.hpp"
#include "test_support.hpp"

namespace mtled {
namespace {

// A 10 mm cube of the paper's gel (about 340 nodes on Gmsh's irregular cloud), dynamic relaxation.
json cube_scene(const json& integrator, const json& monitors, bool loaded, double top_displacement = -0.002) {
  json scene = {{"mesh", {{"type", "box"}, {"size", {0.01, 0.01, 0.01}}, {"target_nodes", 300}}},
                {"shape_function", {{"type", "mmls"}}},
                {"materials", {{{"type", "ogden"}, {"mu", 722}, {"alpha", -1.3}, {"D", 5.57738e-5}, {"density", 1000}}}},
                {"integrator", integrator},
                {"monitors", monitors}};
  if (loaded)
    scene["boundaries"] = {{{"type", "fixed"}, {"name", "bottom"}, {"nodes", {{"group", "z0"}}}},
                           {{"type", "prescribed_displacement"},
                            {"name", "top"},
                            {"nodes", {{"group", "z1"}}},
                            {"components", {"z"}},
                            {"displacement", {0, 0, top_displacement}}}};
  return scene;
}

Scene make_scene(const json& scene) {
  return validate_scene(parse_scene(scene.dump(), "stable_step_test.json"), test::catalog(), {monitors_section()});
}

// The largest |u| of a reference run and the largest difference of another run from it, over every unknown.
struct SteadyStateDifference {
  double largest = 0.0, difference = 0.0;
};
SteadyStateDifference difference_from(std::span<const double> u, std::span<const double> reference) {
  SteadyStateDifference d;
  for (std::size_t i = 0; i < reference.size(); ++i) {
    d.largest = std::max(d.largest, std::abs(reference[i]));
    d.difference = std::max(d.difference, std::abs(u[i] - reference[i]));
  }
  return d;
}

// 2 / sqrt(lambda_max) of K v = lambda M v at u = 0, K by forward differences of the internal forces, one
// column per unknown, M the simulation's (mass-scaled) lumped masses. With `constrained`, of the operator the
// constrained dynamics see, P~ A P~ with A = M^-1/2 K M^-1/2 and P~ = M^1/2 P M^-1/2 (P the constraint
// projection, assembled column by column).
// `at_current_state`: K at the simulation's displacement instead of u = 0.
double exact_stable_step(const Simulation& simulation, bool constrained = false, bool at_current_state = false) {
  const ForceKernel& kernel = simulation.system().force_kernel();
  const auto mass = simulation.system().mass();
  const Eigen::Index n = 3 * simulation.system().discretisation().node_count();
  std::vector<double> u(static_cast<std::size_t>(n), 0.0), f(static_cast<std::size_t>(n)), f0(u);
  if (at_current_state) u.assign(simulation.system().displacement().begin(), simulation.system().displacement().end());
  EXPECT_LT(kernel.internal_forces(u, f0), 0);
  constexpr double kStep = 1e-10;  // m: strains of 1e-7 on a 1 mm spacing, linear to round-off
  Eigen::MatrixXd a(n, n);
  for (Eigen::Index j = 0; j < n; ++j) {
    const double start = u[static_cast<std::size_t>(j)];
    u[static_cast<std::size_t>(j)] = start + kStep;
    EXPECT_LT(kernel.internal_forces(u, f), 0);
    u[static_cast<std::size_t>(j)] = start;
    for (Eigen::Index i = 0; i < n; ++i)
      a(i, j) = (f[static_cast<std::size_t>(i)] - f0[static_cast<std::size_t>(i)]) / kStep /
                std::sqrt(mass[i / 3] * mass[j / 3]);
  }
  if (constrained) {
    Eigen::MatrixXd p(n, n);
    std::vector<double> column(static_cast<std::size_t>(n));
    for (Eigen::Index j = 0; j < n; ++j) {
      std::fill(column.begin(), column.end(), 0.0);
      column[static_cast<std::size_t>(j)] = 1.0 / std::sqrt(mass[j / 3]);
      simulation.system().constraints().project_out(column);
      for (Eigen::Index i = 0; i < n; ++i) p(i, j) = std::sqrt(mass[i / 3]) * column[static_cast<std::size_t>(i)];
    }
    a = p * a * p;
  }
  // Variationally consistent integration corrects the test functions only, so K is not exactly symmetric:
  // the central-difference limit is set by the spectral radius of the general matrix.
  const Eigen::EigenSolver<Eigen::MatrixXd> eigen(a, false);
  const double radius = eigen.eigenvalues().cwiseAbs().maxCoeff();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> symmetric(0.5 * (a + a.transpose()), Eigen::EigenvaluesOnly);
  ::testing::Test::RecordProperty("symmetric_part_over_radius", std::to_string(symmetric.eigenvalues()[n - 1] / radius));
  return 2.0 / std::sqrt(radius);
}

TEST(StableStepMonitor, LanczosEstimateMatchesTheAssembledSpectrum) {
  const test::OneThread one_thread;
  // Unloaded: the state stays u = 0, where the check at step 1 runs and the exact spectrum is taken.
  const Scene scene = make_scene(cube_scene({{"type", "dynamic_relaxation"}, {"load_steps", 1}},
                                            {{"stable_step_every_steps", 1000000}, {"stable_step", "adapt"}}, false));
  Simulation simulation(scene, test::catalog());
  add_scene_monitors(simulation, scene);
  simulation.loop().run();
  const json report = simulation.loop().monitor_reports().at("stable_step");
  ASSERT_EQ(report.at("checks").get<long>(), 1);
  const double estimate = report.at("last_estimate_s").get<double>();
  const double exact = exact_stable_step(simulation);
  // For a symmetric K the Ritz values never exceed lambda_max and the estimate could only overstate the
  // stable step. K is slightly unsymmetric here (the symmetric part's largest eigenvalue is about 4% above
  // the spectral radius), and the estimate lands within a few percent of the truth on either side; the
  // monitor allows 5% before it stops a run.
  EXPECT_GE(estimate, exact * 0.95);
  EXPECT_LE(estimate, exact * 1.02);
  // The per-integration-point bound the integrators use must be conservative.
  EXPECT_LE(simulation.system().stable_time_step(), exact);
  RecordProperty("estimate_over_exact", std::to_string(estimate / exact));
  RecordProperty("setup_bound_over_exact", std::to_string(simulation.system().stable_time_step() / exact));
}

// The Lanczos iteration's reorthogonalisation by row chunks: w loses exactly its part in the span of Q's first columns
// (the later columns untouched, a last chunk shorter than the others), and the result is bit for bit the same however
// the chunks are spread: on the caller, on a team of 2 and 3 threads, in shares taken in reverse order.
TEST(StableStepMonitor, ReorthogonalisationByChunksRemovesTheBasisAlikeOnAnyThreads) {
  const Eigen::Index rows = 3 * kReorthogonalisationChunk + 101, used = 7;
  std::srand(5);
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(Eigen::MatrixXd::Random(rows, used + 2));
  const Eigen::MatrixXd q = qr.householderQ() * Eigen::MatrixXd::Identity(rows, used + 2);
  const Eigen::VectorXd w0 = Eigen::VectorXd::Random(rows);
  Eigen::VectorXd serial = w0;
  reorthogonalise(q, used, serial, {});
  const Eigen::VectorXd expected = w0 - q.leftCols(used) * (q.leftCols(used).transpose() * w0);
  EXPECT_LE((serial - expected).cwiseAbs().maxCoeff(), 1e-14 * w0.norm());
  EXPECT_LE((q.leftCols(used).transpose() * serial).cwiseAbs().maxCoeff(), 1e-14 * w0.norm());
  for (Eigen::Index k = used; k < used + 2; ++k) EXPECT_NEAR(q.col(k).dot(serial), q.col(k).dot(w0), 1e-14 * w0.norm());

  const ForEachShare reversed = [](std::int64_t n, const auto& body) {
    for (std::int64_t end = n; end > 0; end -= 2) body(std::max<std::int64_t>(end - 2, 0), end);
  };
  Eigen::VectorXd w = w0;
  reorthogonalise(q, used, w, reversed);
  EXPECT_TRUE(w == serial) << "shares in reverse order";
  for (const int threads : {2, 3}) {
    ThreadTeam team(threads);
    w = w0;
    reorthogonalise(q, used, w, [&](std::int64_t n, const auto& body) { team.for_each_share(n, body); });
    EXPECT_TRUE(w == serial) << threads << " threads";
  }
}

// The projection the constrained iteration uses: what it returns leaves every constrained value unchanged (the
// bottom face held in x, y, z and the top in z; MMLS does not interpolate, so these are interpolated values),
// projecting twice changes nothing, and what it removes is M-orthogonal to what it keeps.
TEST(StableStepMonitor, ConstraintProjectionKeepsConstrainedValuesAndIsMOrthogonal) {
  const test::OneThread one_thread;
  const Scene scene = make_scene(cube_scene({{"type", "dynamic_relaxation"}, {"load_steps", 1}},
                                            {{"stable_step_every_steps", 1000000}}, true, 0.0));
  Simulation simulation(scene, test::catalog());
  simulation.loop().run();
  const Discretisation& model = simulation.system().discretisation();
  const auto mass = simulation.system().mass();
  const std::size_t n = 3 * static_cast<std::size_t>(model.node_count());
  std::vector<double> v(n), w(n);
  for (std::size_t i = 0; i < n; ++i) {
    v[i] = std::sin(1.3 * static_cast<double>(i) + 0.4);
    w[i] = std::cos(0.7 * static_cast<double>(i));
  }
  std::vector<double> pv = v, pw = w;
  simulation.system().constraints().project_out(pv);
  simulation.system().constraints().project_out(pw);
  const double scale = Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(n)).lpNorm<Eigen::Infinity>();
  int checked = 0;
  for (const NodalConstraints* set : simulation.system().constraint_sets())
    for (Index node : set->nodes()) {
      const Vec3 value = model.interpolate_node(node, pv);
      for (int c = 0; c < 3; ++c)
        if (set->components()[c]) {
          EXPECT_NEAR(value[c], 0.0, 1e-12 * scale) << set->name << " node " << node;
          ++checked;
        }
    }
  EXPECT_GT(checked, 100);
  std::vector<double> twice = pv;
  simulation.system().constraints().project_out(twice);
  double change = 0.0, removed_dot_kept = 0.0, removed_norm = 0.0, kept_norm = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    change = std::max(change, std::abs(twice[i] - pv[i]));
    removed_dot_kept += (v[i] - pv[i]) * mass[i / 3] * pw[i];
    removed_norm += (v[i] - pv[i]) * mass[i / 3] * (v[i] - pv[i]);
    kept_norm += pw[i] * mass[i / 3] * pw[i];
  }
  EXPECT_LT(change, 1e-12 * scale);
  EXPECT_GT(removed_norm, 0.0);
  EXPECT_NEAR(removed_dot_kept / std::sqrt(removed_norm * kept_norm), 0.0, 1e-10);
}

// With constraints the estimate is that of the constrained dynamics: against the assembled P~ A P~, and never
// below the unconstrained one's stable step.
TEST(StableStepMonitor, ConstrainedEstimateMatchesTheConstrainedSpectrum) {
  const test::OneThread one_thread;
  // Constrained faces held at zero: the state stays u = 0, where the check at step 1 runs.
  const Scene scene = make_scene(cube_scene({{"type", "dynamic_relaxation"}, {"load_steps", 1}},
                                            {{"stable_step_every_steps", 1000000}, {"stable_step", "adapt"}}, true,
                                            0.0));
  Simulation simulation(scene, test::catalog());
  add_scene_monitors(simulation, scene);
  simulation.loop().run();
  const json report = simulation.loop().monitor_reports().at("stable_step");
  ASSERT_EQ(report.at("checks").get<long>(), 1);
  const double estimate = report.at("last_estimate_s").get<double>();
  const double exact = exact_stable_step(simulation, true);
  const double unconstrained = exact_stable_step(simulation, false);
  EXPECT_GE(estimate, exact * 0.95);
  EXPECT_LE(estimate, exact * 1.02);
  EXPECT_GE(exact, unconstrained * (1.0 - 1e-9));
  RecordProperty("estimate_over_exact", std::to_string(estimate / exact));
  RecordProperty("constrained_over_unconstrained", std::to_string(exact / unconstrained));
}

TEST(StableStepMonitor, StopsAStepAboveTheStableStepAtTheFirstCheck) {
  const test::OneThread one_thread;
  const Scene scene =
      make_scene(cube_scene({{"type", "dynamic_relaxation"}, {"load_steps", 100}, {"time_step_factor", 10}},
                            {{"stable_step", "stop"}}, true));
  Simulation simulation(scene, test::catalog());
  add_scene_monitors(simulation, scene);
  try {
    simulation.loop().run();
    FAIL() << "a time step 10 times the bound ran";
  } catch (const InstabilityError& e) {
    EXPECT_EQ(e.diagnostic().what, "time_step_above_stable");
    EXPECT_EQ(e.diagnostic().step, 1);
    ASSERT_EQ(e.diagnostic().nodes.size(), 1u);
    EXPECT_NE(std::string(e.what()).find("/integrator/time_step_factor"), std::string::npos);
  }
}

// An extreme stiffening: Ogden with alpha = 20 (compressible, nu = 0.3) stretched 80%, whose tangent stiffness
// grows about 1.8^18 = 4e4-fold along the load. The setup's step, kept fixed, blows up (energy growth); re-estimated
// every 20 steps and adopted ("adapt"; "follow", the default, lowers alike), the step is lowered and the relaxation
// reaches the same steady state as a run whose step is small enough from the start (factor 0.05 instead of 0.9), to
// the relaxations' tolerance.
TEST(StableStepMonitor, AdaptsTheStepWhereAFixedStepBlowsUp) {
  const test::OneThread one_thread;
  auto scene_with = [](const json& monitors, double factor) {
    json scene = cube_scene({{"type", "dynamic_relaxation"}, {"load_steps", 400}, {"tolerance", 1e-5},
                             {"time_step_factor", factor}},
                            monitors, true, 0.008);
    scene["materials"][0]["alpha"] = 20.0;
    scene["materials"][0]["D"] = 1.2786e-3;  // nu = 0.3: D = 3 (1 - 2 nu) / (mu (1 + nu))
    return make_scene(scene);
  };
  {
    const Scene fixed = scene_with({{"stable_step_every_steps", 0}}, 0.9);
    Simulation simulation(fixed, test::catalog());
    add_scene_monitors(simulation, fixed);
    EXPECT_THROW(simulation.loop().run(), InstabilityError);
  }
  const Scene adapt = scene_with({{"stable_step_every_steps", 20}, {"stable_step", "adapt"}}, 0.9);
  Simulation adapted(adapt, test::catalog());
  add_scene_monitors(adapted, adapt);
  adapted.loop().run();
  const json report = adapted.loop().monitor_reports().at("stable_step");
  EXPECT_GE(report.at("time_step_lowered").get<long>(), 1) << report.dump();
  // The integrator took the lowered step, below the setup's (0.9 of the mass-scaled setup estimate).
  const double step = adapted.loop().integrator().report().time_step;
  EXPECT_NEAR(step, report.at("lowest_time_step_s").get<double>(), 1e-12 * step);
  EXPECT_LT(step, 0.9 * report.at("setup_estimate_s").get<double>());
  const Scene small = scene_with({{"stable_step_every_steps", 0}}, 0.05);
  Simulation reference(small, test::catalog());
  add_scene_monitors(reference, small);
  reference.loop().run();
  const auto [largest, difference] =
      difference_from(adapted.system().displacement(), reference.system().displacement());
  // Each relaxation stops within 1e-5 of the largest displacement of its steady state (with margin: 10x).
  EXPECT_LT(difference, 1e-4 * largest);
  RecordProperty("difference_over_largest", std::to_string(difference / largest));
}

// Dynamic relaxation's held_mass_scaling on a cube of a law that stiffens hard in compression (the scene above, 80%
// compressed): at the held state its tangent is many times stiffer than at rest, and with the setup's masses the
// state's stable step falls below the step the ramp started at (0.9 of the setup's per-point bound; 0.66 of the bound
// when written). The masses scaled to the current stiffness as the hold begins bring it back above the bound (4.0 times
// it, as conservative as at rest), and the relaxation reaches the same steady state.
TEST(StableStepMonitor, MassesScaledToTheHeldStateKeepThePerPointBound) {
  const test::OneThread one_thread;
  auto run = [](bool held_mass_scaling) {
    json scene = cube_scene({{"type", "dynamic_relaxation"},
                             {"load_steps", 400},
                             {"tolerance", 1e-5},
                             {"held_mass_scaling", held_mass_scaling}},
                            {{"stable_step_every_steps", 20}}, true, 0.008);
    scene["materials"][0]["alpha"] = 20.0;
    scene["materials"][0]["D"] = 1.2786e-3;  // nu = 0.3
    const Scene valid = make_scene(scene);
    auto simulation = std::make_unique<Simulation>(valid, test::catalog());
    add_scene_monitors(*simulation, valid);
    simulation->loop().run();
    return simulation;
  };
  const auto scaled = run(true), unscaled = run(false);
  // The setup's per-point bound (mass-scaled), the same for both: the scaling at the hold does not move it.
  const double bound = scaled->loop().monitor_reports().at("stable_step").at("setup_estimate_s").get<double>();
  EXPECT_EQ(unscaled->loop().monitor_reports().at("stable_step").at("setup_estimate_s").get<double>(), bound);
  const double exact_scaled = exact_stable_step(*scaled, false, true);
  const double exact_unscaled = exact_stable_step(*unscaled, false, true);
  RecordProperty("exact_over_bound_scaled", std::to_string(exact_scaled / bound));
  RecordProperty("exact_over_bound_unscaled", std::to_string(exact_unscaled / bound));
  EXPECT_LT(exact_unscaled, 0.9 * bound);
  EXPECT_GE(exact_scaled, bound);
  const auto [largest, difference] =
      difference_from(scaled->system().displacement(), unscaled->system().displacement());
  // Each relaxation stops within 1e-5 of the largest displacement of the same steady state (with margin: 10x).
  EXPECT_LT(difference, 1e-4 * largest);
  RecordProperty("difference_over_largest", std::to_string(difference / largest));
  RecordProperty("steps_scaled", std::to_string(scaled->system().step()));
  RecordProperty("steps_unscaled", std::to_string(unscaled->system().step()));
}

// Records every step's size and whether it held the loads (its load fraction equal to the previous step's).
class StepSizes final : public StepMonitor {
 public:
  struct Entry {
    double size;
    bool held;
  };
  std::string name() const override { return "step_sizes"; }
  bool reads_displacement(long) const override { return false; }
  void after_step(const StepRecord& step) override {
    entries.push_back({step.step_size, step.load.load_fraction == previous_});
    previous_ = step.load.load_fraction;
  }
  std::vector<Entry> entries;

 private:
  double previous_ = NAN;
};

// "follow" (the default) raises dynamic relaxation's step to its margin of the estimate while the loads are held (the
// cube's estimate is about three times the setup bound the ramp runs at), puts the ramp's step back when the loads
// move again (two relaxed increments), and reaches the steady states "adapt" reaches, in fewer steps.
TEST(StableStepMonitor, FollowsTheStableStepUpWhileTheLoadsAreHeld) {
  const test::OneThread one_thread;
  struct Run {
    json stable_step;
    std::vector<StepSizes::Entry> steps;
    std::vector<double> u;
  };
  auto run = [](const std::string& response) {
    const Scene scene = make_scene(cube_scene({{"type", "dynamic_relaxation"}, {"load_steps", 200}, {"tolerance", 1e-5},
                                               {"relaxed_increments", 2}},
                                              {{"stable_step", response}}, true));
    Simulation simulation(scene, test::catalog());
    add_scene_monitors(simulation, scene);
    auto sizes = std::make_shared<StepSizes>();
    simulation.loop().add_monitor(sizes);
    simulation.loop().run();
    return Run{
        simulation.loop().monitor_reports().at("stable_step"), sizes->entries,
        std::vector<double>(simulation.system().displacement().begin(), simulation.system().displacement().end())};
  };
  const Run adapt = run("adapt"), follow = run("follow");
  EXPECT_EQ(adapt.stable_step.at("time_step_lowered").get<long>(), 0) << adapt.stable_step.dump();
  EXPECT_EQ(follow.stable_step.at("time_step_raised").get<long>(), 2) << follow.stable_step.dump();  // one per hold
  const double ramp_step = adapt.steps.front().size, raised = follow.stable_step.at("highest_time_step_s");
  EXPECT_GT(raised, 1.5 * ramp_step);
  // Every step of the ramps at the ramp's step, but the first after a hold (taken from the settled state the raised
  // step was estimated for); the holds at the raised step once it is raised.
  long ramp_steps = 0, raised_steps = 0;
  for (std::size_t k = 1; k < follow.steps.size(); ++k) {
    const auto& step = follow.steps[k];
    if (!step.held && !follow.steps[k - 1].held) {
      ++ramp_steps;
      EXPECT_NEAR(step.size, ramp_step, 1e-12 * ramp_step) << "step " << k + 1;
    }
    if (step.held && step.size > 1.05 * ramp_step) ++raised_steps;
  }
  EXPECT_GT(ramp_steps, 190);  // the 200 steps of the two ramps, less their first steps
  EXPECT_GT(raised_steps, 0);
  EXPECT_LT(follow.steps.size(), adapt.steps.size());
  RecordProperty("steps_adapt", std::to_string(adapt.steps.size()));
  RecordProperty("steps_follow", std::to_string(follow.steps.size()));
  const auto [largest, difference] = difference_from(follow.u, adapt.u);
  // Each relaxation stops within 1e-5 of the largest displacement of the same steady state (with margin: 10x).
  EXPECT_LT(difference, 1e-4 * largest);
  RecordProperty("difference_over_largest", std::to_string(difference / largest));
}

// Central differences' time is physical: "follow" raises nothing there and re-estimates at no hold, so a run whose load
// is held for its last third equals the "adapt" run bitwise, lowered step included (factor 5: above the margin 0.5).
TEST(StableStepMonitor, FollowIsAdaptForCentralDifferences) {
  const test::OneThread one_thread;
  auto run = [](const std::string& response) {
    const Scene scene = make_scene(cube_scene({{"type", "central_difference"}, {"duration", 0.03}, {"load_time", 0.02},
                                               {"damping", 60}, {"time_step_factor", 5}},
                                              {{"stable_step", response}, {"stable_step_every_steps", 100}}, true));
    Simulation simulation(scene, test::catalog());
    add_scene_monitors(simulation, scene);
    simulation.loop().run();
    return std::make_pair(
        simulation.loop().monitor_reports().at("stable_step"),
        std::vector<double>(simulation.system().displacement().begin(), simulation.system().displacement().end()));
  };
  const auto [adapt, adapt_u] = run("adapt");
  const auto [follow, follow_u] = run("follow");
  EXPECT_GE(adapt.at("time_step_lowered").get<long>(), 1) << adapt.dump();
  EXPECT_EQ(follow.at("time_step_raised").get<long>(), 0) << follow.dump();
  EXPECT_EQ(follow.at("checks"), adapt.at("checks"));
  EXPECT_EQ(follow_u, adapt_u);
}

TEST(StableStepMonitor, ChangesNothingInTheResultsUnderAdapt) {
  const test::OneThread one_thread;
  auto final_state = [](long every) {
    const Scene scene = make_scene(cube_scene({{"type", "dynamic_relaxation"}, {"load_steps", 200}, {"tolerance", 1e-4}},
                                              {{"stable_step_every_steps", every}, {"stable_step", "adapt"}}, true));
    Simulation simulation(scene, test::catalog());
    add_scene_monitors(simulation, scene);
    simulation.loop().run();
    EXPECT_EQ(simulation.loop().monitor_reports().contains("stable_step"), every != 0);
    return std::vector<double>(simulation.system().displacement().begin(), simulation.system().displacement().end());
  };
  EXPECT_EQ(final_state(0), final_state(50));  // bitwise: the monitor only reads the state
}

}  // namespace
}  // namespace mtled
