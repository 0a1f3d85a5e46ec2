// The kernel's force path (Driver::forces): a boundary that pushes a node group must be balanced, at the
// steady state, by the reactions of the constrained nodes (global equilibrium). With plain quadrature the
// internal forces sum to zero exactly (the shape functions' gradients sum to zero at every point), so the
// balance holds to the relaxation's tolerance.
#include <gtest/gtest.h>

#include "mtled/scene.hpp"
#include "mtled/simulation.hpp"
#include "test_support.hpp"

namespace mtled {
namespace {

TEST(DriverForces, AppliedForcesAreBalancedByTheReactions) {
  const test::OneThread one_thread;
  PluginCatalog catalog({test::plugin_dir(), MTLED_TEST_FORCE_PLUGIN_DIR});
  const Vec3 total(2e-4, -1e-4, -1e-3);  // N on the top face of a 10 mm cube: ~10 Pa against mu = 1 kPa
  const json scene = {
      {"mesh", {{"type", "box"}, {"size", {0.01, 0.01, 0.01}}, {"target_nodes", 300}}},
      {"shape_function", {{"type", "mls"}}},
      {"materials", {{{"type", "neo_hookean"}, {"mu", 1000}, {"D", 4e-5}}}},
      {"boundaries",
       {{{"type", "fixed"}, {"name", "bottom"}, {"nodes", {{"group", "z0"}}}},
        {{"type", "test_nodal_force"}, {"group", "z1"}, {"force", {total[0], total[1], total[2]}}}}},
      {"discretisation", {{"consistent_integration", false}}},
      {"integrator", {{"type", "dynamic_relaxation"}, {"load_steps", 200}, {"tolerance", 1e-8}}}};
  Simulation simulation(validate_scene(parse_scene(scene.dump(), "driver_forces_test.json"), catalog), catalog);
  ASSERT_TRUE(simulation.system().has_external_forces());
  simulation.loop().run();
  ASSERT_EQ(simulation.system().constraint_sets().size(), 1u);
  const Vec3 reaction = simulation.system().constraint_sets()[0]->total_reaction();
  EXPECT_LT((reaction + total).norm(), 1e-5 * total.norm()) << "reaction " << reaction.transpose();
}

}  // namespace
}  // namespace mtled
