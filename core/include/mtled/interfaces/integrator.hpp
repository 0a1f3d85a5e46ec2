#pragma once
#include <nlohmann/json.hpp>

#include "mtled/parameters.hpp"

namespace mtled {

class Simulation;

// Advances the state in time. The kernel's loop calls initialise once, then step until finished, running
// its stability monitors and recorders between steps.
class TimeIntegrator {
 public:
  static constexpr Category category = Category::integrator;
  virtual ~TimeIntegrator();

  virtual void initialise(Simulation& simulation) = 0;
  virtual void step(Simulation& simulation) = 0;
  virtual bool finished(const Simulation& simulation) const = 0;
  // Error indicators and settings for summary.json ("integrator" object).
  virtual nlohmann::json report() const = 0;
};

}  // namespace mtled
