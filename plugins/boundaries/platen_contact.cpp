// `platen_contact`: a rigid plane the body may not pass through (a platen pressing a free face, a table the body is
// pushed onto), given by a point, a normal and a displacement. Surface nodes that reach it are held on it,
// frictionless or sticking, until it has pulled them for `release_steps` steps (plane_contact.hpp). A face bonded to
// a platen takes its node-set boundary's `platen` option instead, which keeps the two on one plane.
#include <fmt/format.h>

#include "mtled/discretisation.hpp"
#include "mtled/log.hpp"
#include "mtled/mesh.hpp"
#include "mtled/node_selector.hpp"
#include "mtled/plugin.hpp"
#include "plane_contact.hpp"

namespace mtled {

class PlatenContact final : public BoundaryCondition {
 public:
  static void declare(ComponentDeclaration& d) {
    d.summary(
        "A rigid plane the body may not pass through: surface nodes that reach it are held on it (frictionless or "
        "sticking) until the plane would have to pull them back.");
    d.vector3("point").unit("m").doc("a point of the plane in the reference configuration").to<&Settings::point>();
    d.vector3("normal")
        .unit("1")
        .doc("the plane's normal, pointing into the body (the side the body stays on); any length")
        .to<&Settings::normal>();
    d.vector3("displacement")
        .unit("m")
        .defaults(json::array({0.0, 0.0, 0.0}))
        .doc("the plane's displacement at full load, growing with the integrator's load curve")
        .to<&Settings::displacement>();
    d.string("tangential")
        .defaults("free")
        .choices({"free", "stick"})
        .doc(
            "free: a node in contact slides on the plane (frictionless; the normal must lie along x, y or z); "
            "stick: it stays where it touched (no slip, any normal)")
        .to<&Settings::tangential>();
    d.integer("release_steps")
        .unit("1")
        .at_least(1)
        .defaults(kPlatenReleaseSteps)
        .doc("a node in contact leaves when the plane has pulled on it for this many consecutive steps")
        .to<&Settings::release_steps>();
    d.node_set("nodes", NodeSelector::syntax())
        .optional()
        .doc("the nodes that may touch the plane; default: every node on the body's surface");
    d.string("name")
        .optional()
        .doc("label of this set in reactions.csv and summary.json; default: \"contact\" and its index")
        .to<&Settings::name>();
    d.example({{"point", {0.0, 0.0, -0.001}}, {"normal", {0.0, 0.0, 1.0}}});
  }

  explicit PlatenContact(const Parameters& p) : PlatenContact(p, p.read<Settings>()) {}

  void setup(const Discretisation& model) override {
    const std::vector<Index> selected =
        selector_ ? select_nodes(*selector_, model.mesh(), model.cloud().surface, parameters_.pointer("nodes"))
                  : surface_node_list(model);
    const std::size_t candidates = contact_.setup(model, selected);
    if (candidates == 0)
      throw InputError(parameters_.pointer(selector_ ? "nodes" : "point"),
                       "no node lies on the side of the plane its normal points to: the normal points into the body, "
                       "so check its sign and the point (in m)");
    log().info("boundary \"{}\": a rigid plane, {} nodes may touch it ({})", contact_.constraints().name, candidates,
               contact_.sticks() ? "sticking" : "frictionless");
  }
  void update(const LoadState& load, const Discretisation& model, std::span<const double> u) override {
    contact_.update(load, model, u);
  }
  std::vector<NodalConstraints*> constraints() override { return {&contact_.constraints()}; }

 private:
  struct Settings {
    Vec3 point = Vec3::Zero(), normal = Vec3::Zero(), displacement = Vec3::Zero();
    std::string tangential;
    long release_steps = 0;
    std::optional<std::string> name;
  };

  PlatenContact(const Parameters& p, const Settings& s)
      : parameters_(p),
        selector_(p.has("nodes") ? std::optional(NodeSelector::from(p, "nodes")) : std::nullopt),
        contact_(s.name.value_or(fmt::format("contact{}", p.pointer().substr(p.pointer().rfind('/') + 1))), plane(p, s),
                 s.tangential == "stick", s.release_steps, p.pointer("normal")) {}

  static PlaneContact::Plane plane(const Parameters& p, const Settings& s) {
    if (s.normal.norm() == 0.0)
      throw InputError(p.pointer("normal"), "the normal is zero: give the direction into the body");
    return {s.point, s.normal.normalized(), s.displacement};
  }

  Parameters parameters_;
  std::optional<NodeSelector> selector_;
  PlaneContact contact_;
};

}  // namespace mtled

MTLED_PLUGIN(mtled::BoundaryCondition, mtled::PlatenContact)
