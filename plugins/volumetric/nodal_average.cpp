// `nodal_average`: nodally averaged dilatation, an F-bar scheme (de Souza Neto et al., IJSS 1996, with J
// averaged at the nodes as in Bonet and Burton's nodally averaged tetrahedron, Commun. Numer. Methods Eng.
// 1998). Each integration point uses F_bar = (J_bar / J)^(1/3) F, J_bar the mean over its tet's four vertices of
// J_I, the weighted mean J of the points in the tets around node I. One point per tet and about five tets per node
// impose J = 1 about five times per node against three unknowns: the classic volumetric locking of nearly
// incompressible materials, which the averaging relieves. The forces are the exact gradient of
// E = sum_q w_q W(F_bar_q), so energy is conserved and the stiffness is symmetric. It sums over ranges of points
// too (an MPI rank's share): a point's stress then comes from the two layers of points around it (Region).
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "mtled/force_kernel.hpp"
#include "mtled/plugin.hpp"

namespace mtled {

class NodalAverageTreatment final : public VolumetricTreatment {
 public:
  static void declare(ComponentDeclaration& d) {
    d.summary("Nodally averaged dilatation (an F-bar scheme): each integration point uses F_bar = (J_bar / J)^(1/3) F "
              "with J averaged over the tets around each node; removes the volumetric locking of nearly "
              "incompressible materials under confinement.");
  }
  explicit NodalAverageTreatment(const Parameters&) {}

  void setup(const ForceKernel& kernel) override {
    const Discretisation& model = kernel.discretisation();
    const auto nodes = static_cast<std::size_t>(model.node_count());
    const auto points = static_cast<std::size_t>(model.points().count());
    const auto& tets = model.mesh().tets;
    const auto& ip_tet = model.points().tets;
    const auto& weight = model.points().weights;
    // In point order, so every node sums its points in the same order whatever the thread count.
    node_points_ = transpose_rows(static_cast<Index>(points), static_cast<Index>(nodes), [&](Index ip, auto&& add) {
      for (Index v : tets[ip_tet[ip]]) add(v);
    });
    node_weight_.assign(nodes, 0.0);
    for (std::size_t node = 0; node < nodes; ++node)
      for (std::int64_t k = node_points_.offsets[node]; k < node_points_.offsets[node + 1]; ++k)
        node_weight_[node] += weight[node_points_.nodes[k]];
    for (double& w : node_weight_)
      if (!(w > 0.0)) w = 1.0;  // a vertex of no tet: never read
    F_.resize(points);
    cofactor_.resize(points);
    J_.resize(points);
    J_bar_.resize(points);
    pressure_.resize(points);
    stress_.resize(points);
    node_value_.resize(nodes);
    first_bad_.resize(static_cast<std::size_t>(model.team().size()));
  }

  // E = sum_q w_q W(F_bar_q), F_bar = r F with r = (J_bar / J)^(1/3), so det F_bar = J_bar. Its gradient has a
  // local part, P_bar : dF_bar/dF at fixed J_bar = r (P_bar - (P_bar : F) F^-T / 3), and a part through every
  // J_bar: dW/dJ_bar = (P_bar : F_bar) / (3 J_bar) =: pi_q / w_q, and dJ_bar_q / dF_p = sum over the vertices I
  // shared by q's and p's tets of (1/4) w_p / W_I times J_p F_p^-T. Summed over q: point p carries the extra
  // stress w_p (sum over its tet's vertices I of Pi_I) J_p F_p^-T with Pi_I = (1/4) sum_q pi_q / W_I.
  Index internal_forces(const ForceKernel& kernel, std::span<const double> u, std::span<double> f) override {
    return internal_forces(kernel, u, f, kernel.discretisation().points().every());
  }

  bool sums_over_ranges() const override { return true; }
  std::vector<PointRange> points_read(const ForceKernel& kernel, std::span<const PointRange> ranges) override {
    return region_of(kernel.discretisation(), ranges).far;
  }

  Index internal_forces(const ForceKernel& kernel, std::span<const double> u, std::span<double> f,
                        std::span<const PointRange> ranges) override {
    const Discretisation& model = kernel.discretisation();
    const Region& region = region_of(model, ranges);
    if (const Index bad = averaged_dilatation(kernel, u, region); bad >= 0) return bad;
    const auto& weight = model.points().weights;
    const int threads = model.team().size();
    model.team().run([&](int thread) {
      Index& thread_bad = first_bad_[static_cast<std::size_t>(thread)];
      thread_bad = kNone;
      ThreadTeam::for_each_piece_of_share(region.near, thread, threads,
                              [&](Index begin, Index end) { local_stresses(model, begin, end, thread_bad); });
      model.team().barrier();
      average_at_nodes(model, pressure_, /*weighted=*/false, region.own_vertices, thread);
      model.team().barrier();
      const auto& tets = model.mesh().tets;
      const auto& ip_tet = model.points().tets;
      ThreadTeam::for_each_piece_of_share(region.own, thread, threads, [&](Index begin, Index end) {
        for (Index ip = begin; ip < end; ++ip) {
          const auto& tet = tets[ip_tet[ip]];
          const double pressure = node_value_[tet[0]] + node_value_[tet[1]] + node_value_[tet[2]] + node_value_[tet[3]];
          stress_[ip] += (weight[ip] * pressure) * cofactor_[ip];
        }
      });
    });
    const Index bad = *std::min_element(first_bad_.begin(), first_bad_.end());
    if (bad != kNone) return bad;
    kernel.scatter_stresses(stress_, f, region.own);
    return -1;
  }

