#pragma once
// Diagnostics located at one node, as the kernel's checks and the monitors raise them.
#include <fmt/format.h>

#include <string>

#include "mtled/discretisation.hpp"
#include "mtled/errors.hpp"

namespace mtled {

inline std::string point_text(const Vec3& x) { return fmt::format("({:.6g}, {:.6g}, {:.6g})", x[0], x[1], x[2]); }

// An instability located at one node of `model`.
inline InstabilityError node_instability(long step, double time, std::string what, std::string detail,
                                         const Discretisation& model, Index node) {
  Diagnostic d;
  d.step = step;
  d.time = time;
  d.what = std::move(what);
  d.detail = std::move(detail);
  d.nodes = {node};
  d.coordinates = {model.nodes()[node]};
  return InstabilityError(std::move(d));
}

}  // namespace mtled
