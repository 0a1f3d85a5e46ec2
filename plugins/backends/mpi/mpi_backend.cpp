// `mpi`: one scene on the processes of an MPI run (mpirun -np N mtled run SCENE; the command line selects this
// backend when it runs on more than one rank). The background cells are partitioned by METIS (the tets' dual graph,
// faces shared); each rank computes the internal forces of its cells' integration points on its threads, sends its
// contributions to the nodes other ranks own (the points at the partition boundary first, the interior computed
// while those travel) and sums those it receives for its own nodes in rank order. It then updates its own nodes: the
// prediction, its part of the constraint projection's products and the step's sums, each global value reduced in rank
// order so that every rank holds the same bits; last, every rank gathers the new displacement of every node, which
// the drivers, the monitors and the next force evaluation read. The constraint solve, the drivers and the monitors run
// on every rank on that same state, and only rank 0 writes. docs/mpi.md gives the design, its costs and what it does
// not distribute yet.
#include <mpi.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <numeric>
#include <stdexcept>

#include "mesh_partition.hpp"
#include "mtled/cpu_engine.hpp"
#include "mtled/constraints.hpp"
#include "mtled/errors.hpp"
#include "mtled/explicit_update.hpp"
#include "mtled/log.hpp"
#include "mtled/model.hpp"
#include "mtled/plugin.hpp"

namespace mtled {

namespace {

using Clock = std::chrono::steady_clock;

// Every rank's value of a per-rank count, on every rank.
std::vector<std::int64_t> all_ranks(std::int64_t value, int ranks) {
  std::vector<std::int64_t> out(static_cast<std::size_t>(ranks));
  MPI_Allgather(&value, 1, MPI_INT64_T, out.data(), 1, MPI_INT64_T, MPI_COMM_WORLD);
  return out;
}

}  // namespace

class MpiBackend final : public CpuEngine {
 public:
  static void declare(ComponentDeclaration& d) {
    d.summary(
        "The processes of an MPI run (mpirun -np N mtled run SCENE, chosen by the command line on more than one "
        "rank): METIS partitions the background cells, each rank computes its cells' integration points on its "
        "threads (--threads per rank) and the ranks exchange their contributions to each other's nodes every force "
        "evaluation; each rank updates its own nodes and the ranks then gather the new displacements; the constraint "
        "solve, the drivers and the monitors run on every rank on the same state, and rank 0 writes the outputs.");
  }
  explicit MpiBackend(const Parameters& parameters) {
    int started = 0;
    MPI_Initialized(&started);
    if (!started)
      throw InputError(parameters.pointer("type"),
                       "the mpi backend runs under an MPI launcher: mpirun -np N mtled run SCENE (it is chosen there "
                       "without this block); to run on one process, leave out /backend");
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &ranks_);
  }

  std::vector<int> cell_groups(const TetMesh& mesh) override {
    // Rank 0 partitions and tells the others, so every rank holds the same partition whatever METIS does.
    MeshPartition partition = rank_ == 0 ? partition_mesh(mesh, ranks_) : MeshPartition{};
    std::vector<int>& tet_part = partition.tet_part;
    tet_part.resize(mesh.tets.size());
    owner_ = std::move(partition.node_part);
    owner_.resize(static_cast<std::size_t>(mesh.node_count()));
    MPI_Bcast(tet_part.data(), static_cast<int>(tet_part.size()), MPI_INT, 0, MPI_COMM_WORLD);
    MPI_Bcast(owner_.data(), static_cast<int>(owner_.size()), MPI_INT, 0, MPI_COMM_WORLD);
    // A rank's points in kLayers + 1 groups, the nearest its part's boundary first: its boundary points, computed
    // before its contributions are sent, are then mostly one range at the front.
    partition.node_part = owner_;
    const std::vector<int> layer = boundary_layers(mesh, partition, kLayers);
    std::vector<int> groups(tet_part.size());
    for (std::size_t t = 0; t < groups.size(); ++t) groups[t] = tet_part[t] * (kLayers + 1) + layer[t];
    return groups;
  }

