// The cuda backend against the CPU engine, where a GPU is (label gpu; each test is skipped, not failed, without one):
// the same forces to round-off in both precisions, the same answer on every run (no floating-point atomics), and a
// whole needle insertion equal to the CPU's within round-off bounds (below).
#include <gtest/gtest.h>

#include <random>

#include "mtled/errors.hpp"
#include "mtled/force_kernel.hpp"
#include "mtled/interfaces/backend.hpp"
#include "mtled/io/mesh_writer.hpp"
#include "test_support.hpp"

namespace mtled {
namespace {

namespace fs = std::filesystem;

// The backend, or null when no usable device is present (the test then skips).
std::shared_ptr<StepEngine> cuda_engine() {
  try {
    return test::make<StepEngine>("cuda", json::object());
  } catch (const InputError& e) {
    if (std::string(e.what()).find("no usable CUDA device") != std::string::npos) return nullptr;
    throw;
  }
}

std::unique_ptr<test::Discretised> make_model(const std::string& material, RowPrecision precision) {
  TetMesh mesh = test::box_mesh(Vec3(0.01, 0.012, 0.008), 6, 7, 5, 0.3, 3);
  const auto shape_functions = test::make<ShapeFunctions>("mmls", json::object());
  json parameters = {{"mu", 722.0}, {"D", 5.57738e-5}, {"density", 1000.0}};
  if (material == "ogden") parameters["alpha"] = -1.3;
  Discretisation::Options options;
  options.precision = precision;
  return std::make_unique<test::Discretised>(
      std::move(mesh), shape_functions,
      std::vector<std::shared_ptr<const Material>>{test::make<Material>(material, parameters)}, options);
}

std::vector<double> random_field(Index nodes, unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> uniform(-3e-4, 3e-4);
  std::vector<double> u(3 * static_cast<std::size_t>(nodes));
  for (double& v : u) v = uniform(random);
  return u;
}

// Both evaluate f_I = sum_p (w P)_p t_pI from the same stored gradients, in other orders: a few ulps of the largest
// force (the CPU kernel's own bound against the one-point definition, Discretisation.VectorisedForces...). In single
// precision too: both store the test gradients grad N + correction rounded to float once (test_gradient) and widen them
// to double (an H100, 2026-11-27: 5.1e-16 of the largest force in both precisions).
TEST(CudaBackend, ForcesEqualTheCpusToRoundOffInBothPrecisions) {
  if (!cuda_engine()) GTEST_SKIP() << "no CUDA device";
  for (const std::string material : {"ogden", "neo_hookean"})
    for (const RowPrecision precision : {RowPrecision::double_precision, RowPrecision::single_precision}) {
      const auto model = make_model(material, precision);
      const auto engine = cuda_engine();
      engine->setup(model->kernel);
      const auto u = random_field(model->discretisation.node_count(), 7);
      std::vector<double> cpu(u.size()), gpu(u.size()), again(u.size());
      ASSERT_EQ(model->kernel.internal_forces(u, cpu), -1);
      ASSERT_EQ(engine->internal_forces(u, gpu), -1);
      ASSERT_EQ(engine->internal_forces(u, again), -1);
      double difference = 0.0, largest = 0.0;
      for (std::size_t i = 0; i < u.size(); ++i) {
        difference = std::max(difference, std::abs(gpu[i] - cpu[i]));
        largest = std::max(largest, std::abs(cpu[i]));
      }
      const bool single = precision == RowPrecision::single_precision;
      std::cout << material << (single ? " single" : " double") << ": max |f_gpu - f_cpu| / max |f| "
                << difference / largest << "\n";
      EXPECT_GT(largest, 0.0);
      EXPECT_LE(difference, 1e-13 * largest) << material << (single ? " single" : " double");
      EXPECT_EQ(gpu, again) << "the same forces on every evaluation";
    }
}

TEST(CudaBackend, AnInvertedPointIsReportedLikeTheCpus) {
  if (!cuda_engine()) GTEST_SKIP() << "no CUDA device";
  const auto model = make_model("ogden", RowPrecision::double_precision);
  const auto engine = cuda_engine();
  engine->setup(model->kernel);
  std::vector<double> u(3 * static_cast<std::size_t>(model->discretisation.node_count())), f(u.size());
  for (Index i = 0; i < model->discretisation.node_count(); ++i)
    u[3 * static_cast<std::size_t>(i) + 2] = -2.0 * model->discretisation.nodes()[i][2];
  EXPECT_EQ(engine->internal_forces(u, f), model->kernel.internal_forces(u, f));
}

// The drivers' reads: displacement_at brings u_n at the nodes asked for (gathered on the device), again after the
// list changes, and displacement() all of it afterwards.
TEST(CudaBackend, DisplacementAtBringsTheNodesAskedFor) {
  if (!cuda_engine()) GTEST_SKIP() << "no CUDA device";
  const auto model = make_model("ogden", RowPrecision::double_precision);
  const auto engine = cuda_engine();
  engine->setup(model->kernel);
  ASSERT_TRUE(engine->spreads_nodes());
  const auto u = random_field(model->discretisation.node_count(), 11),
             u_previous = random_field(model->discretisation.node_count(), 12);
  engine->set_state(u, u_previous);
  const Index last = model->discretisation.node_count() - 1;
  for (const std::vector<Index>& nodes : {std::vector<Index>{3, 0, last}, std::vector<Index>{1, 7}}) {
    const std::span<const double> read = engine->displacement_at(nodes);
    for (const Index n : nodes)
      for (std::size_t c = 0; c < 3; ++c)
        EXPECT_EQ(read[3 * static_cast<std::size_t>(n) + c], u[3 * static_cast<std::size_t>(n) + c]) << n << " " << c;
  }
  const std::span<const double> whole = engine->displacement();
  EXPECT_EQ(std::vector<double>(whole.begin(), whole.end()), u);
}

// A needle insertion into a gel block through the mtled executable (the mesh written by the test: GPU nodes often
// have no Gmsh): on the GPU in double precision the same steps as the CPU, NRMSE <= 1e-10 and the needle force
// within 1e-9 (the bounds for round-off); two GPU runs byte for byte the same; in single precision the GPU
// within the single-precision bounds of the CPU's double run (NRMSE 1e-6, force 1e-5).
TEST(CudaBackend, ANeedleRunEqualsTheCpusAndRepeatsExactly) {
  if (!cuda_engine()) GTEST_SKIP() << "no CUDA device";
  const fs::path folder = test::scratch_dir("cuda-needle");
  write_abaqus_mesh(test::box_mesh(Vec3(0.012, 0.012, 0.01), 10, 10, 8, 0.25, 5), folder / "block.inp");
  const json scene = {
      {"mesh", {{"type", "abaqus_file"}, {"path", "block.inp"}, {"scale", 1.0}}},
      {"shape_function", {{"type", "mmls"}}},
      {"materials", {{{"type", "ogden"}, {"mu", 722}, {"alpha", -1.3}, {"D", 5.57738e-5}, {"density", 1000}}}},
      {"boundaries", {{{"type", "fixed"}, {"name", "bottom"}, {"nodes", {{"group", "z0"}}}}}},
      {"needle", {{"type", "kinematic"}, {"diameter", 0.0016}, {"entry", {0.006, 0.006, 0.01}}, {"direction", {0, 0, -1}},
                  {"depth", 0.006}}},
      {"integrator", {{"type", "dynamic_relaxation"}, {"load_steps", 300}, {"load_curve", "linear"}, {"tolerance", 1e-3}}}};
  test::write_text(folder / "scene.json", scene.dump(2));
  std::map<std::string, json> summaries;
  for (const std::string run : {"cpu", "cuda", "cuda_again", "cuda_single"}) {
    std::vector<std::string> arguments = {"run", (folder / "scene.json").string(), "-o", (folder / run).string(),
                                          "--backend", run == "cpu" ? "cpu" : "cuda", "--no-progress"};
    arguments.insert(arguments.end(), {"--set", run == "cuda_single" ? "/discretisation/precision=\"single\""
                                                                     : "/discretisation/precision=\"double\""});
    const auto result = test::run_mtled(arguments);
    ASSERT_EQ(result.exit_code, 0) << result.output;
    summaries[run] = test::read_json(folder / run / "summary.json");
  }
  EXPECT_EQ(summaries["cuda"]["backend"]["type"], "cuda");
  EXPECT_EQ(summaries["cpu"]["steps"], summaries["cuda"]["steps"]);
  const auto force = [&](const std::string& run) { return summaries[run]["needle"]["final_force_N"].get<double>(); };
  EXPECT_GT(std::abs(force("cpu")), 0.0);
  EXPECT_NEAR(force("cuda"), force("cpu"), 1e-9 * std::abs(force("cpu")));
  EXPECT_NEAR(force("cuda_single"), force("cpu"), 1e-5 * std::abs(force("cpu")));
  for (const auto& [run, bound] : {std::pair{"cuda", 1e-10}, std::pair{"cuda_single", 1e-6}}) {
    const auto compared = test::run_mtled({"compare", (folder / run).string(), (folder / "cpu").string(), "--json"});
    ASSERT_EQ(compared.exit_code, 0) << compared.output;
    for (const auto& [component, nrmse] : json::parse(compared.output)["nrmse"].items())
      EXPECT_LE(nrmse.get<double>(), bound) << run << " " << component;
  }
  EXPECT_EQ(test::read_text(folder / "cuda" / "result.vtu"), test::read_text(folder / "cuda_again" / "result.vtu"));
}

}  // namespace
}  // namespace mtled