  Index stress_deformation_gradients(const ForceKernel& kernel, std::span<const double> u, std::span<Mat3> F) override {
    const Discretisation& model = kernel.discretisation();
    if (const Index bad = averaged_dilatation(kernel, u, region_of(model, model.points().every())); bad >= 0)
      return bad;
    for (std::size_t ip = 0; ip < F.size(); ++ip) F[ip] = std::cbrt(J_bar_[ip] / J_[ip]) * F_[ip];
    return -1;
  }

  double strain_energy(const ForceKernel& kernel, std::span<const double> u) override {
    const Discretisation& model = kernel.discretisation();
    if (averaged_dilatation(kernel, u, region_of(model, model.points().every())) >= 0)
      return std::numeric_limits<double>::quiet_NaN();
    double energy = 0.0;
    for (Index ip = 0; ip < model.points().count(); ++ip)
      energy += model.points().weights[ip] * model.material(ip).energy(std::cbrt(J_bar_[ip] / J_[ip]) * F_[ip]);
    return energy;
  }

 private:
  static constexpr Index kNone = std::numeric_limits<Index>::max();

  // What the forces of some points (`own`) need: their stresses need Pi at their tets' vertices (`own_vertices`),
  // which sums the pressures of every point around those vertices (`near`, the own points among them); those
  // pressures need J_bar at the near points, the average of J at their tets' vertices (`near_vertices`), which sums
  // J over every point around them (`far`). Each sum runs over all of a node's points in point order, as for the
  // whole model, so a point's stress does not depend on which ranges it is computed with.
  struct Region {
    std::vector<PointRange> own, near, far;
    std::vector<Index> own_vertices, near_vertices;
  };

  const Region& region_of(const Discretisation& model, std::span<const PointRange> ranges) {
    for (const auto& [key, region] : regions_)
      if (std::equal(key.begin(), key.end(), ranges.begin(), ranges.end())) return region;
    if (regions_.size() >= 4) regions_.clear();  // an engine uses one or two lists of ranges, fixed for the run
    const auto& tets = model.mesh().tets;
    const auto& ip_tet = model.points().tets;
    const auto points = static_cast<std::size_t>(model.points().count());
    const auto nodes = static_cast<std::size_t>(model.node_count());
    Region region;
    region.own.assign(ranges.begin(), ranges.end());
    // The vertices of the marked points' tets, then every point around those vertices.
    const auto vertices_of = [&](const std::vector<char>& point_marked) {
      std::vector<char> node_marked(nodes, 0);
      for (std::size_t ip = 0; ip < points; ++ip)
        if (point_marked[ip])
          for (const Index v : tets[ip_tet[ip]]) node_marked[static_cast<std::size_t>(v)] = 1;
      std::vector<Index> list;
      for (std::size_t v = 0; v < nodes; ++v)
        if (node_marked[v]) list.push_back(static_cast<Index>(v));
      return list;
    };
    const auto points_around = [&](const std::vector<Index>& vertices) {
      std::vector<char> marked(points, 0);
      for (const Index v : vertices)
        for (std::int64_t k = node_points_.offsets[v]; k < node_points_.offsets[v + 1]; ++k)
          marked[static_cast<std::size_t>(node_points_.nodes[k])] = 1;
      return marked;
    };
    std::vector<char> own(points, 0);
    for (const PointRange& range : ranges) std::fill(own.begin() + range.first, own.begin() + range.second, 1);
    region.own_vertices = vertices_of(own);
    const std::vector<char> near = points_around(region.own_vertices);
    region.near = as_ranges(near);
    region.near_vertices = vertices_of(near);
    region.far = as_ranges(points_around(region.near_vertices));
    regions_.emplace_back(std::vector<PointRange>(ranges.begin(), ranges.end()), std::move(region));
    return regions_.back().second;
  }

  static std::vector<PointRange> as_ranges(const std::vector<char>& marked) {
    std::vector<PointRange> out;
    for (std::size_t ip = 0; ip < marked.size(); ++ip) {
      if (!marked[ip]) continue;
      if (!out.empty() && out.back().second == static_cast<Index>(ip))
        ++out.back().second;
      else
        out.emplace_back(static_cast<Index>(ip), static_cast<Index>(ip) + 1);
    }
    return out;
  }