  void setup(const Model& model) override {
    CpuEngine::setup(model);
    // A volumetric treatment that sums over ranges of points computes its own points' contributions (their averages
    // reach a few layers of other ranks' points, which it evaluates too); one that does not is computed whole on
    // every rank (the same answer, no speed-up).
    const VolumetricTreatment* treatment = model.volumetric_treatment();
    whole_on_every_rank_ = treatment != nullptr && !treatment->sums_over_ranges();
    if (whole_on_every_rank_ && rank_ == 0)
      log().warn("mpi: the volumetric treatment's forces are computed whole on every rank (not divided between "
                 "the {} ranks): it does not sum over ranges of points", ranks_);
    const Index n_points = model.integration_point_count();
    // This rank's groups (cell_groups); groups past the model's last one are empty.
    const auto group_start = [&](int group) {
      return group < model.group_count() ? model.group_points(group).first : n_points;
    };
    points_ = {group_start(rank_ * (kLayers + 1)), group_start((rank_ + 1) * (kLayers + 1))};
    build_exchange(model);
    split_points(model);
    record_partition(model);
  }

  json describe() const override {
    json out = CpuEngine::describe();
    out["type"] = "mpi";
    out["ranks"] = ranks_;
    out["threads_per_rank"] = out["threads"];
    out.erase("threads");
    out["partition"] = partition_;
    if (whole_on_every_rank_) out["forces"] = "whole on every rank (volumetric treatment)";
    out["exchange_s"] = exchange_s_;  // rank 0's: sends, receives, its sums, the gathers and the step's reductions
    return out;
  }

  // The step on this rank's own nodes (CpuEngine's state: u_ and u_previous_ hold every node, the other vectors are
  // right at the rank's own nodes only).
  Index evaluate_forces(IncrementSums* sums) override {
    f_previous_.swap(f_);
    const std::int64_t bad = timed([&] { return owned_forces(u_, f_); });
    IncrementSums mine;
    if (sums != nullptr)
      for (const Index i : owned_)
        for (std::size_t d = 3 * static_cast<std::size_t>(i); d < 3 * static_cast<std::size_t>(i) + 3; ++d)
          add_increment_sums(d, u_, u_previous_, f_, f_previous_, mass_, mine);
    // One exchange for both: the first inadmissible point (an index, exact as a double) and the sums.
    const auto start = Clock::now();
    const double values[] = {static_cast<double>(bad), mine.stiffness, mine.inertia};
    const std::vector<double>& all = from_every_rank(values);
    exchange_s_ += seconds_since(start);
    const auto none = static_cast<double>(kNoneIndex);  // 2^63: above any point index, which a double holds exactly
    double first_bad = none;
    IncrementSums total;
    for (int q = 0; q < ranks_; ++q) {
      const double* v = &all[3 * static_cast<std::size_t>(q)];
      first_bad = std::min(first_bad, v[0]);
      total.stiffness += v[1];
      total.inertia += v[2];
    }
    if (first_bad != none) return static_cast<Index>(first_bad);
    if (sums != nullptr) *sums = total;
    return -1;
  }

  std::int64_t predict(double alpha, double beta, std::span<const double> f_ext) override {
    const ScopeTimer timer(update_s_);
    const double* external = f_ext.empty() ? nullptr : f_ext.data();
    std::int64_t first_bad = kNoneIndex;
    for (const Index node : owned_) {
      const auto i = static_cast<std::size_t>(node);
      explicit_update(u_.data(), u_previous_.data(), external, f_.data(), mass_.data(), alpha, beta,
                      prediction_.data(), i, i + 1);
      for (std::size_t d = 3 * i; d < 3 * i + 3; ++d) {
        free_[d] = prediction_[d];
        if (!std::isfinite(prediction_[d])) first_bad = std::min(first_bad, static_cast<std::int64_t>(d));
      }
    }
    MPI_Allreduce(MPI_IN_PLACE, &first_bad, 1, MPI_INT64_T, MPI_MIN, MPI_COMM_WORLD);
    return first_bad == kNoneIndex ? -1 : first_bad;
  }

  void prediction(std::span<double> out) override {
    gather_owned(prediction_);
    std::copy(prediction_.begin(), prediction_.end(), out.begin());
  }

