#include "mtled/analysis/mls_transfer.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "mtled/parameters.hpp"

namespace mtled {

namespace {

constexpr std::size_t kNeighbours = 10;

std::shared_ptr<ShapeFunctions> linear_mls(PluginCatalog& catalog) {
  const ComponentDeclaration& declaration = catalog.load(Category::shape_function, "mls", "MLS transfer");
  std::vector<Problem> problems;
  const Parameters parameters = validate_parameters(declaration, json::object(), "", problems);
  return catalog.create<ShapeFunctions>("mls", parameters);
}

}  // namespace

MlsTransfer::MlsTransfer(const std::vector<Vec3>& nodes, PluginCatalog& catalog)
    : nodes_(nodes), mls_(linear_mls(catalog)), search_(nodes), radius_(nodes.size()) {
#pragma omp parallel
  {
    std::vector<Index> nearest;
#pragma omp for schedule(static)
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      search_.nearest(nodes[i], kNeighbours + 1, nearest);  // the node itself comes first
      radius_[i] = 1.3 * (nodes[static_cast<std::size_t>(nearest.back())] - nodes[i]).norm();
    }
  }
  fill_bins();
}

void MlsTransfer::fill_bins() {
  if (nodes_.empty()) return;
  if (nodes_.size() >= std::numeric_limits<std::uint32_t>::max())
    throw std::invalid_argument("MlsTransfer: 2^32 nodes or more");
  // Bins of a third of the median support radius, over the box the supports cover, at most about 2^24 of them; a bin
  // lists the nodes whose support sphere reaches it, about 1.5 times the nodes a point's support holds.
  std::vector<double> sorted = radius_;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2), sorted.end());
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    lo = lo.cwiseMin(nodes_[i] - Vec3::Constant(radius_[i]));
    hi = hi.cwiseMax(nodes_[i] + Vec3::Constant(radius_[i]));
  }
  bin_size_ = std::max(sorted[sorted.size() / 2] / 3.0, std::cbrt((hi - lo).prod() / double(1 << 24)));
  if (!(bin_size_ > 0.0)) bin_size_ = std::max(1e-12, (hi - lo).maxCoeff());
  bins_origin_ = lo;
  for (int a = 0; a < 3; ++a) bins_[static_cast<std::size_t>(a)] = std::int64_t((hi[a] - lo[a]) / bin_size_) + 1;
  // Whether node i's support sphere reaches the bin: the distance from the node to the bin's nearest point.
  const auto reaches = [&](std::size_t i, const std::array<std::int64_t, 3>& bin) {
    double distance2 = 0.0;
    for (std::size_t a = 0; a < 3; ++a) {
      const double low = lo[static_cast<Index>(a)] + double(bin[a]) * bin_size_;
      const double gap =
          std::max({low - nodes_[i][static_cast<Index>(a)], 0.0, nodes_[i][static_cast<Index>(a)] - (low + bin_size_)});
      distance2 += gap * gap;
    }
    return distance2 <= radius_[i] * radius_[i];
  };
  // visit(b) for each bin b in layers k_first..k_last that node i's support reaches.
  const auto each_bin = [&](std::size_t i, std::int64_t k_first, std::int64_t k_last, auto&& visit) {
    std::array<std::int64_t, 3> first{}, last{};
    for (std::size_t a = 0; a < 3; ++a) {
      const auto axis = static_cast<Index>(a);
      first[a] = std::max<std::int64_t>(0, std::int64_t((nodes_[i][axis] - radius_[i] - lo[axis]) / bin_size_));
      last[a] = std::min(bins_[a] - 1, std::int64_t((nodes_[i][axis] + radius_[i] - lo[axis]) / bin_size_));
    }
    for (std::int64_t k = std::max(first[2], k_first); k <= std::min(last[2], k_last); ++k)
      for (std::int64_t j = first[1]; j <= last[1]; ++j)
        for (std::int64_t b = first[0]; b <= last[0]; ++b)
          if (reaches(i, {b, j, k})) visit(b + bins_[0] * (j + bins_[1] * k));
  };
  pack_nodes();
  const std::vector<Index>& order = packed_node_;
  // Counted, then listed, by threads that each own a range of bin layers and go through the nodes in packed order: a
  // bin is written by one thread only and lists its nodes in packed order, whatever the number of threads.
  const auto by_layers = [&](auto&& visit_layers) {
#pragma omp parallel
    {
#ifdef _OPENMP
      const auto threads = std::int64_t(omp_get_num_threads()), thread = std::int64_t(omp_get_thread_num());
#else
      const std::int64_t threads = 1, thread = 0;
#endif
      visit_layers(bins_[2] * thread / threads, bins_[2] * (thread + 1) / threads - 1);
    }
  };
  bin_start_.assign(static_cast<std::size_t>(bins_[0] * bins_[1] * bins_[2] + 1), 0);
  by_layers([&](std::int64_t k_first, std::int64_t k_last) {
    for (const Index i : order)
      each_bin(std::size_t(i), k_first, k_last, [&](std::int64_t b) { ++bin_start_[std::size_t(b) + 1]; });
  });
  for (std::size_t b = 1; b < bin_start_.size(); ++b) bin_start_[b] += bin_start_[b - 1];
  bin_nodes_.resize(static_cast<std::size_t>(bin_start_.back()));
  std::vector<std::int64_t> next(bin_start_.begin(), bin_start_.end() - 1);
  by_layers([&](std::int64_t k_first, std::int64_t k_last) {
    for (std::size_t p = 0; p < order.size(); ++p)
      each_bin(std::size_t(order[p]), k_first, k_last, [&](std::int64_t b) {
        bin_nodes_[std::size_t(next[std::size_t(b)]++)] = static_cast<std::uint32_t>(p);
      });
  });
}

