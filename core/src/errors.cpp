#include "mtled/errors.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <numeric>

namespace mtled {

std::string Problem::format() const { return where.empty() ? message : where + ": " + message; }

namespace {
std::string join_problems(const std::vector<Problem>& problems) {
  std::string text;
  for (const auto& p : problems) {
    if (!text.empty()) text += '\n';
    text += p.format();
  }
  return text;
}

std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  std::iota(row.begin(), row.end(), 0);
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t above = row[j];
      const std::size_t substitution = diagonal + (a[i - 1] == b[j - 1] ? 0 : 1);
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, substitution});
      diagonal = above;
    }
  }
  return row[b.size()];
}
}  // namespace

InputError::InputError(std::vector<Problem> problems)
    : std::runtime_error(join_problems(problems)), problems_(std::move(problems)) {}
InputError::InputError(std::string where, std::string message)
    : InputError(std::vector<Problem>{Problem{std::move(where), std::move(message)}}) {}
InputError::~InputError() = default;

InstabilityError::InstabilityError(Diagnostic diagnostic)
    : std::runtime_error(fmt::format("numerical instability at step {} (t = {:.6g} s): {}: {}", diagnostic.step,
                                     diagnostic.time, diagnostic.what, diagnostic.detail)),
      diagnostic_(std::move(diagnostic)) {}
InstabilityError::~InstabilityError() = default;

std::vector<std::string> closest_names(const std::string& name, const std::vector<std::string>& candidates,
                                       std::size_t max_results) {
  // A suggestion is worth making when at most a third of the letters (and at least 2) differ, or when one
  // name is a shortened form of the other ("dynamic_relax" for "dynamic_relaxation").
  const std::size_t limit = std::max<std::size_t>(2, name.size() / 3);
  auto abbreviates = [](const std::string& shorter, const std::string& longer) {
    return shorter.size() >= 4 && shorter.size() < longer.size() && longer.compare(0, shorter.size(), shorter) == 0;
  };
  std::vector<std::pair<std::size_t, std::string>> scored;
  for (const auto& candidate : candidates) {
    const std::size_t d = edit_distance(name, candidate);
    if (d <= limit || abbreviates(name, candidate) || abbreviates(candidate, name)) scored.emplace_back(d, candidate);
  }
  std::stable_sort(scored.begin(), scored.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
  std::vector<std::string> result;
  for (const auto& s : scored) {
    if (result.size() == max_results) break;
    result.push_back(s.second);
  }
  return result;
}

std::string did_you_mean(const std::string& name, const std::vector<std::string>& candidates) {
  const auto close = closest_names(name, candidates);
  if (close.empty()) return "";
  std::string text = "did you mean ";
  for (std::size_t i = 0; i < close.size(); ++i) {
    if (i > 0) text += (i + 1 == close.size()) ? " or " : ", ";
    text += '"' + close[i] + '"';
  }
  return text + "?";
}

}  // namespace mtled
