// Mesh source "label_map": a segmented image (NRRD, Slicer's .seg.nrrd, NIfTI) meshed into labelled tetrahedra by
// CGAL's Mesh_3 (Delaunay refinement of a labelled-image domain, then sliver exudation), in the image's physical
// frame, so that results lie on the image they came from. Each meshed label becomes a region named after its
// segment (or "label_N"), which the scene's materials choose by "region"; labels left out (background, fluid) are
// outside the body.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Image_3.h>
#include <CGAL/Labeled_mesh_domain_3.h>
#include <CGAL/Mesh_3/initialize_triangulation_from_labeled_image.h>
#include <CGAL/Mesh_complex_3_in_triangulation_3.h>
#include <CGAL/Mesh_criteria_3.h>
#include <CGAL/Mesh_triangulation_3.h>
#include <CGAL/refine_mesh_3.h>
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <iostream>
#include <map>
#include <set>
#include <sstream>
#include <unordered_map>

#include "mtled/errors.hpp"
#include "mtled/interfaces/mesh_source.hpp"
#include "mtled/io/label_image.hpp"
#include "mtled/log.hpp"
#include "mtled/plugin.hpp"
#include "path_refinement.hpp"

namespace mtled {

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Domain = CGAL::Labeled_mesh_domain_3<Kernel>;
using Triangulation = CGAL::Mesh_triangulation_3<Domain, CGAL::Default, CGAL::Sequential_tag>::type;
using Complex = CGAL::Mesh_complex_3_in_triangulation_3<Triangulation>;
using Criteria = CGAL::Mesh_criteria_3<Triangulation>;

// Nodes per unit volume of a Mesh_3 mesh with cell and facet size h, times h^3: 0.78 on the brain phantom's label
// map (30,181 nodes at h = 3.34 mm), 0.88 on a small sphere (more surface per volume). The first generation for
// target_nodes uses it; a second corrects h by the count the first gave.
constexpr double kNodesPerCellVolume = 0.8;

// The smallest dihedral angle (degrees) the sliver perturbation and exudation work towards: Gmsh's brain phantom
// reaches 11.7; without them CGAL's stops at 6.3.
constexpr double kSliverBound = 12.0;

// The mesh size at a point of the refinement: `h`, or a region's own smaller size for the cells inside it and the
// surface facets on its boundary (a facet between two regions takes the smaller). A small curved region needs it:
// flat facets of size a inside a surface of curvature radius R cut off a fraction of its volume growing as (a/R)^2,
// 0.96% of the brain phantom's stem (semi-axes 14 and 16 mm across) at the 2.45 mm that suits the rest of the brain.
// Near the segment to refine along (in CGAL's frame, the image's axes through its origin: distances are physical),
// the refined size where it is smaller.
struct RegionSizes {
  double h;
  std::map<std::int32_t, double> by_label;
  std::optional<std::pair<Vec3, Vec3>> segment;
  RefinedSize refined;