// The nodes packed (position, support radius) in the order of their own bins, so that a bin's list reads nearby memory.
void MlsTransfer::pack_nodes() {
  std::vector<Index> order(nodes_.size());
  std::vector<std::int64_t> home(nodes_.size());
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    order[i] = static_cast<Index>(i);
    home[i] = bin_of(nodes_[i]);
  }
  std::stable_sort(order.begin(), order.end(),
                   [&](Index a, Index b) { return home[std::size_t(a)] < home[std::size_t(b)]; });
  packed_.resize(nodes_.size());
  for (std::size_t p = 0; p < order.size(); ++p) {
    const auto i = static_cast<std::size_t>(order[p]);
    packed_[p] << nodes_[i], radius_[i];
  }
  packed_node_ = std::move(order);
}

std::int64_t MlsTransfer::bin_of(const Vec3& x) const {
  std::int64_t index[3];
  for (int a = 0; a < 3; ++a) {
    const double q = (x[a] - bins_origin_[a]) / bin_size_;
    if (!(q >= 0.0 && q < double(bins_[static_cast<std::size_t>(a)]))) return -1;
    index[a] = std::int64_t(q);
  }
  return index[0] + bins_[0] * (index[1] + bins_[1] * index[2]);
}

Vec3 MlsTransfer::at(const Vec3& x, const std::vector<Vec3>& values) const { return evaluate(x, values, nullptr); }

Vec3 MlsTransfer::at(const Vec3& x, const std::vector<Vec3>& values, Mat3& gradient) const {
  return evaluate(x, values, &gradient);
}

Vec3 MlsTransfer::evaluate(const Vec3& x, const std::vector<Vec3>& values, Mat3* gradient) const {
  // Per-thread scratch: the field on an image grid calls this millions of times.
  struct Scratch {
    std::vector<Vec3> coordinates, node_values;
    std::vector<double> radii;
    std::vector<Index> nearest;
  };
  thread_local Scratch scratch;
  auto& [coordinates, node_values, radii, nearest] = scratch;
  std::size_t count = 0;
  if (const std::int64_t b = bin_of(x); b >= 0) {
    const std::uint32_t* listed = bin_nodes_.data() + bin_start_[std::size_t(b)];
    const std::uint32_t* end = bin_nodes_.data() + bin_start_[std::size_t(b) + 1];
    // Room for every listed node, written through plain pointers: no size bookkeeping per node.
    const auto listed_count = static_cast<std::size_t>(end - listed);
    if (coordinates.size() < listed_count) {
      coordinates.resize(listed_count);
      node_values.resize(listed_count);
      radii.resize(listed_count);
    }
    Vec3* to_coordinates = coordinates.data();
    Vec3* to_values = node_values.data();
    double* to_radii = radii.data();
    // Every listed node is written and the count advances past those whose support holds x: about half of them do,
    // which a branch would guess wrong half the time.
    for (; listed != end; ++listed) {
      const auto p = static_cast<std::size_t>(*listed);
      const Eigen::Vector4d& node = packed_[p];
      const double distance2 = (node.head<3>() - x).squaredNorm();
      const double radius2 = node[3] * node[3];
      to_coordinates[count] = node.head<3>();
      to_values[count] = values[static_cast<std::size_t>(packed_node_[p])];
      // As below, at least 1.01 |x_I - x|.
      to_radii[count] = 1.0201 * distance2 > radius2 ? 1.01 * std::sqrt(distance2) : node[3];
      count += static_cast<std::size_t>(std::signbit(distance2 - radius2));  // distance2 < radius2, with no branch
    }
  }
  if (static_cast<int>(count) < mls_->minimum_support_size()) {
    search_.nearest(x, 2 * kNeighbours, nearest);  // outside the cloud (a coarser boundary): the nearest nodes
    coordinates.resize(std::max(coordinates.size(), nearest.size()));
    node_values.resize(coordinates.size());
    radii.resize(coordinates.size());
    count = nearest.size();
    for (std::size_t k = 0; k < count; ++k) {
      const auto node = static_cast<std::size_t>(nearest[k]);
      coordinates[k] = nodes_[node];
      node_values[k] = values[node];
      radii[k] = std::max(radius_[node], 1.01 * (nodes_[node] - x).norm());
    }
  }
  Vec3 out;
  if (!mls_->interpolate(x, std::span(coordinates).first(count), std::span(radii).first(count),
                         std::span(node_values).first(count), out, gradient)
           .ok)
    throw std::runtime_error(
        fmt::format("cannot interpolate at ({:g}, {:g}, {:g}): degenerate neighbourhood", x[0], x[1], x[2]));
  return out;
}

}  // namespace mtled