  // The local part of each point's stress and its pressure (see internal_forces) for points begin .. end - 1,
  // the material law called on batches of consecutive points with one material (its vectorised stress_batch).
  void local_stresses(const Discretisation& model, Index begin, Index end, Index& first_bad) {
    const auto& weight = model.points().weights;
    StressBatch batch{};
    double r[StressBatch::kCapacity];
    for (Index first = begin; first < end; first += batch.count) {
      const Material& material = model.material(first);
      int count = 1;
      while (count < StressBatch::kCapacity && first + count < end && &model.material(first + count) == &material)
        ++count;
      batch.count = count;
      for (int p = 0; p < StressBatch::kCapacity; ++p) {
        r[p] = p < count ? std::cbrt(J_bar_[first + p] / J_[first + p]) : 1.0;
        const Mat3 F_bar = p < count ? Mat3(r[p] * F_[first + p]) : Mat3::Identity();  // spare lanes: F = I
        batch.set_deformation_gradient(p, F_bar);
      }
      material.stress_batch(batch);
      for (int p = 0; p < count; ++p) {
        const Index ip = first + p;
        if (!batch.admissible[p]) {
          first_bad = std::min(first_bad, ip);
          pressure_[ip] = 0.0;
          stress_[ip].setZero();
          continue;
        }
        const Mat3 S = batch.stress(p);
        const Mat3& F = F_[ip];
        const Mat3 F_bar = r[p] * F;
        const Mat3 P_bar = F_bar * S;
        const Mat3 F_inverse_transpose = cofactor_[ip] / J_[ip];
        stress_[ip] = (weight[ip] * r[p]) * (P_bar - (P_bar.cwiseProduct(F).sum() / 3.0) * F_inverse_transpose);
        pressure_[ip] = weight[ip] * P_bar.cwiseProduct(F_bar).sum() / (3.0 * J_bar_[ip]);
      }
    }
  }

  // F, J and J F^-T at the region's far points, J_bar at its near points; -1, or the first inadmissible point.
  Index averaged_dilatation(const ForceKernel& kernel, std::span<const double> u, const Region& region) {
    const Discretisation& model = kernel.discretisation();
    if (const Index bad = kernel.deformation_gradients(u, F_, region.far); bad >= 0) return bad;
    const int threads = model.team().size();
    model.team().run([&](int thread) {
      ThreadTeam::for_each_piece_of_share(region.far, thread, threads, [&](Index begin, Index end) {
        for (Index ip = begin; ip < end; ++ip) {
          J_[ip] = F_[ip].determinant();
          cofactor_[ip] = J_[ip] * F_[ip].inverse().transpose();
        }
      });
      model.team().barrier();
      average_at_nodes(model, J_, /*weighted=*/true, region.near_vertices, thread);
      model.team().barrier();
      const auto& tets = model.mesh().tets;
      const auto& ip_tet = model.points().tets;
      ThreadTeam::for_each_piece_of_share(region.near, thread, threads, [&](Index begin, Index end) {
        for (Index ip = begin; ip < end; ++ip) {
          const auto& tet = tets[ip_tet[ip]];
          J_bar_[ip] = 0.25 * (node_value_[tet[0]] + node_value_[tet[1]] + node_value_[tet[2]] + node_value_[tet[3]]);
        }
      });
    });
    return -1;
  }

  // node_value_[I] = sum over the points p around I of (w_p if weighted) value_p / W_I (times 1/4 if not
  // weighted: each point's value is spread over its tet's four vertices), for thread `thread`'s share of `nodes`.
  void average_at_nodes(const Discretisation& model, const std::vector<double>& value, bool weighted,
                        const std::vector<Index>& nodes, int thread) {
    const auto& weight = model.points().weights;
    const auto [begin, end] = ThreadTeam::share(static_cast<std::int64_t>(nodes.size()), thread, model.team().size());
    for (auto k = begin; k < end; ++k) {
      const Index node = nodes[static_cast<std::size_t>(k)];
      double sum = 0.0;
      for (std::int64_t e = node_points_.offsets[node]; e < node_points_.offsets[node + 1]; ++e) {
        const Index ip = node_points_.nodes[e];
        sum += weighted ? weight[ip] * value[ip] : value[ip];
      }
      node_value_[node] = (weighted ? 1.0 : 0.25) * sum / node_weight_[node];
    }
  }

  SupportRows node_points_;           // node -> the integration points whose tet has it as a vertex (no values)
  std::vector<double> node_weight_;  // sum of those points' weights
  std::vector<Mat3> F_, cofactor_, stress_;  // per integration point
  std::vector<double> J_, J_bar_, pressure_, node_value_;
  std::vector<Index> first_bad_;                                     // per thread of the discretisation's team
  std::vector<std::pair<std::vector<PointRange>, Region>> regions_;  // by the ranges they serve
};

}  // namespace mtled

MTLED_PLUGIN(mtled::VolumetricTreatment, mtled::NodalAverageTreatment)