  double size(std::int32_t label) const {
    const auto it = by_label.find(label);
    return it == by_label.end() ? h : std::min(h, it->second);
  }
  double operator()(const Kernel::Point_3& point, int dimension, const Domain::Index& index) const {
    double region = h;
    if (dimension == 3) {
      region = size(boost::get<Domain::Subdomain_index>(index));
    } else if (dimension == 2) {
      const auto& patch = boost::get<Domain::Surface_patch_index>(index);
      region = std::min(size(patch.first), size(patch.second));
    }
    if (!segment) return region;
    const Vec3 x(point.x(), point.y(), point.z());
    return refined.at_distance(distance_to_segment(x, segment->first, segment->second), region);
  }
};

// CGAL meshes in the image's voxel-size-scaled index space: x = origin + R s, with R the rotation of the image's axes.
Mat3 cgal_rotation(const LabelImage& image) { return image.axes * image.spacing().cwiseInverse().asDiagonal(); }

// The image as CGAL's meshing sees it: one int32 per voxel, axis-aligned with the voxel sizes (m); labels not
// meshed are 0 (outside).
CGAL::Image_3 cgal_image(const LabelImage& image, const std::set<std::int32_t>& meshed) {
  const Vec3 spacing = image.spacing();
  _image* raw = ::_createImage(static_cast<std::size_t>(image.size[0]), static_cast<std::size_t>(image.size[1]),
                               static_cast<std::size_t>(image.size[2]), 1, static_cast<float>(spacing[0]),
                               static_cast<float>(spacing[1]), static_cast<float>(spacing[2]), 4, WK_FIXED, SGN_SIGNED);
  auto* data = static_cast<std::int32_t*>(raw->data);
  for (std::size_t v = 0; v < image.labels.size(); ++v) data[v] = meshed.count(image.labels[v]) != 0 ? image.labels[v] : 0;
  return CGAL::Image_3(raw);
}

// Stalling, Zöckler and Hege's weights (Weighted labels for 3D image segmentation, ZIB report 98-39, 1998), as
// CGAL's labelled-image domain takes them: at each voxel, the largest over the labels of the label's indicator (255
// inside) smoothed by a Gaussian of one voxel. The domain then places each boundary where the smoothed indicators of
// the two sides cross, a smooth surface through the voxels' staircase rather than along it.
CGAL::Image_3 label_weights(const CGAL::Image_3& labels) {
  const std::array<std::size_t, 3> n = {labels.xdim(), labels.ydim(), labels.zdim()};
  const std::size_t count = n[0] * n[1] * n[2];
  const auto* label = static_cast<const std::int32_t*>(labels.data());
  const std::set<std::int32_t> values(label, label + count);
  constexpr int kRadius = 3;  // the Gaussian (sigma one voxel) truncated at three sigma, normalised
  std::array<float, 2 * kRadius + 1> kernel{};
  float sum = 0.0F;
  for (int k = -kRadius; k <= kRadius; ++k) sum += kernel[static_cast<std::size_t>(k + kRadius)] = std::exp(-0.5F * static_cast<float>(k * k));
  for (float& k : kernel) k /= sum;
  std::vector<float> largest(count, 0.0F), field(count), blurred(count);
  for (const std::int32_t value : values) {
    for (std::size_t v = 0; v < count; ++v) field[v] = label[v] == value ? 255.0F : 0.0F;
    for (std::size_t axis = 0; axis < 3; ++axis) {  // separable: one pass per axis, clamped at the image's faces
      const std::size_t stride = axis == 0 ? 1 : axis == 1 ? n[0] : n[0] * n[1];
      for (std::size_t v = 0; v < count; ++v) {
        const auto i = static_cast<std::ptrdiff_t>((v / stride) % n[axis]);
        float total = 0.0F;
        for (int k = -kRadius; k <= kRadius; ++k) {
          const std::ptrdiff_t j = std::clamp<std::ptrdiff_t>(i + k, 0, static_cast<std::ptrdiff_t>(n[axis]) - 1);
          total += kernel[static_cast<std::size_t>(k + kRadius)] *
                   field[static_cast<std::size_t>(static_cast<std::ptrdiff_t>(v) + (j - i) * static_cast<std::ptrdiff_t>(stride))];
        }
        blurred[v] = total;
      }
      std::swap(field, blurred);
    }
    for (std::size_t v = 0; v < count; ++v) largest[v] = std::max(largest[v], field[v]);
  }
  _image* raw = ::_createImage(n[0], n[1], n[2], 1, static_cast<float>(labels.vx()), static_cast<float>(labels.vy()),
                               static_cast<float>(labels.vz()), 1, WK_FIXED, SGN_UNSIGNED);
  auto* weight = static_cast<unsigned char*>(raw->data);
  for (std::size_t v = 0; v < count; ++v) weight[v] = static_cast<unsigned char>(std::lround(std::min(largest[v], 255.0F)));
  return CGAL::Image_3(raw);
}

// A meshed label's region: its segment's name, or "label_N".
std::string region_name(const LabelImage& image, std::int32_t label) {
  const auto name = image.segment_names.find(label);
  return name != image.segment_names.end() ? name->second : fmt::format("label_{}", label);
}

class LabelMapMesh final : public MeshSource {
 public:
  static void declare(ComponentDeclaration& d) {
    d.summary("A segmented image (label map) meshed into labelled tets by CGAL's Mesh_3, in the image's physical "
              "frame: NRRD (.nrrd, 3D Slicer's .seg.nrrd with its segment names) or NIfTI-1/2 (.nii, .nii.gz). "
              "Each meshed label is a region named after its segment, or \"label_N\"; node set \"surface\" holds "
              "the boundary nodes (docs/label-maps.md)");
    d.string("path").doc("the label map; a relative path is taken from the scene's folder").to<&Settings::path>();
    d.number_list("labels")
        .unit("1")
        .optional()
        .doc("label values to mesh (default: every label but 0); the others are outside the body")
        .to<&Settings::labels>();
    d.string_list("segments")
        .optional()
        .doc("segment names to mesh (a .seg.nrrd's names), instead of or besides \"labels\"")
        .to<&Settings::segments>();
    d.number("mesh_size")
        .unit("m")
        .positive()
        .optional()
        .doc("the largest cell and surface-facet size (give this or target_nodes)")
        .to<&Settings::mesh_size>();
    d.integer("target_nodes")
        .at_least(100)
        .unit("1")
        .optional()
        .doc("about this many nodes (within about 15%): sets mesh_size")
        .to<&Settings::target_nodes>();
    d.number("surface_distance")
        .unit("m")
        .positive()
        .optional()
        .doc(
            "the largest distance between the mesh's surface facets and the labels' boundaries (default: the largest "
            "voxel size)")
        .to<&Settings::surface_distance>();
    d.number_map("region_mesh_size")
        .unit("m")
        .positive()
        .optional()
        .doc(
            "a smaller mesh size for some regions, by region name (a segment's name, or \"label_N\"): the largest cell "
            "size inside the region and facet size on its boundary, e.g. {\"brain_stem\": 0.0012}: flat facets cut off "
            "a "
            "fraction of a curved region's volume that grows as (size / curvature radius)^2 (the brain phantom's stem: "
            "0.96% at 2.45 mm, 0.32% at 1.2 mm)")
        .to<&Settings::region_mesh_size>();
    d.boolean("smooth")
        .defaults(false)
        .doc(
            "place the boundaries on a smooth surface through the voxels (weighted labels: each label's indicator "
            "smoothed "
            "over a voxel) rather than along their staircase: for large smooth organs (the brain phantom's surface "
            "lies "
            "within 0.19 mm of the analytic one at its top); it shrinks small or sharp regions (a sphere of 7 voxels' "
            "radius by 9% of its volume), which the default keeps at the voxels' boundaries")
        .to<&Settings::smooth>();
    declare_path_refinement<Settings>(d);
    d.example({{"path", "brain.nii.gz"}, {"target_nodes", 20000}});
  }

