#pragma once
// /monitors/inversion_every_steps: the background tets moved by the interpolated displacements at their
// vertices, every that many steps and after the last one. A tet whose moved volume is not positive is looked at
// closer, as the integration points' J cannot show a fold between them:
// - in the needle's zone (a vertex within the needle's radius plus its support radius of the swept shaft) it is cut:
//   the kinematic needle cannot cut the tissue, so the tets around its path fold ("cut_tets" in summary.json);
// - otherwise the displacement field itself is read inside the tet (its centroid and the degree-2 rule's four
//   points): J <= 0 at one of them is a fold of the material between integration points (a driver pushed nodes
//   through it); J > 0 at all of them means the field turns within the tet further than its four corners can follow
//   (a rolled rim, a sliver in a relaxation's transient, whose corners turn over as soon as the field departs from
//   an affine one by its thickness), counted as bent, not as a fold. A fold of the material turns the field inside
//   out; the tet's straight edges may turn over without one.
// /monitors/inversion says what a fold does: "stop" (the default) ends the run (InstabilityError
// "inverted_between_points"), "warn" logs it once and records it in summary.json.
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "mtled/monitor.hpp"
#include "mtled/monitors/scene_monitors.hpp"
#include "mtled/parameters.hpp"

namespace mtled {

// What the message of a fold may advise, from what the scene already does: never a lever it already uses.
struct FoldAdvice {
  bool needle_drives_nodes = false;  // the kinematic needle drives nodes, not material points on the shaft's surface
  bool refined_along = false;        // the mesh source refines the cloud along a segment (refine_from)
  bool refined_to_size = false;      // ... to an absolute size (refine_size) rather than a ratio
  bool drag_limited = false;   // the kinematic needle's drag is limited (/needle/drag_limit)
};

// A fold this close to the needle's axis (m) is the needle's drag's doing; farther out, a driver's.
constexpr double kBesideTheNeedle = 0.02;

// What the scene may do about a fold (a tet turned over, or J <= 0 at an integration point): `needle` the needle's
// state, if one is in (null otherwise); `radial` the fold's distance from its axis; `boundary` the constraint set (not
// the needle's) that holds a vertex of the folded tet, if any.
std::string fold_lever(const FoldAdvice& advice, const NeedleStatus* needle, double radial,
                       const NodalConstraints* boundary);
// What the scene already does, so that a fold's message never advises it.
FoldAdvice fold_advice(const Scene& scene);

class InversionMonitor final : public StepMonitor {
 public:
  // Its parameters in the scene's "monitors" section, read into Settings.
  static void declare(ComponentDeclaration& d);
  struct Settings {
    long inversion_every_steps = 0;
    std::string inversion;
  };
  // The monitor the section asks for; null when inversion_every_steps is 0. When it stops a run it marks the folded
  // tets in `folded`.
  static std::unique_ptr<InversionMonitor> from_section(const Parameters& monitors, FoldAdvice advice,
                                                        std::shared_ptr<FoldedTets> folded);
  InversionMonitor(long every, bool stop, FoldAdvice advice = {}, std::shared_ptr<FoldedTets> folded = nullptr)
      : every_(every), stop_(stop), advice_(advice), folded_(std::move(folded)) {}
  std::string name() const override { return "inversion"; }
  void before_run(const RunContext& run, const StepRecord&) override { run_ = &run; }
  void after_step(const StepRecord& step) override {
    if (reads_displacement(step.load.step)) check(step);
  }
  bool reads_displacement(long step) const override { return step % every_ == 0; }
  void after_run(const StepRecord& last) override {
    if (last_checked_ != last.load.step) check(last);
  }
  json report() const override;

 private:
  void check(const StepRecord& step);
  // One check's findings over the tets turned over by their vertices (the smallest volume ratio over all but cut
  // tets; `worst` the folded tet with the smallest J inside, `worst_ratio` its moved volume ratio).
  struct Census {
    double smallest = INFINITY, folded_jacobian = INFINITY, bent_jacobian = INFINITY, worst_ratio = 0.0;
    Index worst = 0;
    long folded = 0, bent = 0, cut = 0;
  };
  // Moves the tets by the interpolated displacements of state `step` and sorts those turned over (kinds_).
  Census classify(const StepRecord& step);
  Vec3 moved(Index node) const;  // where node went, by the last interpolated displacements
  // The stop: where the fold is against the needle, how far it went, and the lever that applies.
  [[noreturn]] void stop(const StepRecord& step, const Census& census, Index node, Vec3 moved_by) const;
  // What a tet turned over by its vertices' displacements is, at the last check (whole: not turned over).
  enum class TetState : char { whole, cut, bent, folded };

  const RunContext* run_ = nullptr;
  long every_;
  bool stop_;
  FoldAdvice advice_;
  std::shared_ptr<FoldedTets> folded_;  // filled when the check stops a run (last_good_state.vtu's "folded")
  long checks_ = 0, last_checked_ = -1, inverted_tets_ = 0, first_inverted_at_ = 0;
  long cut_tets_ = 0;                 // the most inverted tets the needle's shaft crossed at any check
  long bent_tets_ = 0;                // the most tets turned over with the field whole inside them, at any check
  double smallest_bent_jacobian_ = INFINITY;  // the field's smallest J inside those, over the run
  std::vector<TetState> kinds_;               // per tet, at the last check
  double smallest_ratio_ = INFINITY;  // the smallest moved volume over reference volume of any tet
  long smallest_at_ = 0;
  std::vector<double> interpolated_;
  Index first_node_ = 0;        // the farthest-moved vertex of the worst tet, at the first check that found one
  Vec3 first_position_ = Vec3::Zero();
};

}  // namespace mtled