  // out = Phi u~: each rank's rows summed over the entries at its own nodes, the ranks' sums added in rank order.
  void constrained_values(const ConstraintBlock& block, std::vector<double>& out) override {
    const ScopeTimer timer(update_s_);
    const OwnEntries& own = own_entries(block);
    const std::size_t k = block.components.size();
    std::vector<double>& mine = rank_products_;
    mine.assign(static_cast<std::size_t>(block.rows) * k, 0.0);
    for (std::size_t r = 0; r < static_cast<std::size_t>(block.rows); ++r) {
      double sum[3] = {0.0, 0.0, 0.0};
      for (std::int64_t i = own.row_offsets[r]; i < own.row_offsets[r + 1]; ++i) {
        const std::int64_t e = own.row_entries[static_cast<std::size_t>(i)];
        const double* v = &prediction_[3 * static_cast<std::size_t>(block.row_nodes[e])];
        for (std::size_t j = 0; j < k; ++j) sum[j] += block.row_values[e] * v[block.components[j]];
      }
      for (std::size_t j = 0; j < k; ++j) mine[k * r + j] = sum[j];
    }
    const auto start = Clock::now();
    const std::vector<double>& all = from_every_rank(mine);
    exchange_s_ += seconds_since(start);
    out.assign(mine.size(), 0.0);
    for (int q = 0; q < ranks_; ++q)
      for (std::size_t i = 0; i < out.size(); ++i) out[i] += all[static_cast<std::size_t>(q) * out.size() + i];
  }

  // u~ += M^-1 Phi^T y at the rank's own nodes (each node's sum as on one process).
  void add_correction(const ConstraintBlock& block, const std::vector<double>& y) override {
    const ScopeTimer timer(update_s_);
    const std::size_t k = block.components.size();
    for (const std::size_t n : own_entries(block).nodes) {
      double sum[3] = {0.0, 0.0, 0.0};
      for (std::int64_t e = block.node_offsets[n]; e < block.node_offsets[n + 1]; ++e)
        for (std::size_t j = 0; j < k; ++j)
          sum[j] += block.node_values[e] * y[k * static_cast<std::size_t>(block.node_rows[e]) + j];
      double* v = &prediction_[3 * static_cast<std::size_t>(block.nodes[n])];
      for (std::size_t j = 0; j < k; ++j) v[block.components[j]] += sum[j];
    }
  }

  // The rank's own nodes' sums, combined in rank order; then every rank gathers u_(n+1).
  StepSums commit() override {
    const ScopeTimer timer(update_s_);
    StepSums mine;
    double fastest = 0.0;
    for (const Index node : owned_)
      add_step_sums(static_cast<std::size_t>(node), u_.data(), u_previous_.data(), prediction_.data(), free_.data(),
                    mass_.data(), mine, fastest);
    u_previous_.swap(u_);
    u_.swap(prediction_);
    // The sums travel with the displacements: one exchange.
    const auto start = Clock::now();
    const double values[kStepSumValues] = {mine.largest_increment, mine.largest_displacement, mine.projection_energy,
                                           mine.kinetic_product,   fastest,  static_cast<double>(mine.fastest_node)};
    gather_owned(u_, values);
    exchange_s_ += seconds_since(start);
    StepSums sums;
    double fastest_energy = 0.0;
    for (int q = 0; q < ranks_; ++q) {
      const double* v = rank_extra(q);
      combine_step_sums(StepSums{v[0], v[1], v[2], v[3], static_cast<Index>(v[5])}, v[4], sums, fastest_energy);
    }
    return sums;
  }

 protected:
  // f at every node (the monitors' evaluations on host vectors): this rank's own sums, then gathered.
  Index forces(std::span<const double> u, std::span<double> f) override {
    std::int64_t first_bad = owned_forces(u, f);
    const auto start = Clock::now();
    MPI_Allreduce(MPI_IN_PLACE, &first_bad, 1, MPI_INT64_T, MPI_MIN, MPI_COMM_WORLD);
    gather_owned(f);
    exchange_s_ += seconds_since(start);
    return first_bad == kNoneIndex ? -1 : static_cast<Index>(first_bad);
  }

