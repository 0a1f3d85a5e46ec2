#include "support/generator.hpp"

#include <fmt/format.h>
#include <gmsh.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <random>

#include "mtled/errors.hpp"
#include "mtled/log.hpp"
#include "support/gmsh_session.hpp"

namespace mtled {

namespace {

// Node-count model N(h) = c_v V / h^3 + c_s A / h^2 for Gmsh's Delaunay mesher under Mesh.MeshSizeMax = h,
// fitted to the 30 x 17 mm cylinder at 3,700 to 32,000 nodes. The shape factor k that the calibration
// measures was 0.96 to 1.16 for boxes, cylinders, the layered sample, the brain phantom and STL spheres.
constexpr double kVolumeNodeDensity = 0.70;   // nodes per h^3 of volume
constexpr double kSurfaceNodeDensity = 0.79;  // extra nodes per h^2 of surface

constexpr long kMinTargetNodes = 200;
constexpr long kMaxTargetNodes = 2'000'000;
// A mesh_size that the model says gives more nodes than this is refused before Gmsh spends hours on it.
constexpr double kMaxEstimatedNodes = 5'000'000;
constexpr int kMaxGenerations = 5;
constexpr long kPilotThreshold = 20'000;  // targets from here on calibrate k on a pilot mesh first
// k drifts with the mesh size on shapes with creases (the brain phantom: 1.046 at 1/8 of its default
// target, 1.014 at 1/4, 1.003 at the target): a quarter-size pilot lands the full mesh within 3%.
constexpr double kPilotFraction = 1.0 / 4.0;

double model_node_count(const GeometryMeasure& g, double h) {
  return kVolumeNodeDensity * g.volume / (h * h * h) + kSurfaceNodeDensity * g.surface_area / (h * h);
}

// The h with k * N(h) = nodes. In u = 1/h, a u^3 + b u^2 = nodes / k is increasing and convex for u > 0;
// Newton from the volume-only root (where the left side is already >= the right) converges from above.
double size_for_node_count(const GeometryMeasure& g, double nodes, double k) {
  const double a = kVolumeNodeDensity * g.volume;
  const double b = kSurfaceNodeDensity * g.surface_area;
  const double goal = nodes / k;
  double u = std::cbrt(goal / a);
  for (int iteration = 0; iteration < 60; ++iteration) {
    const double f = a * u * u * u + b * u * u - goal;
    const double step = f / (3.0 * a * u * u + 2.0 * b * u);
    u -= step;
    if (std::abs(step) <= 1e-12 * u) break;
  }
  return 1.0 / u;
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

struct Generation {
  TetMesh mesh;
  double mesh_size = 0.0;
  Index nodes = 0;
};

// Finer mesh near a segment (a needle's path) and/or a shape's rims (where bonded faces meet a free side, the
// stress is singular).
struct Refinement {
  std::optional<std::pair<Vec3, Vec3>> segment;
  bool rims = false;
  RefinedSize size;
};

std::optional<Refinement> read_refinement(const MeshSizeSettings& size, const Parameters& p,
                                          const GeneratorRequest& request) {
  auto segment = refined_segment_for(size, p, request.context, "");  // Gmsh's meshes record no frame
  const bool rims = request.rim_curves && size.refine_rims;
  warn_if_refining_nothing(size, p, rims);
  if (!segment && !rims) return std::nullopt;
  return Refinement{std::move(segment), rims, read_refined_size(size)};
}

class Generator {
 public:
  Generator(const GeneratorRequest& request, std::optional<Refinement> refinement)
      : request_(request), refinement_(std::move(refinement)) {}

  const GeometryMeasure& measure() {
    if (!built_) build();
    return measure_;
  }

  Generation generate(double mesh_size) {
    if (!built_) build();
    gmsh_checked([&] {
      if (meshed_) gmsh::model::mesh::clear();
      gmsh::option::setNumber("Mesh.MeshSizeMax", mesh_size);
      if (refinement_) {
        gmsh::model::mesh::field::setNumber(kThresholdField, "SizeMin", refinement_->size.fine(mesh_size));
        gmsh::model::mesh::field::setNumber(kThresholdField, "SizeMax", mesh_size);
      }
      gmsh::model::mesh::generate(3);
    });
    meshed_ = true;
    built_ = !request_.rebuild_each_generation;
    Generation generation{extract_tet_mesh(), mesh_size, 0};
    // Gmsh's optimiser moves inner vertices only: a sliver capping the curved surface stays (the brain phantom's
    // clouds at 66,000 and 82,000 nodes had one each, 0.62 and 0.36 degrees).
    if (const Index removed = remove_boundary_slivers(generation.mesh))
      log().debug("{}: removed {} sliver(s) capping the surface", request_.component, removed);
    generation.nodes = used_node_count(generation.mesh);
    check_volume(generation.mesh);
    ++generations_;
    log().debug("{}: generation {} at mesh size {:.4g} m gave {} nodes", request_.component, generations_, mesh_size,
                generation.nodes);
    return generation;
  }

  int generations() const { return generations_; }

 private:
  void build() {
    gmsh_checked([] { gmsh::clear(); });
    meshed_ = false;
    measure_ = request_.build_geometry();
    if (!(measure_.volume > 0.0) || !(measure_.surface_area > 0.0)) throw GmshError("the geometry has no volume");
    if (refinement_) add_refinement_field(*refinement_, request_);
    built_ = true;
  }

  // Free geometric points along the segment (every quarter of the refinement distance: the distance to them
  // is within 1/8 of it of the distance to the segment) and the rim curves (sampled as finely) feed a Distance
  // field, which a Threshold field turns into sizes; the free points are meshed as lone vertices, which
  // remove_unused_nodes drops.
  static void add_refinement_field(const Refinement& r, const GeneratorRequest& request) {
    const double spacing = 0.25 * r.size.distance;
    std::vector<double> points, curves;
    if (r.segment) {
      const auto& [from, to] = *r.segment;
      const int intervals = std::max(1, static_cast<int>(std::ceil((to - from).norm() / spacing)));
      for (int i = 0; i <= intervals; ++i) {
        const Vec3 x = from + (to - from) * (static_cast<double>(i) / intervals);
        points.push_back(gmsh::model::occ::addPoint(x[0], x[1], x[2]));
      }
      gmsh::model::occ::synchronize();
    }
    double longest = 0.0;
    if (r.rims)
      for (const int curve : request.rim_curves()) {
        double length = 0.0;
        gmsh::model::occ::getMass(1, curve, length);
        longest = std::max(longest, length);
        curves.push_back(curve);
      }
    gmsh::model::mesh::field::add("Distance", kDistanceField);
    if (!points.empty()) gmsh::model::mesh::field::setNumbers(kDistanceField, "PointsList", points);
    if (!curves.empty()) {
      gmsh::model::mesh::field::setNumbers(kDistanceField, "CurvesList", curves);
      gmsh::model::mesh::field::setNumber(kDistanceField, "NumPointsPerCurve",
                                          std::clamp(std::ceil(longest / spacing), 20.0, 1e5));
    }
    gmsh::model::mesh::field::add("Threshold", kThresholdField);
    gmsh::model::mesh::field::setNumber(kThresholdField, "InField", kDistanceField);
    gmsh::model::mesh::field::setNumber(kThresholdField, "DistMin", r.size.distance);
    gmsh::model::mesh::field::setNumber(kThresholdField, "DistMax", r.size.distance + r.size.transition);
    gmsh::model::mesh::field::setAsBackgroundMesh(kThresholdField);
    // Gmsh carries the sizes of a face's boundary curves into the face by default: the fine rims would make
    // the whole top and bottom faces fine. Only the field decides.
    if (r.rims) gmsh::option::setNumber("Mesh.MeshSizeExtendFromBoundary", 0);
  }
  static constexpr int kDistanceField = 1, kThresholdField = 2;

  // Gross failures (a volume left unmeshed) show as missing volume; the polygonal approximation of curved
  // faces stays far below a quarter of the volume even on the coarsest meshes allowed.
  void check_volume(const TetMesh& mesh) const {
    if (mesh.tets.empty()) throw GmshError("Gmsh produced no tetrahedra");
    double volume = 0.0;
    for (Index t = 0; t < mesh.tet_count(); ++t) volume += std::abs(tet_volume(mesh, t));
    if (std::abs(volume - measure_.volume) > 0.25 * measure_.volume)
      throw GmshError(
          fmt::format("the tetrahedra fill {:.4g} m^3 of the {:.4g} m^3 geometry", volume, measure_.volume));
  }

  const GeneratorRequest& request_;
  std::optional<Refinement> refinement_;
  GeometryMeasure measure_;
  bool built_ = false;
  bool meshed_ = false;
  int generations_ = 0;
};

// The coarsest mesh size the generator allows (infinite when it sets no limit).
double coarsest_size(const GeneratorRequest& request) {
  return request.max_mesh_size ? request.max_mesh_size->size : std::numeric_limits<double>::infinity();
}

Generation calibrated_generation(Generator& generator, long target, const Parameters& parameters,
                                 const GeneratorRequest& request) {
  const double goal = static_cast<double>(target);
  const GeometryMeasure& measure = generator.measure();
  const double coarsest = coarsest_size(request);
  if (size_for_node_count(measure, goal, 1.0) > coarsest)
    throw InputError(parameters.pointer("target_nodes"),
                     fmt::format("target_nodes {} is too few for this {}: the mesh size would exceed {} ({:.4g} m); "
                                 "ask for at least {:.0f} nodes",
                                 target, request.component, request.max_mesh_size->what, coarsest,
                                 std::ceil(model_node_count(measure, coarsest))));
  double k = request.node_factor.value_or(1.0);
  if (target >= kPilotThreshold && !request.node_factor) {
    const double h = std::min(size_for_node_count(measure, kPilotFraction * goal, k), coarsest);
    const Generation pilot = generator.generate(h);
    k = pilot.nodes / model_node_count(measure, h);
    log().debug("{}: the pilot's node-model factor k = {:.17g}", request.component, k);
  }
  std::optional<Generation> best;
  auto error = [&](const Generation& g) { return std::abs(g.nodes / goal - 1.0); };
  // Sizes known to give too many nodes (below too_fine) and too few (above too_coarse): the count is a step
  // function of the size (edges get whole numbers of segments), so the model's next guess is kept inside.
  double too_fine = 0.0, too_coarse = std::numeric_limits<double>::infinity();
  for (int attempt = 0; attempt < kMaxGenerations; ++attempt) {
    double h = size_for_node_count(measure, goal, k);
    if (h <= too_fine || h >= too_coarse) {
      if (too_fine > 0.0 && std::isfinite(too_coarse))
        h = std::sqrt(too_fine * too_coarse);
      else
        h = h <= too_fine ? too_fine * 1.02 : too_coarse / 1.02;
    }
    h = std::min(h, coarsest);
    Generation generation = generator.generate(h);
    k = generation.nodes / model_node_count(measure, h);
    const bool too_many = generation.nodes > goal;
    if (!best || error(generation) < error(*best)) best = std::move(generation);
    if (error(*best) <= kNodeCountTolerance) break;
    if (too_many)
      too_fine = std::max(too_fine, h);
    else
      too_coarse = std::min(too_coarse, h);
    if (too_coarse < 1.005 * too_fine) break;  // the count jumps across the target between two close sizes
    if (too_many && h >= coarsest) break;      // no coarser size allowed
  }
  if (error(*best) > kNodeCountTolerance)
    log().warn(
        "{}: {} nodes, {:.1f}% from target_nodes {} after {} generations: near this size the node count "
        "changes in steps larger than +-3% (a coarse mesh of this shape); the closest was kept. Give another "
        "target_nodes, or mesh_size to choose the size directly",
        request.component, best->nodes, 100.0 * error(*best), target, generator.generations());
  return std::move(*best);
}

// Stability studies need poor clouds: moves each interior node by a uniform random vector in a ball of radius
// `jitter` x its mean edge length (a fixed seed: the same scene gives the same cloud). A move that would leave
// an adjacent tet with less than 1% of its volume is halved, up to four times, then dropped, so the mesh stays
// valid (every tet positive) but gains slivers. Surface nodes stay: the geometry and its node sets are kept.
void jitter_interior_nodes(TetMesh& mesh, double jitter, const std::string& component) {
  const auto surface = surface_nodes(mesh);
  const auto spacing = mean_edge_length_at_nodes(mesh);
  std::vector<std::vector<Index>> node_tets(mesh.points.size());
  for (Index t = 0; t < mesh.tet_count(); ++t)
    for (Index n : mesh.tets[t]) node_tets[n].push_back(t);
  std::vector<double> original(static_cast<std::size_t>(mesh.tet_count()));
  for (Index t = 0; t < mesh.tet_count(); ++t) original[t] = tet_volume(mesh, t);
  std::mt19937_64 random(20261123);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  Index moved = 0;
  for (std::size_t n = 0; n < mesh.points.size(); ++n) {
    if (surface[n] || node_tets[n].empty()) continue;
    Vec3 offset;
    do offset = Vec3(uniform(random), uniform(random), uniform(random));
    while (offset.squaredNorm() > 1.0);
    offset *= jitter * spacing[n];
    const Vec3 home = mesh.points[n];
    for (int attempt = 0; attempt < 5; ++attempt, offset *= 0.5) {
      mesh.points[n] = home + offset;
      bool valid = true;
      for (Index t : node_tets[n]) valid = valid && tet_volume(mesh, t) >= 0.01 * original[t];
      if (valid) break;
      mesh.points[n] = home;
    }
    moved += mesh.points[n] != home ? 1 : 0;
  }
  double smallest = INFINITY;
  Index slivers = 0;
  for (Index t = 0; t < mesh.tet_count(); ++t) {
    const double ratio = tet_volume(mesh, t) / original[t];
    smallest = std::min(smallest, ratio);
    slivers += ratio < 0.1 ? 1 : 0;
  }
  log().info("{}: jitter {:g} moved {} interior nodes; {} tets kept less than 10% of their volume (smallest {:.3g}%)",
             component, jitter, moved, slivers, 100.0 * smallest);
}

}  // namespace

void declare_mesh_size(ComponentDeclaration& declaration, long default_target_nodes) {
  declaration.integer("target_nodes")
      .defaults(default_target_nodes)
      .between(static_cast<double>(kMinTargetNodes), static_cast<double>(kMaxTargetNodes))
      .unit("1")
      .doc(
          "number of mesh nodes wanted: the mesh size is calibrated (a few deterministic generations) until the "
          "node count is within +-3% of it (on coarse meshes, where the count jumps in steps, the closest is kept "
          "with a warning); ignored when mesh_size is given")
      .to<&MeshSizeSettings::target_nodes>();
  declaration.number("mesh_size")
      .optional()
      .positive()
      .unit("m")
      .doc(
          "target tet edge length (Gmsh's Mesh.MeshSizeMax), used directly in one generation; when given, "
          "target_nodes is ignored. Refused when it would give more than 5 million nodes, or when it exceeds a "
          "cylinder's radius")
      .to<&MeshSizeSettings::mesh_size>();
  declaration.number("jitter")
      .defaults(0.0)
      .at_least(0.0)
      .less_than(0.5)
      .unit("1")
      .doc(
          "for stability studies: move each interior node randomly by up to this fraction of its mean edge length "
          "(deterministic; moves that would leave a tet with under 1% of its volume are shortened), giving an "
          "irregular, sliver-rich cloud; 0 keeps Gmsh's nodes")
      .to<&MeshSizeSettings::jitter>();
  declare_path_refinement<MeshSizeSettings>(declaration, " (and the rims, with refine_rims)");
}

void declare_rim_refinement(ComponentDeclaration& declaration) {
  declaration.boolean("refine_rims")
      .defaults(false)
      .doc(
          "refine the mesh along the rims, the circular edges where the top and bottom faces meet the side (with "
          "refine_ratio or refine_size, refine_distance and refine_transition): where bonded faces meet a free side "
          "the stress is "
          "singular, and a cloud graded there gets the platen force closer with a fifth of the nodes of a uniform "
          "one (docs/validation.md); "
          "target_nodes then counts the refined mesh's nodes")
      .to<&MeshSizeSettings::refine_rims>();
}

Vec3 positive_extent(const Vec3& extent, const Parameters& parameters, std::string_view name) {
  for (int axis = 0; axis < 3; ++axis)
    if (!(extent[axis] >= kMinLength))
      throw InputError(parameters.pointer(name),
                       fmt::format("{} {} m has a component below {:g} m: each of x, y, z must be a length of at "
                                   "least {:g} m (e.g. [0.03, 0.02, 0.01] for 30 x 20 x 10 mm)",
                                   name, format_vector(extent), kMinLength, kMinLength));
  return extent;
}

std::string format_vector(const Vec3& v) { return fmt::format("[{:.6g}, {:.6g}, {:.6g}]", v[0], v[1], v[2]); }

TetMesh generate_tet_mesh(const Parameters& parameters, const GeneratorRequest& request) {
  const auto start = std::chrono::steady_clock::now();
  const auto size = parameters.read<MeshSizeSettings>();
  const std::optional<double>& mesh_size = size.mesh_size;
  const long target = size.target_nodes;
  Generation result;
  try {
    GmshSession session;
    Generator generator(request, read_refinement(size, parameters, request));
    if (mesh_size) {
      const double estimate = model_node_count(generator.measure(), *mesh_size);
      if (estimate > kMaxEstimatedNodes)
        throw InputError(parameters.pointer("mesh_size"),
                         fmt::format("mesh_size {:.4g} m would give about {:.3g} million nodes for the {} (more than "
                                     "{:.0f} million); use a larger mesh_size, or give target_nodes instead",
                                     *mesh_size, estimate / 1e6, request.component, kMaxEstimatedNodes / 1e6));
      if (*mesh_size > coarsest_size(request))
        throw InputError(parameters.pointer("mesh_size"),
                         fmt::format("mesh_size {:.4g} m is larger than {} ({:.4g} m), too coarse to follow the {}'s "
                                     "shape; use a mesh_size of at most {:.4g} m",
                                     *mesh_size, request.max_mesh_size->what, coarsest_size(request), request.component,
                                     coarsest_size(request)));
      result = generator.generate(*mesh_size);
    } else {
      result = calibrated_generation(generator, target, parameters, request);
    }
    log().info("{}: {} nodes, {} tets, mesh size {:.4g} mm ({} generation{}{}), {:.2f} s", request.component,
               result.nodes, result.mesh.tet_count(), result.mesh_size * 1e3, generator.generations(),
               generator.generations() == 1 ? "" : "s", mesh_size ? "" : fmt::format(", target_nodes {}", target),
               seconds_since(start));
  } catch (const GmshError& e) {
    throw InputError(request.failure_where.value_or(parameters.pointer()),
                     fmt::format("Gmsh could not mesh the {} ({}): {}; {}", request.component, request.description,
                                 e.what(), request.failure_advice));
  }
  result.mesh.source = request.description;
  if (const double jitter = size.jitter; jitter > 0.0) {
    remove_unused_nodes(result.mesh);
    jitter_interior_nodes(result.mesh, jitter, request.component);
    result.mesh.source += fmt::format(", interior nodes jittered by {:g} edge lengths", jitter);
  }
  return std::move(result.mesh);
}

}  // namespace mtled
