// `cpu`: the kernel's own step engine (mtled/cpu_engine.hpp), named in a scene ("backend": {"type": "cpu"}) or on
// the command line (--backend cpu). A scene without a "backend" block runs on the same engine without loading this
// library.
#include "mtled/cpu_engine.hpp"
#include "mtled/plugin.hpp"

namespace mtled {

class CpuBackend final : public CpuEngine {
 public:
  static void declare(ComponentDeclaration& d) {
    d.summary(
        "The CPU: the force kernel and the per-node passes of each step on the run's threads (--threads), the "
        "state in host memory. The default when a scene names no backend.");
  }
  explicit CpuBackend(const Parameters&) {}
};

}  // namespace mtled

MTLED_PLUGIN(mtled::StepEngine, mtled::CpuBackend)