  explicit LabelMapMesh(const Parameters& p) : p_(p), settings_(p.read<Settings>()) {
    read_refined_segment(settings_, p);  // refused early: both ends or neither, one size
    if (settings_.mesh_size.has_value() == settings_.target_nodes.has_value())
      throw InputError(p.pointer("mesh_size"), "give exactly one of mesh_size (m) and target_nodes");
    warn_if_refining_nothing(settings_, p, false);
  }

  TetMesh load(const MeshContext& context) override {
    const auto start = std::chrono::steady_clock::now();
    std::filesystem::path file = settings_.path;
    if (file.is_relative()) file = context.scene_directory / file;
    const LabelImage image = read_label_image(file);
    const auto counts = image.voxel_counts();
    const std::set<std::int32_t> meshed = meshed_labels(image, counts);
    CGAL::Random random(0);
    const CGAL::Image_3 cgal = cgal_image(image, meshed);
    const CGAL::Image_3 weights = settings_.smooth ? label_weights(cgal) : CGAL::Image_3();
    const Domain domain = Domain::create_labeled_image_mesh_domain(cgal, CGAL::parameters::weights = weights,
                                                                   CGAL::parameters::relative_error_bound = 1e-6,
                                                                   CGAL::parameters::p_rng = &random);
    const double distance = settings_.surface_distance.value_or(image.spacing().maxCoeff());
    const auto segment = refined_segment_for(settings_, p_, context, image.space);
    RegionSizes sizes{mesh_size(image, meshed, counts), region_sizes(image, meshed), to_cgal_frame(segment, image),
                      read_refined_size(settings_)};
    if (settings_.target_nodes) {  // a trial refinement first, to size h by its count (N ~ 1 / h^3)
      const double target = static_cast<double>(*settings_.target_nodes);
      sizes.h *=
          std::cbrt(static_cast<double>(generate(domain, cgal, sizes, distance, image, false).node_count()) / target);
    }
    const double h = sizes.h;
    TetMesh mesh = generate(domain, cgal, sizes, distance, image, true);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    mesh.statistics["meshing_time_s"] = seconds;
    mesh.statistics["mesh_size_m"] = h;
    const MeshQuality quality = mesh_quality(mesh);
    log().info("label_map: {} nodes, {} tets in {} regions from {} ({}x{}x{} voxels), mesh size {:.3g} mm, {:.2f} s; "
               "smallest dihedral angle {:.2f} deg, radius ratio {:.3f}",
               mesh.node_count(), mesh.tet_count(), mesh.region_names.size(), file.filename().string(), image.size[0],
               image.size[1], image.size[2], 1e3 * h, seconds, quality.min_dihedral_angle_deg, quality.min_radius_ratio);
    return mesh;
  }

