// `cpu`: the kernel's own step engine, named in a scene ("backend": {"type": "cpu"}) or on the command line
// (--backend cpu). A scene without a "backend" block runs on the same engine without loading this library.
#include "mtled/cpu_engine.hpp"
#include "mtled/plugin.hpp"

namespace mtled {

class CpuBackend final : public StepEngine {
 public:
  static void declare(ComponentDeclaration& d) {
    d.summary(
        "The CPU: the force kernel and the per-node passes of each step on the run's threads (--threads), the "
        "state in host memory. The default when a scene names no backend.");
  }
  explicit CpuBackend(const Parameters&) : engine_(make_cpu_engine()) {}

  void setup(const Model& model) override { engine_->setup(model); }
  json describe() const override { return engine_->describe(); }
  void set_mass(std::span<const double> mass) override { engine_->set_mass(mass); }
  void set_state(std::span<const double> u, std::span<const double> u_previous) override {
    engine_->set_state(u, u_previous);
  }
  std::span<const double> displacement() override { return engine_->displacement(); }
  std::span<const double> previous_displacement() override { return engine_->previous_displacement(); }
  Index evaluate_forces(IncrementSums* sums) override { return engine_->evaluate_forces(sums); }
  std::int64_t predict(double alpha, double beta, std::span<const double> f_ext) override {
    return engine_->predict(alpha, beta, f_ext);
  }
  void set_prediction(std::span<const double> u) override { engine_->set_prediction(u); }
  void prediction(std::span<double> out) override { engine_->prediction(out); }
  void constrained_values(const ConstraintBlock& block, std::vector<double>& out) override {
    engine_->constrained_values(block, out);
  }
  void add_correction(const ConstraintBlock& block, const std::vector<double>& y) override {
    engine_->add_correction(block, y);
  }
  StepSums commit() override { return engine_->commit(); }
  Index internal_forces(std::span<const double> u, std::span<double> f) override {
    return engine_->internal_forces(u, f);
  }

 private:
  std::unique_ptr<StepEngine> engine_;
};

}  // namespace mtled

MTLED_PLUGIN(mtled::StepEngine, mtled::CpuBackend)
