// An example of a needle model written outside the mtled source tree (docs/needle-plugins.md): a blunt,
// flat-ended needle that never punctures. The surface nodes under its end (within its radius of the axis)
// are bonded to it and follow the tip; the needle force is what holding them there takes.
//
// It uses mtled's needle helpers (mtled/needle/needle_geometry.hpp, library mtled::needle_geometry): the same
// "diameter", "entry", "direction" and "depth" parameters as the shipped needle models, the same path
// arithmetic, and the same refusal of an entry point off the body.
#include <fmt/format.h>

#include "mtled/discretisation.hpp"
#include "mtled/errors.hpp"
#include "mtled/log.hpp"
#include "mtled/needle/needle_geometry.hpp"
#include "mtled/plugin.hpp"

namespace example {

using namespace mtled;

class FlatPunchNeedle final : public NeedleModel {
 public:
  static void declare(ComponentDeclaration& d) {
    d.summary("A blunt, flat-ended needle that indents the surface and never punctures (example of an "
              "out-of-tree needle model).");
    declare_needle_path(d);  // diameter, entry, direction, depth: as every needle model declares them
    d.example({{"entry", {0.0, 0.0, 0.017}}, {"depth", 0.001}, {"diameter", 0.004}});
  }

  explicit FlatPunchNeedle(const Parameters& p) : parameters_(p), path_(read_needle_path(p)) {
    bonded_.name = "needle";
  }

  void setup(const Discretisation& model) override {
    place_needle_path(path_, model, parameters_);  // an entry off the body is refused, at its pointer
    // The end's footprint: surface nodes within half a node spacing of the entry plane and the radius of
    // the axis.
    const double spacing = spacing_at_entry(path_, model);
    std::vector<Index> footprint;
    for (Index i = 0; i < model.node_count(); ++i) {
      const Vec3& x = model.nodes()[i];
      if (model.cloud().surface[i] && std::abs(path_.axial(x)) <= 0.5 * spacing && path_.radial(x) <= path_.radius)
        footprint.push_back(i);
    }
    if (footprint.size() < 3)
      throw InputError(parameters_.pointer("diameter"),
                       fmt::format("the punch's end covers {} surface nodes (node spacing {:.3g} mm at the entry): "
                                   "make the diameter larger than about two node spacings, or refine the mesh",
                                   footprint.size(), 1e3 * spacing));
    log().info("flat_punch needle: {} surface nodes bonded to the end", footprint.size());
    bonded_.assign_nodes(std::move(footprint), Vec3::Zero());  // all three components: a bonded end
  }

  void update(const LoadState& load, const Discretisation&, std::span<const double>) override {
    depth_ = load.load_fraction * path_.depth;
    for (auto& value : bonded_.values) value = depth_ * path_.direction;
  }

  std::vector<NodalConstraints*> constraints() override { return {&bonded_}; }

  NeedleStatus status() const override {
    NeedleStatus s = path_.status(depth_, std::nullopt);  // the shaft; indentation for ever (no puncture depth)
    for (const Vec3& r : bonded_.reactions) s.force += r.dot(path_.direction);  // reactions on the body, along the axis
    s.driven_nodes = static_cast<Index>(bonded_.size());
    return s;
  }

 private:
  Parameters parameters_;
  NeedlePath path_;
  NodalConstraints bonded_;
  double depth_ = 0.0;
};

}  // namespace example

MTLED_PLUGIN(mtled::NeedleModel, example::FlatPunchNeedle)
