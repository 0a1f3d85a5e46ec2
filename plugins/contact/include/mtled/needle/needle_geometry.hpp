#pragma once
// What every needle model shares: the straight needle's parameters and path, checks that it enters the
// body, and the nodes along its path.
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "mtled/discretisation.hpp"
#include "mtled/interfaces/driver.hpp"

namespace mtled {

struct NeedlePath {
  // The frame entry and direction are in: "LPS" or "RAS" when they came from a 3D Slicer markups file
  // (`trajectory`), empty when the scene gave them (the mesh's own coordinates).
  std::string frame;
  Vec3 entry = Vec3::Zero();
  Vec3 direction = -Vec3::UnitZ();  // unit
  double depth = 0.0;               // final tip advance from the entry (m)
  double radius = 0.0;              // needle radius (m)
  std::filesystem::path trajectory;  // the markups file it came from, if any

  // Axial coordinate of x along the path (0 at the entry, growing with insertion) and distance from the axis.
  double axial(const Vec3& x) const { return direction.dot(x - entry); }
  double radial(const Vec3& x) const { return ((x - entry) - direction * axial(x)).norm(); }
  Vec3 tip(double advance) const { return entry + advance * direction; }
  // From the entry to the tip at the final depth: what a mesh refines along (refine_along_needle).
  PlannedPath planned() const { return {entry, tip(depth), frame}; }
  // What a needle model's status() says of the path and the puncture (puncture_depth: where it punctured, if it has);
  // the model adds its force and driven nodes.
  NeedleStatus status(double advance, std::optional<double> puncture_depth) const {
    NeedleStatus s;
    s.depth = advance;
    s.phase = puncture_depth ? NeedlePhase::penetration : NeedlePhase::indentation;
    s.puncture_depth = puncture_depth.value_or(-1.0);
    s.entry = entry;
    s.direction = direction;
    s.radius = radius;
    return s;
  }
};

// Declares diameter, entry, direction, depth and trajectory (shared by all needle models), bound to
// NeedlePathSettings. The path is either entry (+ direction, depth) in metres, or a 3D Slicer markups file
// (.mrk.json) whose line, or whose first two points, run from the entry to the target (depth: their distance unless
// given).
struct NeedlePathSettings {
  double diameter = 0.0;
  std::optional<Vec3> entry, direction;
  std::optional<double> depth;
  std::optional<std::filesystem::path> trajectory;
};
void declare_needle_path(ComponentDeclaration& d);

// Declares "strain_radius", where a needle model watches for the puncture strain, bound to TipStrainSettings.
struct TipStrainSettings {
  std::optional<double> strain_radius;
};
void declare_strain_radius(ComponentDeclaration& d);
NeedlePath read_needle_path(const Parameters& p);


// The two points a 3D Slicer markups file (.mrk.json) gives a needle: its first markup's first two defined
// control points, in metres, in the file's coordinateSystem. InputError naming the file otherwise.
struct MarkupsTrajectory {
  Vec3 entry, target;
  std::string frame;  // "LPS" or "RAS"
};
MarkupsTrajectory read_markups_trajectory(const std::filesystem::path& file);
MarkupsTrajectory parse_markups_trajectory(const std::string& text, const std::string& label);  // the file's text

// First in a needle's setup(): puts a path read from a markups file, which is in the file's frame, into the mesh's
// (LPS and RAS differ in the sign of x and y) where the mesh records its frame (label maps, Slicer's files); then
// refuses an entry point that is off the body (no surface node within 1.5 mean edge lengths) or a path that meets
// no nodes of the body, with the scene pointer and a suggestion.
void place_needle_path(NeedlePath& path, const Discretisation& model, const Parameters& p);

// Mean edge length of the surface nodes nearest the entry: the local node spacing where the needle enters.
double spacing_at_entry(const NeedlePath& path, const Discretisation& model);

// The footprint, the surface nodes the tip meets first: those within half the entry's node `spacing` of the entry's
// plane and within `radius` of the axis, or the surface node nearest the entry when none is.
std::vector<Index> footprint_nodes(const NeedlePath& path, const Discretisation& model, double spacing, double radius);

// The puncture test both needle models share: the largest principal Green strain (in absolute value) at the
// integration points within `radius` of the tip.
class TipStrainWatch {
 public:
  // Keeps the integration points that a tip anywhere along the path can come within `radius` of.
  void setup(const NeedlePath& path, const Discretisation& model, double radius);
  double largest(const Discretisation& model, std::span<const double> u, const Vec3& tip) const;
  // Appends the nodes largest(model, u, tip) reads.
  void append_nodes_read(const Discretisation& model, const Vec3& tip, std::vector<Index>& nodes) const;

 private:
  std::vector<Index> watched_;
  double radius_ = 0.0;
};

}  // namespace mtled