 private:
  // f right at this rank's own nodes: the points whose supports reach other ranks' nodes first, their contributions
  // sent; the interior points while those travel (the kernel lets MPI move them every few thousand points); then the
  // rank's own sums. With a treatment computed whole on every rank, f is right at every node. Returns this rank's
  // lowest-numbered inadmissible point, or kNoneIndex: the callers reduce it with their own exchange.
  std::int64_t owned_forces(std::span<const double> u, std::span<double> f) {
    std::int64_t first_bad = kNoneIndex;
    const auto note = [&](Index bad) {
      if (bad >= 0) first_bad = std::min<std::int64_t>(first_bad, bad);
    };
    if (whole_on_every_rank_) {
      note(model().internal_forces(u, f));
      return first_bad;
    }
    auto start = Clock::now();
    post_receives();
    exchange_s_ += seconds_since(start);
    note(model().internal_forces(u, boundary_f_, boundary_ranges_));
    start = Clock::now();
    send_contributions();
    exchange_s_ += seconds_since(start);
    note(model().internal_forces(u, f, interior_ranges_, progress_));
    start = Clock::now();
    MPI_Waitall(static_cast<int>(requests_.size()), requests_.data(), MPI_STATUSES_IGNORE);
    sum_owned(f);
    exchange_s_ += seconds_since(start);
    return first_bad;
  }

  // A constraint block's entries at this rank's own nodes: by row (indices into row_nodes) and the positions in
  // `nodes` of its own nodes. Kept per block until the block's revision changes.
  struct OwnEntries {
    const ConstraintBlock* block = nullptr;
    long revision = -1;
    std::vector<std::int64_t> row_offsets, row_entries;
    std::vector<std::size_t> nodes;
  };
  const OwnEntries& own_entries(const ConstraintBlock& block) {
    auto it = std::find_if(own_entries_.begin(), own_entries_.end(),
                           [&](const OwnEntries& o) { return o.block == &block; });
    if (it == own_entries_.end()) it = own_entries_.emplace(own_entries_.end());
    if (it->revision == block.revision) return *it;
    OwnEntries& own = *it;
    own.block = &block;
    own.revision = block.revision;
    own.row_offsets.assign(1, 0);
    own.row_entries.clear();
    for (std::size_t r = 0; r < static_cast<std::size_t>(block.rows); ++r) {
      for (std::int64_t e = block.row_offsets[r]; e < block.row_offsets[r + 1]; ++e)
        if (owner_[static_cast<std::size_t>(block.row_nodes[e])] == rank_) own.row_entries.push_back(e);
      own.row_offsets.push_back(static_cast<std::int64_t>(own.row_entries.size()));
    }
    own.nodes.clear();
    for (std::size_t n = 0; n < block.nodes.size(); ++n)
      if (owner_[static_cast<std::size_t>(block.nodes[n])] == rank_) own.nodes.push_back(n);
    return own;
  }

  // Every rank's `mine` (the same length on every rank), rank after rank, on every rank (valid until the next call).
  const std::vector<double>& from_every_rank(std::span<const double> mine) {
    every_rank_.resize(mine.size() * static_cast<std::size_t>(ranks_));  // kept: no allocation in the time step
    MPI_Allgather(mine.data(), static_cast<int>(mine.size()), MPI_DOUBLE, every_rank_.data(),
                  static_cast<int>(mine.size()), MPI_DOUBLE, MPI_COMM_WORLD);
    return every_rank_;
  }

