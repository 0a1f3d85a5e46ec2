#pragma once
// The kernel's own StepEngine: the state in host memory, the work on the model's thread team (the force kernel,
// and the per-node passes of the update and the step's sums). Scenes without a "backend" block run on it; the
// "cpu" backend plugin names it.
#include <memory>

#include "mtled/interfaces/backend.hpp"

namespace mtled {

std::unique_ptr<StepEngine> make_cpu_engine();

}  // namespace mtled