 private:
  struct Settings {
    std::string path;
    std::optional<std::vector<double>> labels;
    std::optional<std::vector<std::string>> segments;
    std::optional<double> mesh_size;
    std::optional<long> target_nodes;
    std::optional<double> surface_distance;
    std::optional<std::map<std::string, double>> region_mesh_size;
    bool smooth = false;
    bool refine_along_needle = false;
    std::optional<Vec3> refine_from, refine_to;
    std::optional<double> refine_ratio, refine_size;
    double refine_distance = 0.0;
    std::optional<double> refine_transition;
  };

  // A segment in the image's physical frame, in CGAL's (cgal_rotation).
  static std::optional<std::pair<Vec3, Vec3>> to_cgal_frame(const std::optional<std::pair<Vec3, Vec3>>& segment,
                                                            const LabelImage& image) {
    if (!segment) return std::nullopt;
    const Mat3 rotation = cgal_rotation(image);
    const auto to_cgal = [&](const Vec3& x) -> Vec3 { return rotation.transpose() * (x - image.origin); };
    return std::make_pair(to_cgal(segment->first), to_cgal(segment->second));
  }

  std::set<std::int32_t> meshed_labels(const LabelImage& image, const std::map<std::int32_t, std::int64_t>& counts) const {
    std::set<std::int32_t> meshed;
    const auto values = settings_.labels.value_or(std::vector<double>{});
    const auto names = settings_.segments.value_or(std::vector<std::string>{});
    for (std::size_t i = 0; i < values.size(); ++i) {
      const auto label = static_cast<std::int32_t>(values[i]);
      if (label == 0 || static_cast<double>(label) != values[i] || counts.count(label) == 0)
        throw InputError(fmt::format("{}/{}", p_.pointer("labels"), i),
                         fmt::format("label {} is {} (labels in the image: {})", values[i],
                                     label == 0 ? "the outside" : "not in the image", label_list(counts)));
      meshed.insert(label);
    }
    for (std::size_t i = 0; i < names.size(); ++i) meshed.insert(segment_label(image, names[i], i, counts));
    if (values.empty() && names.empty())
      for (const auto& [label, count] : counts)
        if (label != 0) meshed.insert(label);
    if (meshed.empty())
      throw InputError(image.source, "the label map is empty: every voxel is 0 (no labelled region to mesh)");
    return meshed;
  }