 private:
  // The lists each force evaluation uses: the nodes this rank's points support that other ranks own (sent), the
  // nodes it owns that other ranks' points support (received, in the sender's order), and every rank's owned nodes
  // in the gathered vector's order.
  void build_exchange(const Model& model) {
    const GradientRows& rows = model.ip_supports();
    const std::size_t nodes = static_cast<std::size_t>(model.node_count());
    std::vector<char> supported(nodes, 0);
    for (Index p = points_.first; p < points_.second; ++p)
      for (int k = 0; k < rows.size(p); ++k) supported[static_cast<std::size_t>(rows.node(p, k))] = 1;
    send_nodes_.assign(static_cast<std::size_t>(ranks_), {});
    for (std::size_t i = 0; i < nodes; ++i)
      if (supported[i] && owner_[i] != rank_) send_nodes_[static_cast<std::size_t>(owner_[i])].push_back(static_cast<Index>(i));
    std::vector<int> send_counts(static_cast<std::size_t>(ranks_)), receive_counts(static_cast<std::size_t>(ranks_));
    for (int q = 0; q < ranks_; ++q) send_counts[static_cast<std::size_t>(q)] = static_cast<int>(send_nodes_[static_cast<std::size_t>(q)].size());
    MPI_Alltoall(send_counts.data(), 1, MPI_INT, receive_counts.data(), 1, MPI_INT, MPI_COMM_WORLD);
    std::vector<int> send_offsets(static_cast<std::size_t>(ranks_) + 1, 0), receive_offsets(static_cast<std::size_t>(ranks_) + 1, 0);
    std::partial_sum(send_counts.begin(), send_counts.end(), send_offsets.begin() + 1);
    std::partial_sum(receive_counts.begin(), receive_counts.end(), receive_offsets.begin() + 1);
    std::vector<std::int64_t> sent, received(static_cast<std::size_t>(receive_offsets.back()));
    for (const auto& list : send_nodes_) sent.insert(sent.end(), list.begin(), list.end());
    MPI_Alltoallv(sent.data(), send_counts.data(), send_offsets.data(), MPI_INT64_T, received.data(),
                  receive_counts.data(), receive_offsets.data(), MPI_INT64_T, MPI_COMM_WORLD);
    receive_nodes_.assign(static_cast<std::size_t>(ranks_), {});
    for (int q = 0; q < ranks_; ++q)
      receive_nodes_[static_cast<std::size_t>(q)].assign(received.begin() + receive_offsets[static_cast<std::size_t>(q)],
                                                          received.begin() + receive_offsets[static_cast<std::size_t>(q) + 1]);
    // The gathered vector: rank 0's owned nodes in ascending order, then rank 1's, ...
    gather_counts_.assign(static_cast<std::size_t>(ranks_), 0);
    for (const int o : owner_) gather_counts_[static_cast<std::size_t>(o)] += 3;
    gather_offsets_.assign(static_cast<std::size_t>(ranks_), 0);
    std::partial_sum(gather_counts_.begin(), gather_counts_.end() - 1, gather_offsets_.begin() + 1);
    step_gather_counts_ = gather_counts_;
    for (int& count : step_gather_counts_) count += kStepSumValues;
    step_gather_offsets_.assign(static_cast<std::size_t>(ranks_), 0);
    std::partial_sum(step_gather_counts_.begin(), step_gather_counts_.end() - 1, step_gather_offsets_.begin() + 1);
    gather_order_.clear();
    for (int q = 0; q < ranks_; ++q)
      for (std::size_t i = 0; i < nodes; ++i)
        if (owner_[i] == q) gather_order_.push_back(static_cast<Index>(i));
    const auto mine = static_cast<std::size_t>(gather_offsets_[static_cast<std::size_t>(rank_)] / 3);
    owned_.assign(gather_order_.begin() + static_cast<std::ptrdiff_t>(mine),
                  gather_order_.begin() + static_cast<std::ptrdiff_t>(mine) + gather_counts_[static_cast<std::size_t>(rank_)] / 3);
    slot_.assign(nodes, -1);
    for (std::size_t k = 0; k < owned_.size(); ++k) slot_[static_cast<std::size_t>(owned_[k])] = static_cast<Index>(k);
    send_buffer_.resize(static_cast<std::size_t>(ranks_));
    receive_buffer_.resize(static_cast<std::size_t>(ranks_));
    for (int q = 0; q < ranks_; ++q) {
      send_buffer_[static_cast<std::size_t>(q)].resize(3 * send_nodes_[static_cast<std::size_t>(q)].size());
      receive_buffer_[static_cast<std::size_t>(q)].resize(3 * receive_nodes_[static_cast<std::size_t>(q)].size());
    }
    owned_sum_.resize(3 * owned_.size() + kStepSumValues);
    gathered_.resize(3 * nodes + kStepSumValues * static_cast<std::size_t>(ranks_));
    requests_.reserve(2 * static_cast<std::size_t>(ranks_));
  }

  // The boundary points: those whose supports reach a node another rank owns, in blocks of consecutive points
  // (whole blocks keep the kernel's batches long); the rest of the rank's points are its interior.
  void split_points(const Model& model) {
    constexpr Index kBlock = 16;  // two of the kernel's batches (StressBatch::kCapacity)
    const GradientRows& rows = model.ip_supports();
    boundary_ranges_.clear();
    interior_ranges_.clear();
    boundary_points_ = 0;
    // With a volumetric treatment every point goes first: its averages reach past the boundary points, so the
    // interior would evaluate them again.
    const bool all_first = model.volumetric_treatment() != nullptr;
    for (Index block = points_.first; block < points_.second; block += kBlock) {
      const Index end = std::min(block + kBlock, points_.second);
      bool boundary = false;
      for (Index p = block; p < end; ++p) {
        const bool reaches = reaches_another_part(rows, p, owner_, rank_);
        boundary_points_ += reaches ? 1 : 0;
        boundary = boundary || reaches;
      }
      auto& ranges = boundary || all_first ? boundary_ranges_ : interior_ranges_;
      if (!ranges.empty() && ranges.back().second == block)
        ranges.back().second = end;
      else
        ranges.emplace_back(block, end);
    }
    boundary_f_.assign(3 * static_cast<std::size_t>(model.node_count()), 0.0);
  }

