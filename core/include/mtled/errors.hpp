#pragma once
#include <stdexcept>
#include <string>
#include <vector>

#include "mtled/types.hpp"

namespace mtled {

// One thing wrong with the user's input. `where` is a JSON pointer into the scene ("/materials/0/mu") or a
// file location ("mesh.msh:120"); the scene loader adds "scene.json:LINE" in front of pointers it can place.
struct Problem {
  std::string where;
  std::string message;
  std::string format() const;
};

// Invalid input: arguments, scene, mesh, plugin. The command line exits with code 2.
class InputError : public std::runtime_error {
 public:
  explicit InputError(std::vector<Problem> problems);
  InputError(std::string where, std::string message);
  ~InputError() override;
  const std::vector<Problem>& problems() const { return problems_; }

 private:
  std::vector<Problem> problems_;
};

// Where and how a run went numerically wrong. Written into summary.json as "diagnostic".
struct Diagnostic {
  long step = 0;
  double time = 0.0;
  std::string what;    // short code: "non_finite", "inverted_material", "energy_growth", ...
  std::string detail;  // one sentence for people
  std::vector<Index> nodes;
  std::vector<Index> integration_points;
  std::vector<Vec3> coordinates;  // reference coordinates of the entities above, in the same order
};

// A numerical instability detected while running. The command line exits with code 3.
class InstabilityError : public std::runtime_error {
 public:
  explicit InstabilityError(Diagnostic diagnostic);
  ~InstabilityError() override;
  const Diagnostic& diagnostic() const { return diagnostic_; }

 private:
  Diagnostic diagnostic_;
};

// Names within `max_distance` edits of `name`, closest first (for "did you mean" suggestions).
std::vector<std::string> closest_names(const std::string& name, const std::vector<std::string>& candidates,
                                       std::size_t max_results = 3);

// "did you mean "a" or "b"?" or "" when nothing is close.
std::string did_you_mean(const std::string& name, const std::vector<std::string>& candidates);

}  // namespace mtled