  std::int32_t segment_label(const LabelImage& image, const std::string& name, std::size_t i,
                             const std::map<std::int32_t, std::int64_t>& counts) const {
    std::vector<std::string> known;
    for (const auto& [label, segment] : image.segment_names) {
      if (segment == name) {
        if (counts.count(label) == 0)
          throw InputError(fmt::format("{}/{}", p_.pointer("segments"), i),
                           fmt::format("segment \"{}\" (label {}) has no voxel in the image: it is empty", name, label));
        return label;
      }
      known.push_back(fmt::format("\"{}\"", segment));
    }
    throw InputError(fmt::format("{}/{}", p_.pointer("segments"), i),
                     fmt::format("the image has no segment named \"{}\" (segments: {})", name,
                                 known.empty() ? "none; name labels by value with \"labels\"" : fmt::format("{}", fmt::join(known, ", "))));
  }

  static std::string label_list(const std::map<std::int32_t, std::int64_t>& counts) {
    std::vector<std::string> parts;
    for (const auto& [label, count] : counts) parts.push_back(fmt::format("{} ({} voxels)", label, count));
    return fmt::format("{}", fmt::join(parts, ", "));
  }

  // region_mesh_size by label; every name must be a meshed region's.
  std::map<std::int32_t, double> region_sizes(const LabelImage& image, const std::set<std::int32_t>& meshed) const {
    std::map<std::int32_t, double> by_label;
    if (!settings_.region_mesh_size) return by_label;
    std::map<std::string, std::int32_t> labels;
    for (const std::int32_t label : meshed) labels[region_name(image, label)] = label;
    for (const auto& [name, size] : *settings_.region_mesh_size) {
      const auto it = labels.find(name);
      if (it == labels.end()) {
        std::vector<std::string> known;
        for (const auto& [region, label] : labels) known.push_back(region);
        const std::string hint = did_you_mean(name, known);
        throw InputError(fmt::format("{}/{}", p_.pointer("region_mesh_size"), name),
                         fmt::format("no meshed region is named \"{}\"{} (regions: {})", name,
                                     hint.empty() ? "" : "; " + hint, fmt::join(known, ", ")));
      }
      by_label[it->second] = size;
    }
    return by_label;
  }

  double mesh_size(const LabelImage& image, const std::set<std::int32_t>& meshed,
                   const std::map<std::int32_t, std::int64_t>& counts) const {
    if (settings_.mesh_size) return *settings_.mesh_size;
    const Vec3 s = image.spacing();
    std::int64_t voxels = 0;
    for (const auto& [label, count] : counts)
      if (meshed.count(label) != 0) voxels += count;
    const double volume = static_cast<double>(voxels) * s[0] * s[1] * s[2];
    return std::cbrt(kNodesPerCellVolume * volume / static_cast<double>(*settings_.target_nodes));
  }