  void post_receives() {
    requests_.clear();  // kept: no allocation in the time step
    for (int q = 0; q < ranks_; ++q) {
      auto& in = receive_buffer_[static_cast<std::size_t>(q)];
      if (in.empty()) continue;
      requests_.emplace_back();
      MPI_Irecv(in.data(), static_cast<int>(in.size()), MPI_DOUBLE, q, 0, MPI_COMM_WORLD, &requests_.back());
    }
  }

  // The boundary points' contributions to the nodes each other rank owns.
  void send_contributions() {
    for (int q = 0; q < ranks_; ++q) {
      const auto& list = send_nodes_[static_cast<std::size_t>(q)];
      auto& out = send_buffer_[static_cast<std::size_t>(q)];
      if (list.empty()) continue;
      for (std::size_t k = 0; k < list.size(); ++k)
        for (std::size_t c = 0; c < 3; ++c) out[3 * k + c] = boundary_f_[3 * static_cast<std::size_t>(list[k]) + c];
      requests_.emplace_back();
      MPI_Isend(out.data(), static_cast<int>(out.size()), MPI_DOUBLE, q, 0, MPI_COMM_WORLD, &requests_.back());
    }
  }

  // f holds this rank's interior contributions, boundary_f_ its boundary ones, the receive buffers the other
  // ranks'; afterwards f holds each own node's sum, added in rank order whatever order the messages came in (the same
  // answer on every repeat).
  void sum_owned(std::span<double> f) {
    std::fill(owned_sum_.begin(), owned_sum_.end(), 0.0);
    for (int q = 0; q < ranks_; ++q) {
      if (q == rank_) {
        for (std::size_t k = 0; k < owned_.size(); ++k)
          for (std::size_t c = 0; c < 3; ++c) {
            const std::size_t d = 3 * static_cast<std::size_t>(owned_[k]) + c;
            owned_sum_[3 * k + c] += boundary_f_[d] + f[d];
          }
        continue;
      }
      const auto& list = receive_nodes_[static_cast<std::size_t>(q)];
      const auto& in = receive_buffer_[static_cast<std::size_t>(q)];
      for (std::size_t k = 0; k < list.size(); ++k) {
        const auto s = static_cast<std::size_t>(slot_[static_cast<std::size_t>(list[k])]);
        for (std::size_t c = 0; c < 3; ++c) owned_sum_[3 * s + c] += in[3 * k + c];
      }
    }
    for (std::size_t k = 0; k < owned_.size(); ++k)
      for (std::size_t c = 0; c < 3; ++c) f[3 * static_cast<std::size_t>(owned_[k]) + c] = owned_sum_[3 * k + c];
  }

  // v (3 per node), right at this rank's own nodes, becomes right at every node: each rank's own values gathered,
  // with the step's sums (kStepSumValues) after them when given (every rank's, rank_extra(q), valid until the next
  // gather).
  void gather_owned(std::span<double> v, std::span<const double> step_sums = {}) {
    const std::size_t own = 3 * owned_.size();
    for (std::size_t k = 0; k < owned_.size(); ++k)
      for (std::size_t c = 0; c < 3; ++c) owned_sum_[3 * k + c] = v[3 * static_cast<std::size_t>(owned_[k]) + c];
    std::copy(step_sums.begin(), step_sums.end(), owned_sum_.begin() + static_cast<std::ptrdiff_t>(own));
    const int extra = static_cast<int>(step_sums.size());
    const std::vector<int>& counts = extra > 0 ? step_gather_counts_ : gather_counts_;
    const std::vector<int>& offsets = extra > 0 ? step_gather_offsets_ : gather_offsets_;
    MPI_Allgatherv(owned_sum_.data(), static_cast<int>(own) + extra, MPI_DOUBLE, gathered_.data(), counts.data(),
                   offsets.data(), MPI_DOUBLE, MPI_COMM_WORLD);
    std::size_t k = 0;  // in gather_order_: rank 0's nodes, then rank 1's, ...
    for (int q = 0; q < ranks_; ++q) {
      const double* in = &gathered_[static_cast<std::size_t>(offsets[static_cast<std::size_t>(q)])];
      for (int i = 0; i < gather_counts_[static_cast<std::size_t>(q)]; i += 3, ++k)
        for (std::size_t c = 0; c < 3; ++c)
          v[3 * static_cast<std::size_t>(gather_order_[k]) + c] = in[static_cast<std::size_t>(i) + c];
    }
  }
  // Rank q's step sums from the last gather_owned that carried them.
  const double* rank_extra(int q) const {
    const auto i = static_cast<std::size_t>(q);
    return &gathered_[static_cast<std::size_t>(step_gather_offsets_[i] + gather_counts_[i])];
  }

