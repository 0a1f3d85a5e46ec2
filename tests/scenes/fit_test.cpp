// mtled fit end to end on small scenes, each with a known truth: data made by the model at known parameter values
// (`mtled fit --synthesize`, seeded Gaussian noise of the stated standard deviation), then fitted from start points
// 40% off. The recovered values must lie within their reported 2-sigma intervals and within the accuracy the noise
// allows; a parameter the data do not depend on is reported as not identifiable; bad input stops before any run.
#include "mtled/analysis/fit.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <set>

#include "in_process_run.hpp"
#include "mtled/errors.hpp"
#include "mtled/simulation.hpp"
#include "test_support.hpp"
#include "xml_check.hpp"

namespace fs = std::filesystem;

namespace mtled::test {
namespace {

void expect_contains(const std::string& text, const std::string& part) {
  EXPECT_NE(text.find(part), std::string::npos) << "expected \"" << part << "\" in:\n" << text;
}

// A 10 mm Ogden cube compressed to a stretch of 0.7 (the uniaxial scene at a coarse resolution), its top force in
// equilibrium at six depths of the platen.
json compression_cube() {
  return {{"mesh", {{"type", "box"}, {"size", {0.01, 0.01, 0.01}}, {"target_nodes", 300}}},
          {"shape_function", {{"type", "mls"}}},
          {"materials", {{{"type", "ogden"}, {"mu", 722}, {"alpha", -1.3}, {"D", 5.57738e-5}, {"density", 1000}}}},
          {"boundaries",
           {{{"type", "fixed"}, {"name", "bottom"}, {"nodes", {{"group", "z0"}}}, {"components", {"z"}}},
            {{"type", "prescribed_displacement"},
             {"name", "top"},
             {"nodes", {{"group", "z1"}}},
             {"components", {"z"}},
             {"displacement", {0, 0, -0.004}}},
            {{"type", "fixed"}, {"name", "symmetry_x"}, {"nodes", {{"group", "x0"}}}, {"components", {"x"}}},
            {{"type", "fixed"}, {"name", "symmetry_y"}, {"nodes", {{"group", "y0"}}}, {"components", {"y"}}}}},
          {"integrator",
           {{"type", "dynamic_relaxation"}, {"load_steps", 300}, {"tolerance", 1e-7}, {"relaxed_increments", 8}}}};
}

// The platen's displacements where the force was "measured" (the values are filled by --synthesize).
void write_compression_template(const fs::path& file) {
  std::string text = "displacement_m,force_N\n";
  for (int k = 1; k <= 8; ++k) text += std::to_string(-0.0005 * k) + ",0\n";
  write_text(file, text);
}

json compression_fit(const std::string& data) {
  return {{"description", "Ogden mu and alpha from a compression force curve"},
          {"parameters",
           {{{"name", "mu"},
             {"pointer", "/materials/0/mu"},
             {"lower", 100},
             {"upper", 5000},
             {"start", 722},
             {"log", true}},
            {{"name", "alpha"}, {"pointer", "/materials/0/alpha"}, {"lower", -6}, {"upper", -0.2}, {"start", -1.3}}}},
          {"experiments",
           {{{"name", "compression"},
             {"scene", "cube.json"},
             {"data", data},
             {"compare", {{"type", "reaction_force"}, {"set", "top"}, {"component", "z"}}},
             {"sigma_relative", 0.01}}}},
          {"method", {{"type", "levenberg_marquardt"}, {"max_evaluations", 40}}},
          {"threads", 2}};
}

// The compression cube's scene and data template written in `folder`, and `fit` (compression_fit's, edited) read.
fit::Plan compression_plan(const fs::path& folder, const json& fit) {
  write_text(folder / "cube.json", compression_cube().dump(2));
  write_compression_template(folder / "compression.csv");
  write_text(folder / "fit.json", fit.dump(2));
  return fit::read(folder / "fit.json", {}, {plugin_dir()});
}

// Forward runs in this process, as mtled fit makes them, sharing `bases`.
fit::InProcessRunner in_process(BasisCache& bases) {
  return [&bases](const fit::ForwardRun& run) { return app::run_forward_in_process(run, &bases); };
}

// Synthesizes data at the fit file's start values (noise seeded with `seed`) into folder/truth, then fits them from
// `starts` (pointer=value overrides on the fit file) into folder/fit.
json synthesize_then_fit(const fs::path& folder, const fs::path& fit_file, const std::string& template_data,
                         const std::string& data_pointer, int seed, const std::vector<std::string>& starts) {
  const auto made =
      run_mtled({"fit", fit_file.string(), "-o", (folder / "truth").string(), "--synthesize", std::to_string(seed)});
  EXPECT_EQ(made.exit_code, 0) << made.output;
  const fs::path data = folder / "truth" / "data" / template_data;
  EXPECT_TRUE(fs::exists(data)) << made.output;
  std::vector<std::string> args = {
      "fit", fit_file.string(), "-o", (folder / "fit").string(), "--set", data_pointer + "=\"" + data.string() + "\""};
  for (const auto& s : starts) args.insert(args.end(), {"--set", s});
  const auto fitted = run_mtled(args);
  EXPECT_EQ(fitted.exit_code, 0) << fitted.output;
  return read_json(folder / "fit" / "fit.json");
}

const json& parameter(const json& report, const std::string& name) {
  for (const auto& p : report["parameters"])
    if (p["name"] == name) return p;
  throw std::runtime_error("no parameter " + name);
}

// Four noise realisations (seeds 1 to 4): a 2-sigma interval holds the truth 95% of the time, so each parameter's
// must hold it in at least 3 of 4 fits (fewer has a chance of 1.4% for intervals that are right), and the mean of
// the four estimates must lie within 2 standard errors of the mean (sigma / 2) of the truth: no bias. mu is the
// initial shear modulus of eq. (1), fixed by the small-strain forces: within 2% in every fit. alpha, fixed by the
// curve's bend alone, is known to about 5% (1 sigma) from eight forces to 40% compression at 1% noise.
TEST(Fit, RecoversOgdenMuAndAlphaFromACompressionForceCurve) {
  const fs::path folder = scratch_dir("fit-compression");
  write_text(folder / "cube.json", compression_cube().dump(2));
  write_compression_template(folder / "compression.csv");
  write_text(folder / "fit.json", compression_fit("compression.csv").dump(2));
  const std::vector<std::pair<std::string, double>> truths = {{"mu", 722.0}, {"alpha", -1.3}};
  std::map<std::string, std::vector<double>> values, errors;
  for (const int seed : {1, 2, 3, 4}) {
    // Starts 40% off the truth.
    const json report =
        synthesize_then_fit(folder / std::to_string(seed), folder / "fit.json", "compression.csv",
                            "/experiments/0/data", seed, {"/parameters/0/start=433.2", "/parameters/1/start=-1.82"});
    ASSERT_TRUE(report.is_object());
    EXPECT_EQ(report["status"], "converged") << report.dump(2);
    EXPECT_TRUE(report["not_identifiable"].empty()) << report.dump(2);
    EXPECT_GT(report["experiments"][0]["r_squared"].get<double>(), 0.999);
    for (const auto& [name, truth] : truths) {
      values[name].push_back(parameter(report, name)["value"].get<double>());
      errors[name].push_back(parameter(report, name)["standard_error"].get<double>());
    }
    EXPECT_LT(std::abs(values["mu"].back() - 722.0), 0.02 * 722.0) << report.dump(2);
    if (seed == 1) {  // every evaluation recorded with its folder; the figure and the fitted-against-measured table
      const fs::path out = folder / "1" / "fit";
      EXPECT_EQ(read_csv(out / "fit.csv").size(), report["evaluations"].get<std::size_t>() + 1);
      EXPECT_EQ(xml_problem(read_text(out / "fit.svg")), "");
      EXPECT_EQ(read_csv(out / "fit_data.csv").size(), 9u);
      EXPECT_TRUE(fs::exists(out / "meshes" / "compression.inp"));  // the mesh written once, read by every run
    }
  }
  for (const auto& [name, truth] : truths) {
    int covered = 0;
    double mean = 0.0, error = 0.0;
    for (std::size_t i = 0; i < values[name].size(); ++i) {
      covered += std::abs(values[name][i] - truth) < 2.0 * errors[name][i];
      mean += values[name][i] / 4.0;
      error += errors[name][i] / 4.0;
    }
    EXPECT_GE(covered, 3) << name;
    EXPECT_LT(std::abs(mean - truth), 2.0 * error / 2.0) << name << ": mean " << mean;
  }
}

TEST(Fit, ReportsAParameterTheDataDoNotDependOnAsNotIdentifiable) {
  const fs::path folder = scratch_dir("fit-density");
  write_text(folder / "cube.json", compression_cube().dump(2));
  write_compression_template(folder / "compression.csv");
  json fit = compression_fit("compression.csv");
  // A steady state does not depend on the density: the force curve cannot identify it.
  fit["parameters"][1] = {
      {"name", "density"}, {"pointer", "/materials/0/density"}, {"lower", 500}, {"upper", 2000}, {"start", 1000}};
  write_text(folder / "fit.json", fit.dump(2));
  const json report = synthesize_then_fit(folder, folder / "fit.json", "compression.csv", "/experiments/0/data", 7,
                                          {"/parameters/0/start=433.2"});
  ASSERT_TRUE(report.is_object());
  bool density_named = false;
  for (const auto& line : report["not_identifiable"]) density_named |= line.get<std::string>().rfind("density", 0) == 0;
  EXPECT_TRUE(density_named) << report.dump(2);
  const double mu = parameter(report, "mu")["value"].get<double>();
  EXPECT_LT(std::abs(mu - 722.0), 0.02 * 722.0);
}

// The paper's X-ray experiment in small: 36 markers around the needle's path in a small gel cylinder, their
// displacements at a depth of 4 mm "measured" with 0.05 mm noise; C_D fitted from 0.24 (40% below the truth, 0.4).
// The markers come as a CSV file, or as two 3D Slicer point lists (before and after, matched by label, in mm).
class FitMarkers : public ::testing::TestWithParam<bool> {};

TEST_P(FitMarkers, RecoverTheDeformationCoefficient) {
  const bool slicer = GetParam();
  const fs::path folder = scratch_dir(slicer ? "fit-markups" : "fit-markers");
  json needle = {{"type", "kinematic"},     {"diameter", 0.0016}, {"entry", {0, 0, 0.008}},
                 {"direction", {0, 0, -1}}, {"depth", 0.004},     {"deformation_coefficient", 0.4},
                 {"puncture_strain", 1e-5}};
  write_text(folder / "gel.json", gel_cylinder_scene(0.008, needle).dump(2));
  std::string csv = "label,x_m,y_m,z_m,ux_m,uy_m,uz_m\n";
  json points = json::array();
  for (const double r : {0.0015, 0.0025, 0.0035, 0.0045})
    for (const double z : {0.0035, 0.005, 0.0065})
      for (int k = 0; k < 3; ++k) {
        const double a = 2.0 * M_PI * (k + 0.37 * r / 0.001) / 3.0;
        const std::string label = fmt::format("m{}", points.size() + 1);
        csv += fmt::format("{},{},{},{},0,0,0\n", label, r * std::cos(a), r * std::sin(a), z);
        points.push_back({{"label", label}, {"position", {1e3 * r * std::cos(a), 1e3 * r * std::sin(a), 1e3 * z}}});
      }
  ASSERT_EQ(points.size(), 36u);
  const json markups = {{"markups", {{{"type", "Fiducial"}, {"coordinateSystem", "RAS"}, {"controlPoints", points}}}}};
  write_text(folder / "markers.csv", csv);
  write_text(folder / "before.mrk.json", markups.dump(2));
  write_text(folder / "after.mrk.json", markups.dump(2));  // a template: --synthesize moves the points
  const json data = slicer ? json{{"before", "before.mrk.json"}, {"after", "after.mrk.json"}} : json("markers.csv");
  const json fit = {
      {"parameters",
       {{{"name", "C_D"},
         {"pointer", "/needle/deformation_coefficient"},
         {"lower", 0.05},
         {"upper", 0.9},
         {"start", 0.4}}}},
      {"experiments",
       {{{"name", "xray"}, {"scene", "gel.json"}, {"data", data}, {"compare", "markers"}, {"sigma", 5e-5}}}},
      {"threads", 2}};
  write_text(folder / "fit.json", fit.dump(2));
  const json report = synthesize_then_fit(folder, folder / "fit.json", slicer ? "after.mrk.json" : "markers.csv",
                                          slicer ? "/experiments/0/data/after" : "/experiments/0/data", 7,
                                          {"/parameters/0/start=0.24"});
  ASSERT_TRUE(report.is_object());
  const json& c_d = parameter(report, "C_D");
  const double v = c_d["value"].get<double>(), se = c_d["standard_error"].get<double>();
  EXPECT_LT(std::abs(v - 0.4), 0.01) << c_d.dump();
  EXPECT_LT(std::abs(v - 0.4), 2.0 * se) << c_d.dump();
  EXPECT_EQ(report["experiments"][0]["data_count"], 108);
}

INSTANTIATE_TEST_SUITE_P(Fit, FitMarkers, ::testing::Bool(),
                         [](const auto& test) { return test.param ? "FromSlicerPointLists" : "FromACsvFile"; });

// Every problem of a fit file and its data in one message, each naming the file and line; nothing runs.
TEST(Fit, BadInputIsReportedBeforeAnyRun) {
  const fs::path folder = scratch_dir("fit-bad");
  write_text(folder / "cube.json", compression_cube().dump(2));
  write_text(folder / "bad.csv", "displacement_m,force_N\n-0.001,0.02\n-0.002,nan\n-0.0025,abc\n");
  write_text(folder / "no_force.csv", "displacement_m,load_N\n-0.001,0.02\n");
  json fit = compression_fit("bad.csv");
  fit["parameters"][0]["lower"] = 6000;  // above upper
  fit["parameters"][1]["start"] = -7;    // below lower
  fit["experiments"].push_back(fit["experiments"][0]);
  fit["experiments"][1]["name"] = "second";
  fit["experiments"][1]["data"] = "no_force.csv";
  fit["experiments"][1]["sigma"] = -1;
  write_text(folder / "fit.json", fit.dump(2));
  const auto result = run_mtled({"fit", (folder / "fit.json").string(), "-o", (folder / "out").string()});
  EXPECT_EQ(result.exit_code, 2) << result.output;
  expect_contains(result.output, "fit.json:");  // located by line
  expect_contains(result.output, "/parameters/0/upper");
  expect_contains(result.output, "the bounds are inverted");
  expect_contains(result.output, "/parameters/1/start");
  expect_contains(result.output, "outside the bounds");
  expect_contains(result.output, "bad.csv:3");
  expect_contains(result.output, "\"nan\": a finite number");
  expect_contains(result.output, "bad.csv:4");
  expect_contains(result.output, "no_force.csv:1");
  expect_contains(result.output, "no column \"force_N\"");
  expect_contains(result.output, "/experiments/1/sigma");
  EXPECT_FALSE(fs::exists(folder / "out" / "runs"));

  // With the file itself right: a pointer that names nothing, a measured point outside the run's range.
  write_text(folder / "late.csv", "displacement_m,force_N\n-0.001,0.02\n-0.005,0.05\n");
  fit = compression_fit("late.csv");
  fit["parameters"][1]["pointer"] = "/materials/0/beta";
  write_text(folder / "fit2.json", fit.dump(2));
  const auto second = run_mtled({"fit", (folder / "fit2.json").string(), "-o", (folder / "out2").string()});
  EXPECT_EQ(second.exit_code, 2) << second.output;
  expect_contains(second.output, "/materials/0/beta names nothing");
  fit["parameters"][1]["pointer"] = "/materials/0/alpha";
  write_text(folder / "fit3.json", fit.dump(2));
  const auto third = run_mtled({"fit", (folder / "fit3.json").string(), "-o", (folder / "out3").string()});
  EXPECT_EQ(third.exit_code, 2) << third.output;
  expect_contains(third.output, "late.csv:3");
  expect_contains(third.output, "outside the run's range");
  EXPECT_FALSE(fs::exists(folder / "out3" / "runs"));

  // Markers outside the body are named by their line.
  write_text(folder / "markers.csv",
             "label,x_m,y_m,z_m,ux_m,uy_m,uz_m\ninside,0.005,0.005,0.005,0,0,0\n"
             "outside,0.005,0.005,0.012,0,0,0\n");
  fit["experiments"][0] = {
      {"name", "beads"}, {"scene", "cube.json"}, {"data", "markers.csv"}, {"compare", "markers"}, {"sigma", 1e-4}};
  write_text(folder / "fit4.json", fit.dump(2));
  const auto fourth = run_mtled({"fit", (folder / "fit4.json").string(), "-o", (folder / "out4").string()});
  EXPECT_EQ(fourth.exit_code, 2) << fourth.output;
  expect_contains(fourth.output, "markers.csv:3");
  expect_contains(fourth.output, "marker \"outside\"");
  EXPECT_EQ(fourth.output.find("\"inside\""), std::string::npos) << fourth.output;
}

// Levenberg-Marquardt from two start points searched at the same time, and BOBYQA from one: the same optimum.
TEST(Fit, BobyqaFindsTheOptimumLevenbergMarquardtFindsFromTwoStarts) {
  const fs::path folder = scratch_dir("fit-bobyqa");
  write_text(folder / "cube.json", compression_cube().dump(2));
  write_compression_template(folder / "compression.csv");
  json fit = compression_fit("compression.csv");
  fit["method"]["starts"] = {{1000.0, -0.8}};
  write_text(folder / "fit.json", fit.dump(2));
  const json lm = synthesize_then_fit(folder / "lm", folder / "fit.json", "compression.csv", "/experiments/0/data", 1,
                                      {"/parameters/0/start=433.2", "/parameters/1/start=-1.82"});
  fit["method"] = {{"type", "bobyqa"}, {"max_evaluations", 60}, {"tolerance", 1e-3}};
  write_text(folder / "fit.json", fit.dump(2));
  const json bobyqa =
      synthesize_then_fit(folder / "bobyqa", folder / "fit.json", "compression.csv", "/experiments/0/data", 1,
                          {"/parameters/0/start=433.2", "/parameters/1/start=-1.82"});
  ASSERT_TRUE(lm.is_object() && bobyqa.is_object());
  EXPECT_EQ(bobyqa["method"], "bobyqa");
  // The same data (seed 1): BOBYQA, stopped at a relative change of 1e-3, ends inside the 1-sigma region of
  // Levenberg-Marquardt's optimum (chi^2 within 1 of it, each parameter within one standard error), which is as
  // close as the data tell two points apart.
  for (const char* name : {"mu", "alpha"})
    EXPECT_LT(std::abs(parameter(bobyqa, name)["value"].get<double>() - parameter(lm, name)["value"].get<double>()),
              parameter(lm, name)["standard_error"].get<double>())
        << name << "\n"
        << bobyqa.dump(2);
  EXPECT_LT(bobyqa["objective"].get<double>(), lm["objective"].get<double>() + 1.0);
  EXPECT_GT(bobyqa["objective"].get<double>(), lm["objective"].get<double>() - 0.05);  // LM's is the minimum
  std::set<std::string> starts;
  for (const auto& row : read_csv(folder / "lm" / "fit" / "fit.csv")) starts.insert(row[1]);
  EXPECT_TRUE(starts.count("0") && starts.count("1")) << "both start points searched";
}

// A forward run that goes unstable is recorded with its status and has no objective; the others are measured.
TEST(Fit, AnUnstableForwardRunIsABadPointNotTheEnd) {
  const fs::path folder = scratch_dir("fit-unstable");
  json fit = compression_fit("compression.csv");
  fit["parameters"][1] = {{"name", "time_step_factor"},
                          {"pointer", "/integrator/time_step_factor"},
                          {"lower", 0.5},
                          {"upper", 8},
                          {"start", 1}};
  fit["experiments"][0]["set"] = {{"/monitors/stable_step", "stop"}, {"/integrator/time_step_factor", 1.0}};
  fit["experiments"][0].erase("sigma_relative");
  fit["experiments"][0]["sigma"] = 5e-4;
  const fit::Plan plan = compression_plan(folder, fit);
  BasisCache bases;
  fit::Evaluator evaluator(plan, folder / "out", {plugin_dir()}, "warn", in_process(bases));
  const auto evaluations = evaluator.evaluate({{722, 1.0}, {722, 8.0}}, 0, "start");
  ASSERT_EQ(evaluations.size(), 2u);
  EXPECT_EQ(evaluations[0].status, "ok") << evaluations[0].message;
  EXPECT_TRUE(std::isfinite(evaluations[0].objective));
  EXPECT_EQ(evaluations[1].status, "unstable") << evaluations[1].message;
  EXPECT_TRUE(std::isnan(evaluations[1].objective));
  expect_contains(evaluations[1].message, "compression");
  EXPECT_EQ(evaluator.history().size(), 2u);
}

// Forward runs in the fit's process share each mesh's meshless basis (one built for the experiment, by its first run)
// and predict what child `mtled run`s predict, to the last bit: the basis is the same computation, done once.
TEST(Fit, InProcessRunsShareTheBasisAndPredictAsChildRunsDo) {
  const fs::path folder = scratch_dir("fit-in-process");
  json file = compression_fit("compression.csv");
  file["threads"] = 1;
  const fit::Plan plan = compression_plan(folder, file);
  const std::vector<std::vector<double>> points = {{722, -1.3}, {900, -1.0}, {500, -2.0}};
  fit::Evaluator children(plan, folder / "children", {plugin_dir()}, "warn", {}, MTLED_EXECUTABLE);
  const auto child = children.evaluate(points, 0, "start");
  BasisCache bases;
  fit::Evaluator here(plan, folder / "here", {plugin_dir()}, "debug", in_process(bases));
  const auto first = here.evaluate({points[0]}, 0, "start");  // builds the basis
  const auto rest = here.evaluate({points[1], points[2]}, 0, "jacobian");
  EXPECT_EQ(bases.size(), 1u);
  ASSERT_EQ(first.size() + rest.size(), child.size());
  for (std::size_t p = 0; p < child.size(); ++p) {
    const fit::Evaluation& e = p == 0 ? first[0] : rest[p - 1];
    ASSERT_EQ(e.status, "ok") << e.message;
    ASSERT_EQ(child[p].status, "ok") << child[p].message;
    EXPECT_EQ(e.model, child[p].model) << "point " << p;
    const std::string log = read_text(e.folder / "compression" / "mtled.log");
    EXPECT_EQ(log.find("the basis built for an earlier run") != std::string::npos, p > 0) << log;
    expect_contains(log, "done:");  // the run's messages in its own folder, as a child's
  }
}

// A mesh refined along the needle's planned path is shared by the runs whose needle plans that path (a fit of C_D or
// the puncture strain builds one basis) and built again for a needle going elsewhere (a fit of the depth); a mesh
// that does not refine along the needle is shared whatever the needle does.
TEST(Fit, AMeshRefinedAlongTheNeedleIsSharedWhileThePathStays) {
  const json needle = {{"type", "kinematic"},
                       {"entry", {0.001, 0.0, 0.01}},
                       {"direction", {0, 0, -1}},
                       {"depth", 0.006},
                       {"deformation_coefficient", 0.5}};
  const auto basis_of = [](json scene, BasisCache& bases) {
    Simulation simulation(validate_scene(parse_scene(scene.dump(), "refined.json"), catalog()), catalog(), &bases);
    return simulation.system().discretisation().basis();
  };
  for (const bool along : {true, false}) {
    json scene = gel_cylinder_scene(0.01, needle);
    if (along) {
      scene["mesh"]["refine_along_needle"] = true;
      scene["mesh"]["refine_size"] = 0.0007;
    }
    json other_coefficient = scene, other_depth = scene;
    other_coefficient["needle"]["deformation_coefficient"] = 0.3;
    other_depth["needle"]["depth"] = 0.004;
    BasisCache bases;
    const auto first = basis_of(scene, bases);
    EXPECT_EQ(basis_of(other_coefficient, bases), first) << "along the needle: " << along;
    EXPECT_EQ(basis_of(other_depth, bases) == first, !along) << "along the needle: " << along;
    EXPECT_EQ(bases.size(), along ? 2u : 1u);
  }
}

// A fit writes each experiment's mesh once, except where a fitted parameter may change it: one under /mesh, or one
// under /needle when the mesh is refined along the needle's path (the runs then mesh along their own needle).
TEST(Fit, AMeshRefinedAlongAFittedNeedleIsNotWrittenOnce) {
  const fs::path folder = scratch_dir("fit-mesh-along-needle");
  const json needle = {{"type", "kinematic"},
                       {"entry", {0.001, 0.0, 0.01}},
                       {"direction", {0, 0, -1}},
                       {"depth", 0.006},
                       {"deformation_coefficient", 0.4}};
  json along = gel_cylinder_scene(0.01, needle);
  along["mesh"]["refine_along_needle"] = true;
  along["mesh"]["refine_size"] = 0.0007;
  write_text(folder / "along.json", along.dump(2));
  write_text(folder / "plain.json", gel_cylinder_scene(0.01, needle).dump(2));
  write_text(folder / "force.csv", "depth_m,force_N\n0.003,0.01\n0.006,0.02\n");
  json file = {{"parameters",
                {{{"name", "C_D"},
                  {"pointer", "/needle/deformation_coefficient"},
                  {"lower", 0.05},
                  {"upper", 0.9},
                  {"start", 0.4}}}},
               {"experiments", json::array()}};
  for (const std::string name : {"along", "plain"})
    file["experiments"].push_back({{"name", name},
                                   {"scene", name + ".json"},
                                   {"data", "force.csv"},
                                   {"compare", "needle_force"},
                                   {"sigma", 1e-3}});
  write_text(folder / "fit.json", file.dump(2));
  fit::Plan plan = fit::read(folder / "fit.json", {}, {plugin_dir()});
  fit::write_meshes_once(plan, folder / "out", {plugin_dir()});
  EXPECT_TRUE(plan.experiments[0].mesh_file.empty()) << plan.experiments[0].mesh_file;
  EXPECT_TRUE(fs::exists(plan.experiments[1].mesh_file)) << plan.experiments[1].mesh_file;
}

// A forward run in the fit's process still going after timeout_s is stopped and recorded as "timeout", as a child
// run's is; the fit goes on.
TEST(Fit, AnInProcessRunPastTheTimeoutIsStoppedAndRecorded) {
  const fs::path folder = scratch_dir("fit-timeout");
  json file = compression_fit("compression.csv");
  file["timeout_s"] = 0.05;  // the cube's run takes about a second
  const fit::Plan plan = compression_plan(folder, file);
  BasisCache bases;
  fit::Evaluator evaluator(plan, folder / "out", {plugin_dir()}, "warn", in_process(bases));
  const auto evaluations = evaluator.evaluate({{722, -1.3}}, 0, "start");
  ASSERT_EQ(evaluations.size(), 1u);
  EXPECT_EQ(evaluations[0].status, "timeout") << evaluations[0].message;
  EXPECT_TRUE(std::isnan(evaluations[0].objective));
  EXPECT_EQ(read_json(evaluations[0].folder / "compression" / "summary.json")["status"], "timeout");
}

// A launcher (srun in a batch job, mpirun for ranks) goes before each forward run, and what the fit measures is the
// same: each prediction within 1e-9 of the plain run's (the threads, or the ranks, only reorder sums). A launcher
// that names no program is refused when the fit file is read.
TEST(Fit, ALauncherGoesBeforeEachForwardRunAndChangesNoPrediction) {
  const fs::path folder = scratch_dir("fit-launcher");
  write_text(folder / "cube.json", compression_cube().dump(2));
  write_compression_template(folder / "compression.csv");
  json fit = compression_fit("compression.csv");
  fit["threads"] = 1;
  const std::vector<std::vector<double>> points = {{722, -1.3}, {900, -1.0}};
  const auto evaluate = [&](const std::string& name, const json& launcher) {
    json file = fit;
    if (!launcher.is_null()) file["launcher"] = launcher;
    write_text(folder / (name + ".json"), file.dump(2));
    const fit::Plan plan = fit::read(folder / (name + ".json"), {}, {plugin_dir()});
    fit::Evaluator evaluator(plan, folder / name, {plugin_dir()}, "warn", {}, MTLED_EXECUTABLE);
    return evaluator.evaluate(points, 0, "start");
  };
  const auto expect_same = [&](const std::vector<fit::Evaluation>& a, const std::vector<fit::Evaluation>& b) {
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t p = 0; p < a.size(); ++p) {
      ASSERT_EQ(b[p].status, "ok") << b[p].message;
      ASSERT_EQ(a[p].model[0].size(), b[p].model[0].size());
      for (std::size_t k = 0; k < a[p].model[0].size(); ++k)
        EXPECT_NEAR(b[p].model[0][k], a[p].model[0][k], 1e-9 * std::abs(a[p].model[0][k])) << "point " << p;
    }
  };
  const auto plain = evaluate("plain", nullptr);
  const fs::path launched_log = folder / "launched.txt";
  const auto wrapped = evaluate("wrapped", {"sh", "-c", "echo launched >> \"$0\"; exec \"$@\"", launched_log.string()});
  expect_same(plain, wrapped);
  EXPECT_EQ(read_csv(launched_log).size(), points.size());  // one line per forward run