  // Delaunay refinement to the criteria, then (when `optimise`) the sliver exudation, which changes no vertex. The
  // refinement starts from points on every connected labelled component of the image (CGAL's default start shoots
  // rays from the bounding box's centre and finds no surface when that centre and the rays' ends are outside).
  static TetMesh generate(const Domain& domain, const CGAL::Image_3& image_3, const RegionSizes& sizes, double distance,
                          const LabelImage& image, bool optimise) {
    CGAL::get_default_random() = CGAL::Random(0);  // the same mesh on every run
    const Criteria criteria(CGAL::parameters::facet_angle = 25, CGAL::parameters::facet_size = sizes,
                            CGAL::parameters::facet_distance = distance, CGAL::parameters::cell_radius_edge_ratio = 3,
                            CGAL::parameters::cell_size = sizes);
    // The exudation stops by default after as long as the refinement took, which would make the mesh depend on the
    // machine's speed: no time limit (0), so that a scene gives the same mesh everywhere. The sliver perturbation
    // (vertices moved) is left out: without a time limit it took 40 of the brain phantom's 62 s.
    Complex complex;
    {
      // It reports its progress on std::cout, which is the user's (mtled logs on stderr): silenced.
      std::ostringstream quiet;
      std::streambuf* const out = std::cout.rdbuf(quiet.rdbuf());
      ::initialize_triangulation_from_labeled_image(complex, domain, image_3, criteria, std::int32_t{0});
      std::cout.rdbuf(out);
    }
    if (optimise)
      CGAL::refine_mesh_3(complex, domain, criteria,
                          CGAL::parameters::perturb(CGAL::parameters::time_limit = 0,
                                                    CGAL::parameters::sliver_bound = kSliverBound),
                          CGAL::parameters::exude(CGAL::parameters::time_limit = 0,
                                                  CGAL::parameters::sliver_bound = kSliverBound));
    else
      CGAL::refine_mesh_3(complex, domain, criteria, CGAL::parameters::no_perturb(), CGAL::parameters::no_exude());
    return to_tet_mesh(complex, image);
  }
  static TetMesh to_tet_mesh(const Complex& complex, const LabelImage& image);

  Parameters p_;
  Settings settings_;
};

// The complex's cells as tets in the image's frame (cgal_rotation).
TetMesh LabelMapMesh::to_tet_mesh(const Complex& complex, const LabelImage& image) {
  TetMesh mesh;
  mesh.source = image.source;
  mesh.coordinate_system = image.space;
  const Mat3 rotation = cgal_rotation(image);
  std::unordered_map<const void*, Index> index;
  std::map<int, Index> regions;  // numbered in label order, so that a region's number does not depend on the mesh
  for (auto cell = complex.cells_in_complex_begin(); cell != complex.cells_in_complex_end(); ++cell)
    regions.emplace(static_cast<int>(complex.subdomain_index(cell)), 0);
  for (auto& [label, region] : regions) {
    region = static_cast<Index>(mesh.region_names.size());
    mesh.region_names.push_back(region_name(image, label));
  }
  for (auto cell = complex.cells_in_complex_begin(); cell != complex.cells_in_complex_end(); ++cell) {
    std::array<Index, 4> tet{};
    for (int v = 0; v < 4; ++v) {
      const auto vertex = cell->vertex(v);
      const auto [it, added] = index.emplace(&*vertex, static_cast<Index>(mesh.points.size()));
      if (added) {
        const auto& p = vertex->point().point();
        mesh.points.push_back(image.origin + rotation * Vec3(p.x(), p.y(), p.z()));
      }
      tet[static_cast<std::size_t>(v)] = it->second;
    }
    mesh.tets.push_back(tet);
    mesh.tet_region.push_back(regions.at(static_cast<int>(complex.subdomain_index(cell))));
  }
  if (mesh.tets.empty())
    throw InputError(image.source, "meshing produced no tets: the labelled regions are smaller than the mesh size; "
                                   "lower mesh_size or raise target_nodes");
  check_mesh(mesh, /*fix_orientation=*/true);
  const auto surface = surface_nodes(mesh);
  for (Index i = 0; i < mesh.node_count(); ++i)
    if (surface[static_cast<std::size_t>(i)]) mesh.node_sets["surface"].push_back(i);
  return mesh;
}

}  // namespace

}  // namespace mtled

MTLED_PLUGIN(mtled::MeshSource, mtled::LabelMapMesh)
