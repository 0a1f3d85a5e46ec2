// A fit's report: the parameters' standard errors from the Jacobian at the optimum, C = s^2 (J^T J)^-1 with J the
// derivatives of the weighted residuals (model - datum) / sigma (s^2 = 1 when the data's standard deviations are
// given, else the residuals' variance SSR / (m - n)); correlations; R^2 per experiment; the parameters the data
// cannot pin down; fit.json, fit.csv (every evaluation), fit_data.csv (measured against fitted) and fit.svg.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iostream>

#include "mtled/analysis/fit.hpp"
#include "mtled/analysis/svg.hpp"
#include "mtled/io/output.hpp"

namespace fs = std::filesystem;

namespace mtled::fit {

namespace {

const Evaluation* best_of(const Result& r) {
  return r.best >= 0 ? &r.evaluations[static_cast<std::size_t>(r.best)] : nullptr;
}

// Parameters whose 2-sigma interval is wider than their bounds, or that are correlated above 0.99 with another, or
// that the data do not depend on at all.
void identifiability(const Plan& plan, const Result& result, Statistics& s) {
  const std::size_t n = plan.parameters.size();
  // Sensitivities per unit of each parameter's range; runs on other thread counts agree to round-off only, so a
  // column that small is no sensitivity at all.
  std::vector<double> sensitivity(n);
  for (std::size_t k = 0; k < n; ++k)
    sensitivity[k] = result.jacobian.col(static_cast<Index>(k)).norm() * plan.parameters[k].slope(result.values[k]);
  const double largest = *std::max_element(sensitivity.begin(), sensitivity.end());
  for (std::size_t k = 0; k < n; ++k) {
    const Parameter& p = plan.parameters[k];
    const double v = result.values[k], se = s.standard_error[static_cast<Index>(k)];
    const double width = p.log_scale ? 4.0 * se / (v * std::log(10.0)) : 4.0 * se;
    const double range = p.log_scale ? std::log10(p.upper / p.lower) : p.upper - p.lower;
    if (sensitivity[k] <= 1e-7 * largest)
      s.not_identifiable.push_back(
          fmt::format("{}: the data do not change with it (no sensitivity beyond round-off)", p.name));
    else if (!std::isfinite(se) || width > range)
      s.not_identifiable.push_back(
          fmt::format("{}: its 2-sigma interval ({:.3g} {}) is wider than its bounds ({:.3g}): "
                      "the data cannot identify it; fix it, or add data that depend on it",
                      p.name, width, p.log_scale ? "decades" : "wide", range));
    for (std::size_t j = 0; j < k; ++j) {
      const double c = s.correlation(static_cast<Index>(j), static_cast<Index>(k));
      if (std::abs(c) > 0.99)
        s.not_identifiable.push_back(
            fmt::format("{} and {}: correlated {:.4f}: the data fix a combination of the two, "
                        "not each",
                        plan.parameters[j].name, p.name, c));
    }
  }
}

}  // namespace

Statistics statistics(const Plan& plan, const Result& result) {
  Statistics s;
  const Evaluation* best = best_of(result);
  if (!best || result.jacobian.size() == 0) return s;
  const Index n = static_cast<Index>(plan.parameters.size());
  const Index m = result.jacobian.rows();
  s.chi_square = best->objective;
  s.sigma_estimated =
      std::any_of(plan.experiments.begin(), plan.experiments.end(), [](const Experiment& e) { return !e.sigma_given; });
  s.residual_variance = s.sigma_estimated ? s.chi_square / static_cast<double>(std::max<Index>(m - n, 1)) : 1.0;
  const Eigen::MatrixXd A = result.jacobian.transpose() * result.jacobian;
  // The pseudo-inverse: a direction the data do not see gets an infinite variance, not a division by zero.
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(A);
  const double largest = eigen.eigenvalues().cwiseAbs().maxCoeff();
  Eigen::VectorXd inverse_values(n);
  for (Index k = 0; k < n; ++k) {
    const double l = eigen.eigenvalues()[k];
    inverse_values[k] = l > 1e-14 * largest && l > 0.0 ? 1.0 / l : INFINITY;
  }
  s.covariance = Eigen::MatrixXd::Zero(n, n);
  for (Index l = 0; l < n; ++l)
    if (std::isfinite(inverse_values[l]))
      s.covariance += inverse_values[l] * eigen.eigenvectors().col(l) * eigen.eigenvectors().col(l).transpose();
  s.covariance *= s.residual_variance;
  for (Index l = 0; l < n; ++l)
    for (Index k = 0; k < n && !std::isfinite(inverse_values[l]); ++k)
      if (std::abs(eigen.eigenvectors()(k, l)) > 1e-8) s.covariance(k, k) = INFINITY;
  s.standard_error = s.covariance.diagonal().cwiseSqrt();
  s.correlation = Eigen::MatrixXd::Identity(n, n);
  for (Index i = 0; i < n; ++i)
    for (Index j = 0; j < n; ++j)
      if (i != j) s.correlation(i, j) = s.covariance(i, j) / (s.standard_error[i] * s.standard_error[j]);
  for (std::size_t x = 0; x < plan.experiments.size(); ++x) {
    const auto& data = plan.experiments[x].data;
    double mean = 0.0, total = 0.0, residual = 0.0;
    for (const auto& d : data) mean += d.value / static_cast<double>(data.size());
    for (std::size_t i = 0; i < data.size(); ++i) {
      total += (data[i].value - mean) * (data[i].value - mean);
      residual += std::pow(best->model[x][i] - data[i].value, 2);
    }
    s.r_squared.push_back(total > 0.0 ? 1.0 - residual / total : NAN);
  }
  identifiability(plan, result, s);
  for (std::size_t k = 0; k < plan.parameters.size(); ++k) {
    const double z = plan.parameters[k].scaled(result.values[k]);
    if (z < 1e-9 || z > 1.0 - 1e-9)
      s.warnings.push_back(
          fmt::format("{} ended at its {} bound ({:g}): the optimum may lie beyond it; widen the bound "
                      "if the physics allows",
                      plan.parameters[k].name, z < 0.5 ? "lower" : "upper", result.values[k]));
  }
  const auto failed = std::count_if(result.evaluations.begin(), result.evaluations.end(),
                                    [](const Evaluation& e) { return e.status != "ok"; });
  if (failed > 0)
    s.warnings.push_back(fmt::format("{} of {} evaluations failed (treated as bad points; see fit.csv)", failed,
                                     result.evaluations.size()));
  return s;
}

namespace {

json finite_or_null(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

json matrix_json(const Eigen::MatrixXd& m) {
  json rows = json::array();
  for (Index i = 0; i < m.rows(); ++i) {
    json row = json::array();
    for (Index j = 0; j < m.cols(); ++j) row.push_back(finite_or_null(m(i, j)));
    rows.push_back(row);
  }
  return rows;
}

const char* quantity_name(Quantity q) {
  return q == Quantity::needle_force ? "needle_force" : q == Quantity::reaction_force ? "reaction_force" : "markers";
}

json report_json(const Plan& plan, const Result& result, const Statistics& s) {
  json parameters = json::array();
  for (std::size_t k = 0; k < plan.parameters.size(); ++k) {
    const Parameter& p = plan.parameters[k];
    json entry = {{"name", p.name}, {"start", p.start}, {"lower", p.lower}, {"upper", p.upper}, {"log", p.log_scale}};
    if (!result.values.empty()) {
      const double v = result.values[k];
      const double se = s.standard_error.size() ? s.standard_error[static_cast<Index>(k)] : NAN;
      entry["value"] = v;
      entry["standard_error"] = finite_or_null(se);
      entry["interval_2sigma"] = {finite_or_null(v - 2 * se), finite_or_null(v + 2 * se)};
    }
    parameters.push_back(entry);
  }
  json experiments = json::array();
  for (std::size_t x = 0; x < plan.experiments.size(); ++x) {
    const Experiment& e = plan.experiments[x];
    experiments.push_back({{"name", e.name},
                           {"scene", e.scene.string()},
                           {"data", e.data_file.string()},
                           {"quantity", quantity_name(e.quantity)},
                           {"data_count", e.data.size()},
                           {"sigma_given", e.sigma_given},
                           {"r_squared", x < s.r_squared.size() ? finite_or_null(s.r_squared[x]) : json(nullptr)}});
  }
  const Evaluation* best = best_of(result);
  return {{"description", plan.description},
          {"status", best ? (result.converged ? "converged" : "not_converged") : "failed"},
          {"termination", result.termination},
          {"method", plan.settings.method == Method::bobyqa ? "bobyqa" : "levenberg_marquardt"},
          {"parameters", parameters},
          {"objective", best ? finite_or_null(best->objective) : json(nullptr)},
          {"best_evaluation", result.best},
          {"sigma_estimated", s.sigma_estimated},
          {"residual_variance", s.residual_variance},
          {"covariance", matrix_json(s.covariance)},
          {"correlation", matrix_json(s.correlation)},
          {"experiments", experiments},
          {"not_identifiable", s.not_identifiable},
          {"warnings", s.warnings},
          {"evaluations", result.evaluations.size()},
          {"seconds", result.seconds},
          {"mesh_setup_seconds", result.setup_seconds},
          {"files", {{"evaluations", "fit.csv"}, {"data", "fit_data.csv"}, {"plot", "fit.svg"}, {"runs", "runs"}}}};
}

void write_evaluations(const OutputFolder& out, const Plan& plan, const Result& result) {
  out.write_file("fit.csv", [&](std::ostream& o) {
    o << "evaluation,start,purpose";
    for (const auto& p : plan.parameters) o << "," << p.name;
    o << ",objective,status,wall_s,folder\n";
    for (const auto& e : result.evaluations) {
      o << fmt::format("{},{},{}", e.index, e.start, e.purpose);
      for (double v : e.values) o << fmt::format(",{:.10g}", v);
      o << fmt::format(",{},{},{:.3f},{}\n", std::isfinite(e.objective) ? fmt::format("{:.10g}", e.objective) : "",
                       e.status, e.wall_s, fs::relative(e.folder, out.path()).string());
    }
  });
}

void write_data_and_plot(const OutputFolder& out, const Plan& plan, const Result& result, const Statistics& s) {
  const Evaluation* best = best_of(result);
  if (!best) return;
  std::vector<svg::XyPanel> panels;
  out.write_file("fit_data.csv", [&](std::ostream& o) {
    o << "experiment,label,abscissa,component,measured,fitted,sigma,weighted_residual\n";
    for (std::size_t x = 0; x < plan.experiments.size(); ++x) {
      const Experiment& e = plan.experiments[x];
      svg::XyPanel panel;
      panel.title = fmt::format("{}: R^2 {:.4f}", e.name, s.r_squared[x]);
      for (std::size_t i = 0; i < e.data.size(); ++i) {
        const Datum& d = e.data[i];
        const double fitted = best->model[x][i];
        o << fmt::format("{},{},{:.9g},{},{:.9g},{:.9g},{:.9g},{:.6g}\n", e.name, d.label, d.abscissa,
                         e.quantity == Quantity::markers ? "xyz"[d.component] : 'f', d.value, fitted, d.sigma,
                         best->residuals[x][i]);
        if (e.quantity == Quantity::markers) {  // measured against fitted, in mm
          panel.x_points.push_back(1e3 * d.value);
          panel.y_points.push_back(1e3 * fitted);
        } else {
          panel.x_points.push_back(1e3 * d.abscissa);
          panel.y_points.push_back(d.value);
          panel.x_line.push_back(1e3 * d.abscissa);
          panel.y_line.push_back(fitted);
        }
      }
      if (e.quantity == Quantity::markers) {
        panel.x_label = "measured displacement component (mm)";
        panel.y_label = "fitted (mm)";
        panel.identity_line = true;
      } else {
        panel.x_label = e.quantity == Quantity::needle_force ? "needle depth (mm)"
                                                             : fmt::format("{} displacement (mm)", e.set_name);
        panel.y_label = "force (N): measured o, fitted -";
      }
      panels.push_back(std::move(panel));
    }
  });
  std::string values;
  for (std::size_t k = 0; k < plan.parameters.size(); ++k)
    values += fmt::format("{}{} = {:.4g} +- {:.2g}", k ? ", " : "", plan.parameters[k].name, result.values[k],
                          s.standard_error.size() ? s.standard_error[static_cast<Index>(k)] : NAN);
  out.write_file("fit.svg", [&](std::ostream& o) {
    svg::write_xy_panels(o, panels, "Measured against fitted", values + " (1 sigma)");
  });
}

}  // namespace

void write_report(const Plan& plan, const Result& result, const Statistics& stats, const fs::path& folder) {
  const OutputFolder out(folder);
  write_evaluations(out, plan, result);
  write_data_and_plot(out, plan, result, stats);
  out.write_file("fit.json", [&](std::ostream& o) { o << report_json(plan, result, stats).dump(2) << "\n"; });
}

void print_summary(std::ostream& out, const Plan& plan, const Result& result, const Statistics& s) {
  out << fmt::format("fit: {} ({} evaluations, {:.1f} s)\n", result.termination, result.evaluations.size(),
                     result.seconds);
  if (result.values.empty()) return;
  for (std::size_t k = 0; k < plan.parameters.size(); ++k) {
    const double se = s.standard_error.size() ? s.standard_error[static_cast<Index>(k)] : NAN;
    out << fmt::format("  {:<24} {:>12.6g} +- {:<10.3g} (2 sigma: [{:.6g}, {:.6g}])\n", plan.parameters[k].name,
                       result.values[k], se, result.values[k] - 2 * se, result.values[k] + 2 * se);
  }
  for (std::size_t x = 0; x < plan.experiments.size() && x < s.r_squared.size(); ++x)
    out << fmt::format("  {}: R^2 {:.5f}\n", plan.experiments[x].name, s.r_squared[x]);
  for (const auto& w : s.not_identifiable) out << "  not identifiable: " << w << "\n";
  for (const auto& w : s.warnings) out << "  warning: " << w << "\n";
}

}  // namespace mtled::fit
