// `central_difference`: explicit dynamics with the meshless stable time step (Joldes, Wittek, Miller 2012)
// and optional mass-proportional damping, for transient problems.
#include <fmt/format.h>

#include <cmath>

#include "explicit_update.hpp"
#include "load_curve.hpp"
#include "mtled/plugin.hpp"

namespace mtled {

class CentralDifferenceIntegrator final : public TimeIntegrator {
 public:
  static void declare(ComponentDeclaration& d) {
    d.summary("Explicit central differences in physical time, with mass-proportional damping and a load curve.");
    d.number("duration").unit("s").positive().doc("simulated time");
    d.number("time_step_factor")
        .unit("1")
        .positive()
        .defaults(0.9)
        .doc("multiplier on the estimated stable time step; above 1 risks instability, which the stability "
             "monitors then report");
    d.number("damping").unit("1/s").non_negative().defaults(0.0).doc(
        "mass-proportional damping coefficient c in M u'' + c M u' + f_int = f_ext");
    d.number("load_time").unit("s").positive().optional().doc(
        "time over which the loads grow from 0 to full; default: the whole duration");
    d.string("load_curve").defaults("smooth").choices({"smooth", "linear"}).doc(
        "shape of the load ramp: smooth (10x^3 - 15x^4 + 6x^5, no jerk at the ends) or linear");
    d.example({{"duration", 0.01}});
  }

  explicit CentralDifferenceIntegrator(const Parameters& p)
      : duration_(p.number("duration")),
        factor_(p.number("time_step_factor")),
        damping_(p.number("damping")),
        load_time_(p.optional_number("load_time").value_or(duration_)),
        curve_(load_curve_from_string(p.string("load_curve"))) {}

  void initialise(DiscreteSystem& system) override {
    stable_ = system.stable_time_step();
    planned_steps_ = static_cast<long>(std::ceil(duration_ / (factor_ * stable_)));
    h_ = duration_ / static_cast<double>(planned_steps_);  // lands exactly on the duration
    // Central differences of M u'' + c M u' = r with u' = (u+ - u-) / 2h: (1 + ch/2) u+ = 2u - (1 - ch/2) u- + h^2 M^-1 r.
    beta_ = (2.0 - damping_ * h_) / (2.0 + damping_ * h_);
    alpha_ = 2.0 * h_ * h_ / (2.0 + damping_ * h_);
    const std::size_t dofs = system.displacement().size();
    f_int_.assign(dofs, 0.0);
    f_ext_.assign(dofs, 0.0);
    u_next_.assign(dofs, 0.0);
  }

  void step(DiscreteSystem& system) override {
    system.internal_forces(system.displacement(), f_int_);
    if (system.has_external_forces()) system.external_forces(f_ext_);
    explicit_update(system.displacement(), system.previous_displacement(), f_ext_, f_int_, system.mass(), alpha_, beta_,
                    u_next_);
    const double t = static_cast<double>(system.step() + 1) * h_;
    system.complete_step(u_next_, t, load_fraction(curve_, t / load_time_), alpha_);
  }

  bool finished(const DiscreteSystem& system) const override { return system.step() >= planned_steps_; }

  IntegratorReport report() const override {
    IntegratorReport r;
    r.type = "central_difference";
    r.time_step = h_;
    r.stable_time_step = stable_;
    r.time_step_factor = factor_;
    r.settings = {{"planned_steps", planned_steps_}, {"damping_per_s", damping_}};
    return r;
  }

 private:
  double duration_, factor_, damping_, load_time_;
  LoadCurve curve_;
  double stable_ = 0.0, h_ = 0.0, alpha_ = 0.0, beta_ = 1.0;
  long planned_steps_ = 0;
  std::vector<double> f_int_, f_ext_, u_next_;
};

}  // namespace mtled

MTLED_PLUGIN(mtled::TimeIntegrator, mtled::CentralDifferenceIntegrator)