  if (std::system("command -v mpirun > /dev/null 2>&1") == 0 && fs::exists(plugin_dir() / "mtled-backend-mpi.so")) {
    const auto ranks = evaluate("ranks", {"mpirun", "--allow-run-as-root", "--oversubscribe", "-np", "2"});
    expect_same(plain, ranks);
    EXPECT_EQ(read_json(folder / "ranks" / "runs" / "0000" / "compression" / "summary.json")["backend"]["ranks"], 2);
  }

  fit["launcher"] = {"no-such-launcher-program", "-n", "1"};
  write_text(folder / "bad.json", fit.dump(2));
  try {
    fit::read(folder / "bad.json", {}, {plugin_dir()});
    FAIL() << "a launcher naming no program was accepted";
  } catch (const InputError& e) {
    expect_contains(e.what(), "/launcher/0");
    expect_contains(e.what(), "no-such-launcher-program");
  }
}

// The shipped fit files (docs/calibration.md's worked examples) read and check, scenes and data included.
TEST(Fit, TheShippedFitFilesAreReadyToRun) {
  int files = 0;
  for (const auto& entry : fs::directory_iterator(source_dir() / "share/fits")) {
    if (entry.path().extension() != ".json") continue;
    ++files;
    const auto result = run_mtled({"fit", entry.path().string(), "-o", scratch_dir("fit-check").string(), "--check"});
    EXPECT_EQ(result.exit_code, 0) << entry.path() << "\n" << result.output;
  }
  EXPECT_GE(files, 5);
}

}  // namespace
}  // namespace mtled::test