  static double seconds_since(Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
  }

  // summary.json's "partition": points, owned and ghost nodes per rank, the imbalance, the bytes exchanged.
  void record_partition(const Model& model) {
    std::int64_t ghosts = 0;
    for (const auto& list : send_nodes_) ghosts += static_cast<std::int64_t>(list.size());
    const auto points = all_ranks(points_.second - points_.first, ranks_);
    const auto ghost_nodes = all_ranks(ghosts, ranks_);
    const auto owned = all_ranks(static_cast<std::int64_t>(owned_.size()), ranks_);
    const auto boundary = all_ranks(boundary_points_, ranks_);
    std::int64_t first = 0;
    for (const PointRange& range : boundary_ranges_) first += range.second - range.first;
    const auto before_sending = all_ranks(first, ranks_);
    const double mean = static_cast<double>(model.integration_point_count()) / ranks_;
    const std::int64_t most = *std::max_element(points.begin(), points.end());
    const std::int64_t sent = std::accumulate(ghost_nodes.begin(), ghost_nodes.end(), std::int64_t{0});
    partition_ = {{"method", "METIS_PartMeshDual (tets sharing a face)"},
                  {"integration_points", points},
                  {"owned_nodes", owned},
                  {"ghost_nodes", ghost_nodes},
                  {"boundary_points", boundary},
                  {"points_before_sending", before_sending},
                  {"imbalance", mean > 0.0 ? static_cast<double>(most) / mean : 1.0},
                  {"halo_bytes_per_evaluation", 24 * sent},
                  {"gather_bytes_per_step", 24 * model.node_count() * (ranks_ - 1)}};
  }

  static constexpr int kStepSumValues = 6;  // StepSums and the fastest node's energy, as doubles
  static constexpr std::int64_t kNoneIndex = std::numeric_limits<std::int64_t>::max();
  static constexpr int kLayers = 4;  // edges from the boundary told apart; a support spans one or two
  int rank_ = 0, ranks_ = 1;
  PointRange points_{0, 0};
  std::vector<int> owner_;  // per node: the rank that sums its force
  std::vector<std::vector<Index>> send_nodes_, receive_nodes_;
  std::vector<std::vector<double>> send_buffer_, receive_buffer_;
  std::vector<Index> owned_, slot_, gather_order_;
  std::vector<int> gather_counts_, gather_offsets_;            // per rank: 3 x its own nodes
  std::vector<int> step_gather_counts_, step_gather_offsets_;  // the same with the step's sums
  std::vector<double> owned_sum_, gathered_;  // this rank's own nodes' values (3 each), and every rank's
  std::vector<double> rank_products_;         // this rank's part of a constraint block's products
  std::vector<double> every_rank_;            // from_every_rank's answer
  std::vector<OwnEntries> own_entries_;       // per constraint block met
  std::vector<MPI_Request> requests_;
  std::vector<PointRange> boundary_ranges_, interior_ranges_;
  std::int64_t boundary_points_ = 0;
  std::vector<double> boundary_f_;  // the boundary points' contributions, every node
  // Called by the kernel between its interior points: lets MPI move the halo meanwhile.
  std::function<void()> progress_ = [this] {
    int done = 0;
    MPI_Testall(static_cast<int>(requests_.size()), requests_.data(), &done, MPI_STATUSES_IGNORE);
  };
  json partition_;
  bool whole_on_every_rank_ = false;
  double exchange_s_ = 0.0;
};

}  // namespace mtled

MTLED_PLUGIN(mtled::StepEngine, mtled::MpiBackend)
