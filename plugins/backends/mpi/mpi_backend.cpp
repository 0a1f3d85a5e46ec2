// `mpi`: one scene on the processes of an MPI run (mpirun -np N mtled run SCENE; the mpi process group,
// process_group.cpp, selects this backend when it has more than one rank). The background cells are partitioned by
// METIS (the tets' dual graph, faces shared); each rank computes the internal forces of its cells' integration points
// on its threads, sends its contributions to the nodes other ranks own (the points at the partition boundary first, the
// interior computed while those travel) and sums those it receives for its own nodes in rank order. It then updates its
// own nodes: the prediction, its part of the constraint projection's products and the step's sums, each global value
// reduced in rank order so that every rank holds the same bits; last, it receives the new displacements of its ghost
// nodes (those its forces read that other ranks own). The drivers' reads are gathered before they update (the nodes
// they name, or all), and the whole displacement on the steps a monitor on some rank reads it. The constraint solve,
// the drivers and the monitors run on every rank on the same values, and only rank 0 writes. The engine holds the CPU
// engine's pieces (HostState, ForceEvaluationClock) rather than deriving from it. docs/mpi.md gives the design, its
// costs and what it does not distribute yet.
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
#include "mtled/constraints.hpp"
#include "mtled/cpu_engine.hpp"
#include "mtled/errors.hpp"
#include "mtled/explicit_update.hpp"
#include "mtled/force_kernel.hpp"
#include "mtled/log.hpp"
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

class MpiBackend final : public StepEngine {
 public:
  static void declare(ComponentDeclaration& d) {
    d.summary(
        "The processes of an MPI run (mpirun -np N mtled run SCENE; the mpi process group chooses it on more than one "
        "rank): METIS partitions the background cells, each rank computes its cells' integration points on its "
        "threads (--threads per rank) and the ranks exchange their contributions to each other's nodes every force "
        "evaluation; each rank updates its own nodes and receives its ghost nodes' new displacements; the constraint "
        "solve, the drivers and the monitors run on every rank on the same values (the nodes the drivers read, and "
        "the whole displacement on the steps the monitors read it, gathered), and rank 0 writes the outputs.");
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

  void setup(const ForceKernel& kernel) override {
    kernel_ = &kernel;
    const Discretisation& model = kernel.discretisation();
    state_.size_for(model.node_count());
    // A volumetric treatment that sums over ranges of points computes its own points' contributions (their averages
    // reach a few layers of other ranks' points, which it evaluates too); one that does not is computed whole on
    // every rank (the same answer, no speed-up).
    const VolumetricTreatment* treatment = kernel.volumetric_treatment();
    whole_on_every_rank_ = treatment != nullptr && !treatment->sums_over_ranges();
    if (whole_on_every_rank_ && rank_ == 0)
      log().warn("mpi: the volumetric treatment's forces are computed whole on every rank (not divided between "
                 "the {} ranks): it does not sum over ranges of points", ranks_);
    const Index n_points = model.points().count();
    // This rank's groups (cell_groups); groups past the discretisation's last one are empty.
    const auto group_start = [&](int group) {
      return group < model.points().group_count() ? model.points().group(group).first : n_points;
    };
    points_ = {group_start(rank_ * (kLayers + 1)), group_start((rank_ + 1) * (kLayers + 1))};
    build_exchange(model);
    build_ghosts(kernel);
    split_points(kernel);
    record_partition(model);
  }

  json describe() const override {
    json out = {{"type", "mpi"}, {"ranks", ranks_}, {"threads_per_rank", kernel_->discretisation().team().size()}};
    clock_.describe(*kernel_, out);
    out["update_s"] = update_s_;
    out["partition"] = partition_;
    if (whole_on_every_rank_) out["forces"] = "whole on every rank (volumetric treatment)";
    out["exchange_s"] = exchange_s_;  // rank 0's: sends, receives, its sums, the gathers and the step's reductions
    out["displacement_gathers"] = {{"whole", whole_gathers_}, {"driver_nodes", driver_nodes_gathered_}};
    return out;
  }

  void set_mass(std::span<const double> mass) override { state_.mass.assign(mass.begin(), mass.end()); }
  void set_prediction(std::span<const double> u) override { state_.set_prediction(u); }

  // The step on this rank's own nodes (state_.u and state_.u_previous hold every node, the other vectors are right at
  // the rank's own nodes only).
  Index evaluate_forces(IncrementSums* sums) override {
    state_.f_previous.swap(state_.f);
    const std::int64_t bad = clock_.timed([&] { return owned_forces(state_.u, state_.f); });
    IncrementSums mine;
    const HostState& s = state_;
    if (sums != nullptr)
      for (const Index i : owned_)
        for (std::size_t d = 3 * static_cast<std::size_t>(i); d < 3 * static_cast<std::size_t>(i) + 3; ++d)
          add_increment_sums(d, s.u, s.u_previous, s.f, s.f_previous, s.mass, mine);
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

  std::int64_t predict(const UpdateCoefficients& update, std::span<const double> f_ext) override {
    const ScopeTimer timer(update_s_);
    const double* external = f_ext.empty() ? nullptr : f_ext.data();
    std::int64_t first_bad = kNoneIndex;
    for (const Index node : owned_) {
      const auto i = static_cast<std::size_t>(node);
      const std::int64_t bad = state_.predict(update, external, i, i + 1);
      if (bad >= 0) first_bad = std::min(first_bad, bad);
    }
    MPI_Allreduce(MPI_IN_PLACE, &first_bad, 1, MPI_INT64_T, MPI_MIN, MPI_COMM_WORLD);
    return first_bad == kNoneIndex ? -1 : first_bad;
  }

  void prediction(std::span<double> out) override {
    gather_owned(state_.prediction);
    std::copy(state_.prediction.begin(), state_.prediction.end(), out.begin());
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
        const double* v = &state_.prediction[3 * static_cast<std::size_t>(block.row_nodes[e])];
        for (std::size_t j = 0; j < k; ++j) sum[j] += block.row_values[e] * v[block.components[j]];
      }
      for (std::size_t j = 0; j < k; ++j) mine[k * r + j] = sum[j];
    }
    const auto start = Clock::now();
    sum_in_rank_order(mine, out);
    exchange_s_ += seconds_since(start);
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
      double* v = &state_.prediction[3 * static_cast<std::size_t>(block.nodes[n])];
      for (std::size_t j = 0; j < k; ++j) v[block.components[j]] += sum[j];
    }
  }

  // The rank's own nodes' sums, combined in rank order; then each rank receives its ghost nodes' u_(n+1), or every
  // node's when some rank's monitors read it this step.
  StepSums commit(bool whole_displacement, double beta) override {
    const ScopeTimer timer(update_s_);
    StepSums mine;
    double fastest = 0.0;
    for (const Index node : owned_) state_.add_step_sums(static_cast<std::size_t>(node), beta, mine, fastest);
    state_.advance();
    previous_whole_ = whole_;
    whole_ = false;
    // The sums and whether this rank's monitors read the whole displacement: one exchange.
    const auto start = Clock::now();
    const double values[kStepValues] = {mine.largest_increment,
                                        mine.largest_displacement,
                                        mine.projection_energy,
                                        mine.kinetic_product,
                                        fastest,
                                        static_cast<double>(mine.fastest_node),
                                        whole_displacement ? 1.0 : 0.0,
                                        mine.largest_residual_step};
    const std::vector<double>& all = from_every_rank(values);
    StepSums sums;
    double fastest_energy = 0.0;
    bool whole = false;
    for (int q = 0; q < ranks_; ++q) {
      const double* v = &all[kStepValues * static_cast<std::size_t>(q)];
      combine_step_sums(StepSums{v[0], v[1], v[2], v[3], static_cast<Index>(v[5]), v[7]}, v[4], sums, fastest_energy);
      whole = whole || v[6] != 0.0;
    }
    if (whole)
      gather_whole_displacement();
    else
      exchange_ghosts();
    exchange_s_ += seconds_since(start);
    return sums;
  }

  void set_state(std::span<const double> u, std::span<const double> u_previous) override {
    state_.set_state(u, u_previous);
    whole_ = previous_whole_ = true;
  }

  // Every node's u_n, gathered when the last commit brought only the ghost nodes (every rank calls it alike).
  std::span<const double> displacement() override {
    if (!whole_) {
      const auto start = Clock::now();
      gather_whole_displacement();
      exchange_s_ += seconds_since(start);
    }
    return state_.u;
  }
  std::span<const double> previous_displacement() override {
    if (!previous_whole_) {
      gather_owned(state_.u_previous);
      previous_whole_ = true;
    }
    return state_.u_previous;
  }

  bool spreads_nodes() const override { return true; }

  // f at every node (the monitors' evaluations on host vectors): this rank's own sums, then gathered.
  Index internal_forces(std::span<const double> u, std::span<double> f) override {
    return clock_.timed([&] {
      std::int64_t first_bad = owned_forces(u, f);
      const auto start = Clock::now();
      MPI_Allreduce(MPI_IN_PLACE, &first_bad, 1, MPI_INT64_T, MPI_MIN, MPI_COMM_WORLD);
      gather_owned(f);
      exchange_s_ += seconds_since(start);
      return first_bad == kNoneIndex ? Index{-1} : static_cast<Index>(first_bad);
    });
  }

  // u_n at `nodes` (the same list on every rank): each rank's own among them, gathered in list order.
  std::span<const double> displacement_at(std::span<const Index> nodes) override {
    if (whole_ || nodes.empty()) return state_.u;
    const auto start = Clock::now();
    subset_counts_.assign(static_cast<std::size_t>(ranks_), 0);
    std::size_t packed = 0;
    for (const Index n : nodes) {
      const int q = owner_[static_cast<std::size_t>(n)];
      subset_counts_[static_cast<std::size_t>(q)] += 3;
      if (q != rank_) continue;
      for (std::size_t c = 0; c < 3; ++c) owned_sum_[packed++] = state_.u[3 * static_cast<std::size_t>(n) + c];
    }
    subset_offsets_.assign(static_cast<std::size_t>(ranks_), 0);
    std::partial_sum(subset_counts_.begin(), subset_counts_.end() - 1, subset_offsets_.begin() + 1);
    MPI_Allgatherv(owned_sum_.data(), static_cast<int>(packed), MPI_DOUBLE, gathered_.data(), subset_counts_.data(),
                   subset_offsets_.data(), MPI_DOUBLE, MPI_COMM_WORLD);
    for (const Index n : nodes) {  // each rank's values in list order
      int& next = subset_offsets_[static_cast<std::size_t>(owner_[static_cast<std::size_t>(n)])];
      for (std::size_t c = 0; c < 3; ++c)
        state_.u[3 * static_cast<std::size_t>(n) + c] = gathered_[static_cast<std::size_t>(next) + c];
      next += 3;
    }
    driver_nodes_gathered_ += static_cast<std::int64_t>(nodes.size());
    exchange_s_ += seconds_since(start);
    return state_.u;
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
      note(kernel_->internal_forces(u, f));
      return first_bad;
    }
    auto start = Clock::now();
    post_receives(forces_.my_values, kForceTag);
    exchange_s_ += seconds_since(start);
    note(kernel_->internal_forces(u, boundary_f_, boundary_ranges_));
    start = Clock::now();
    send_values(forces_.theirs, forces_.their_values, boundary_f_, kForceTag);
    exchange_s_ += seconds_since(start);
    note(kernel_->internal_forces(u, f, interior_ranges_, progress_));
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

  // out = the sum over the ranks of their `mine` (the same length on every rank), each value added in rank order
  // from zero: the same bits on every rank. A reduce-scatter and a gather: rank q sums slice q of the values (every
  // rank sends it its part of that slice) and every rank gathers the summed slices, so a rank moves about twice the
  // values whatever the number of ranks (an all-gather of every rank's values would move N times as many).
  void sum_in_rank_order(std::span<const double> mine, std::vector<double>& out) {
    const auto n = static_cast<std::int64_t>(mine.size());
    slice_offsets_.resize(static_cast<std::size_t>(ranks_) + 1);
    for (int q = 0; q <= ranks_; ++q) slice_offsets_[static_cast<std::size_t>(q)] = static_cast<int>(n * q / ranks_);
    const auto r = static_cast<std::size_t>(rank_);
    const int my_slice = slice_offsets_[r + 1] - slice_offsets_[r];
    send_counts_.resize(static_cast<std::size_t>(ranks_));
    receive_counts_.assign(static_cast<std::size_t>(ranks_), my_slice);
    receive_offsets_.resize(static_cast<std::size_t>(ranks_));
    for (std::size_t q = 0; q < static_cast<std::size_t>(ranks_); ++q) {
      send_counts_[q] = slice_offsets_[q + 1] - slice_offsets_[q];
      receive_offsets_[q] = static_cast<int>(q) * my_slice;
    }
    every_rank_.resize(static_cast<std::size_t>(ranks_) * static_cast<std::size_t>(my_slice));
    MPI_Alltoallv(mine.data(), send_counts_.data(), slice_offsets_.data(), MPI_DOUBLE, every_rank_.data(),
                  receive_counts_.data(), receive_offsets_.data(), MPI_DOUBLE, MPI_COMM_WORLD);
    out.assign(static_cast<std::size_t>(n), 0.0);
    double* slice = out.data() + slice_offsets_[r];
    for (std::size_t q = 0; q < static_cast<std::size_t>(ranks_); ++q)
      for (int i = 0; i < my_slice; ++i) slice[i] += every_rank_[q * static_cast<std::size_t>(my_slice) + static_cast<std::size_t>(i)];
    MPI_Allgatherv(MPI_IN_PLACE, 0, MPI_DOUBLE, out.data(), send_counts_.data(), slice_offsets_.data(), MPI_DOUBLE,
                   MPI_COMM_WORLD);
  }

 private:
  // Per other rank q: the marked nodes q owns (theirs[q], ascending) and the nodes this rank owns that q marked
  // (mine[q], in q's order), with room for 3 values each: who sends what to whom when every rank needs the values
  // of the nodes it marked.
  struct NodeExchange {
    std::vector<std::vector<Index>> theirs, mine;
    std::vector<std::vector<double>> their_values, my_values;
    std::int64_t their_count() const {
      std::int64_t n = 0;
      for (const auto& list : theirs) n += static_cast<std::int64_t>(list.size());
      return n;
    }
  };
  NodeExchange exchange_of(const std::vector<char>& marked) const {
    NodeExchange x;
    x.theirs.assign(static_cast<std::size_t>(ranks_), {});
    for (std::size_t i = 0; i < marked.size(); ++i)
      if (marked[i] && owner_[i] != rank_) x.theirs[static_cast<std::size_t>(owner_[i])].push_back(static_cast<Index>(i));
    std::vector<int> their_counts(static_cast<std::size_t>(ranks_)), my_counts(static_cast<std::size_t>(ranks_));
    for (int q = 0; q < ranks_; ++q) their_counts[static_cast<std::size_t>(q)] = static_cast<int>(x.theirs[static_cast<std::size_t>(q)].size());
    MPI_Alltoall(their_counts.data(), 1, MPI_INT, my_counts.data(), 1, MPI_INT, MPI_COMM_WORLD);
    std::vector<int> their_offsets(static_cast<std::size_t>(ranks_) + 1, 0), my_offsets(static_cast<std::size_t>(ranks_) + 1, 0);
    std::partial_sum(their_counts.begin(), their_counts.end(), their_offsets.begin() + 1);
    std::partial_sum(my_counts.begin(), my_counts.end(), my_offsets.begin() + 1);
    std::vector<std::int64_t> sent, received(static_cast<std::size_t>(my_offsets.back()));
    for (const auto& list : x.theirs) sent.insert(sent.end(), list.begin(), list.end());
    MPI_Alltoallv(sent.data(), their_counts.data(), their_offsets.data(), MPI_INT64_T, received.data(),
                  my_counts.data(), my_offsets.data(), MPI_INT64_T, MPI_COMM_WORLD);
    x.mine.assign(static_cast<std::size_t>(ranks_), {});
    x.their_values.resize(static_cast<std::size_t>(ranks_));
    x.my_values.resize(static_cast<std::size_t>(ranks_));
    for (std::size_t q = 0; q < static_cast<std::size_t>(ranks_); ++q) {
      x.mine[q].assign(received.begin() + my_offsets[q], received.begin() + my_offsets[q + 1]);
      x.their_values[q].resize(3 * x.theirs[q].size());
      x.my_values[q].resize(3 * x.mine[q].size());
    }
    return x;
  }

  // The force exchange (the nodes this rank's points support: it sends its contributions to their owners and
  // receives the others' for its own), and every rank's owned nodes in the gathered vector's order.
  void build_exchange(const Discretisation& model) {
    const GradientRows& rows = model.gradients();
    const std::size_t nodes = static_cast<std::size_t>(model.node_count());
    std::vector<char> supported(nodes, 0);
    for (Index p = points_.first; p < points_.second; ++p)
      for (int k = 0; k < rows.size(p); ++k) supported[static_cast<std::size_t>(rows.node(p, k))] = 1;
    forces_ = exchange_of(supported);
    // The gathered vector: rank 0's owned nodes in ascending order, then rank 1's, ...
    gather_counts_.assign(static_cast<std::size_t>(ranks_), 0);
    for (const int o : owner_) gather_counts_[static_cast<std::size_t>(o)] += 3;
    gather_offsets_.assign(static_cast<std::size_t>(ranks_), 0);
    std::partial_sum(gather_counts_.begin(), gather_counts_.end() - 1, gather_offsets_.begin() + 1);
    gather_order_.clear();
    for (int q = 0; q < ranks_; ++q)
      for (std::size_t i = 0; i < nodes; ++i)
        if (owner_[i] == q) gather_order_.push_back(static_cast<Index>(i));
    const auto mine = static_cast<std::size_t>(gather_offsets_[static_cast<std::size_t>(rank_)] / 3);
    owned_.assign(gather_order_.begin() + static_cast<std::ptrdiff_t>(mine),
                  gather_order_.begin() + static_cast<std::ptrdiff_t>(mine) + gather_counts_[static_cast<std::size_t>(rank_)] / 3);
    slot_.assign(nodes, -1);
    for (std::size_t k = 0; k < owned_.size(); ++k) slot_[static_cast<std::size_t>(owned_[k])] = static_cast<Index>(k);
    owned_sum_.resize(3 * owned_.size());
    gathered_.resize(3 * nodes);
    requests_.reserve(2 * static_cast<std::size_t>(ranks_));
  }

  // The ghost nodes: those other ranks own whose displacements this rank's force evaluation reads (its points'
  // supports; with a volumetric treatment, the supports of every point whose F its averages use).
  void build_ghosts(const ForceKernel& kernel) {
    const Discretisation& model = kernel.discretisation();
    const GradientRows& rows = model.gradients();
    const std::vector<PointRange> own{points_};
    const std::vector<PointRange> read = kernel.points_read(own);  // every point for a treatment computed whole
    std::vector<char> marked(static_cast<std::size_t>(model.node_count()), 0);
    for (const PointRange& range : read)
      for (Index p = range.first; p < range.second; ++p)
        for (int k = 0; k < rows.size(p); ++k) marked[static_cast<std::size_t>(rows.node(p, k))] = 1;
    ghosts_ = exchange_of(marked);
  }

  // The boundary points: those whose supports reach a node another rank owns, in blocks of consecutive points
  // (whole blocks keep the kernel's batches long); the rest of the rank's points are its interior.
  void split_points(const ForceKernel& kernel) {
    constexpr Index kBlock = 16;  // two of the kernel's batches (StressBatch::kCapacity)
    const GradientRows& rows = kernel.discretisation().gradients();
    boundary_ranges_.clear();
    interior_ranges_.clear();
    boundary_points_ = 0;
    // With a volumetric treatment every point goes first: its averages reach past the boundary points, so the
    // interior would evaluate them again.
    const bool all_first = kernel.volumetric_treatment() != nullptr;
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
    boundary_f_.assign(3 * static_cast<std::size_t>(kernel.discretisation().node_count()), 0.0);
  }

  // The start of an exchange: a receive into each other rank's non-empty buffer in[q].
  void post_receives(std::vector<std::vector<double>>& in, int tag) {
    requests_.clear();  // kept: no allocation in the time step
    for (int q = 0; q < ranks_; ++q) {
      auto& buffer = in[static_cast<std::size_t>(q)];
      if (buffer.empty()) continue;
      requests_.emplace_back();
      MPI_Irecv(buffer.data(), static_cast<int>(buffer.size()), MPI_DOUBLE, q, tag, MPI_COMM_WORLD, &requests_.back());
    }
  }

  // Sends each other rank q the values of v (3 per node) at the nodes lists[q], packed into out[q].
  void send_values(const std::vector<std::vector<Index>>& lists, std::vector<std::vector<double>>& out,
                   std::span<const double> v, int tag) {
    for (int q = 0; q < ranks_; ++q) {
      const auto& list = lists[static_cast<std::size_t>(q)];
      auto& buffer = out[static_cast<std::size_t>(q)];
      if (list.empty()) continue;
      for (std::size_t k = 0; k < list.size(); ++k)
        for (std::size_t c = 0; c < 3; ++c) buffer[3 * k + c] = v[3 * static_cast<std::size_t>(list[k]) + c];
      requests_.emplace_back();
      MPI_Isend(buffer.data(), static_cast<int>(buffer.size()), MPI_DOUBLE, q, tag, MPI_COMM_WORLD, &requests_.back());
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
      const auto& list = forces_.mine[static_cast<std::size_t>(q)];
      const auto& in = forces_.my_values[static_cast<std::size_t>(q)];
      for (std::size_t k = 0; k < list.size(); ++k) {
        const auto s = static_cast<std::size_t>(slot_[static_cast<std::size_t>(list[k])]);
        for (std::size_t c = 0; c < 3; ++c) owned_sum_[3 * s + c] += in[3 * k + c];
      }
    }
    for (std::size_t k = 0; k < owned_.size(); ++k)
      for (std::size_t c = 0; c < 3; ++c) f[3 * static_cast<std::size_t>(owned_[k]) + c] = owned_sum_[3 * k + c];
  }

  // v (3 per node), right at this rank's own nodes, becomes right at every node: each rank's own values gathered.
  void gather_owned(std::span<double> v) {
    for (std::size_t k = 0; k < owned_.size(); ++k)
      for (std::size_t c = 0; c < 3; ++c) owned_sum_[3 * k + c] = v[3 * static_cast<std::size_t>(owned_[k]) + c];
    MPI_Allgatherv(owned_sum_.data(), static_cast<int>(3 * owned_.size()), MPI_DOUBLE, gathered_.data(),
                   gather_counts_.data(), gather_offsets_.data(), MPI_DOUBLE, MPI_COMM_WORLD);
    for (std::size_t k = 0; k < gather_order_.size(); ++k)  // rank 0's nodes, then rank 1's, ...
      for (std::size_t c = 0; c < 3; ++c) v[3 * static_cast<std::size_t>(gather_order_[k]) + c] = gathered_[3 * k + c];
  }

  // u_n right at the ghost nodes as well: each rank sends its own nodes' values to the ranks whose forces read them.
  void exchange_ghosts() {
    post_receives(ghosts_.their_values, kGhostTag);
    send_values(ghosts_.mine, ghosts_.my_values, state_.u, kGhostTag);
    MPI_Waitall(static_cast<int>(requests_.size()), requests_.data(), MPI_STATUSES_IGNORE);
    for (std::size_t q = 0; q < static_cast<std::size_t>(ranks_); ++q) {
      const auto& list = ghosts_.theirs[q];
      const auto& in = ghosts_.their_values[q];
      for (std::size_t k = 0; k < list.size(); ++k)
        for (std::size_t c = 0; c < 3; ++c) state_.u[3 * static_cast<std::size_t>(list[k]) + c] = in[3 * k + c];
    }
  }

  // u_n right at every node (the monitors' steps, the drivers that do not say what they read, the run's end).
  void gather_whole_displacement() {
    gather_owned(state_.u);
    whole_ = true;
    ++whole_gathers_;
  }

  static double seconds_since(Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
  }

  // summary.json's "partition": points, owned and ghost nodes per rank, the imbalance, the bytes exchanged.
  void record_partition(const Discretisation& model) {
    const auto points = all_ranks(points_.second - points_.first, ranks_);
    const auto ghost_nodes = all_ranks(ghosts_.their_count(), ranks_);
    const auto halo_nodes = all_ranks(forces_.their_count(), ranks_);
    const auto owned = all_ranks(static_cast<std::int64_t>(owned_.size()), ranks_);
    const auto boundary = all_ranks(boundary_points_, ranks_);
    std::int64_t first = 0;
    for (const PointRange& range : boundary_ranges_) first += range.second - range.first;
    const auto before_sending = all_ranks(first, ranks_);
    const double mean = static_cast<double>(model.points().count()) / ranks_;
    const std::int64_t most = *std::max_element(points.begin(), points.end());
    const auto total = [](const std::vector<std::int64_t>& v) { return std::accumulate(v.begin(), v.end(), std::int64_t{0}); };
    partition_ = {{"method", "METIS_PartMeshDual (tets sharing a face)"},
                  {"integration_points", points},
                  {"owned_nodes", owned},
                  {"ghost_nodes", ghost_nodes},
                  {"boundary_points", boundary},
                  {"points_before_sending", before_sending},
                  {"imbalance", mean > 0.0 ? static_cast<double>(most) / mean : 1.0},
                  {"halo_bytes_per_evaluation", 24 * total(halo_nodes)},
                  {"ghost_bytes_per_step", 24 * total(ghost_nodes)},
                  {"whole_gather_bytes", 24 * model.node_count() * (ranks_ - 1)}};
  }

  const ForceKernel* kernel_ = nullptr;
  HostState state_;  // the CPU engine's pieces: the state in host memory, its per-node work, the force clock
  ForceEvaluationClock clock_;
  double update_s_ = 0.0;  // as CpuEngine's "update_s": the rank's per-node work and constraint products

  static constexpr int kStepValues = 8;  // StepSums, the fastest node's energy and the whole-gather flag, as doubles
  static constexpr int kForceTag = 0, kGhostTag = 1;
  static constexpr std::int64_t kNoneIndex = std::numeric_limits<std::int64_t>::max();
  static constexpr int kLayers = 4;  // edges from the boundary told apart; a support spans one or two
  int rank_ = 0, ranks_ = 1;
  PointRange points_{0, 0};
  std::vector<int> owner_;  // per node: the rank that sums its force
  NodeExchange forces_;  // contributions to other ranks' nodes out, to this rank's in
  NodeExchange ghosts_;  // displacements of other ranks' nodes this rank's forces read in, of its own out
  std::vector<Index> owned_, slot_, gather_order_;
  std::vector<int> gather_counts_, gather_offsets_;  // per rank: 3 x its own nodes
  std::vector<int> subset_counts_, subset_offsets_;  // per rank: 3 x its own nodes among the drivers' reads
  std::vector<double> owned_sum_, gathered_;  // this rank's own nodes' values (3 each), and every rank's
  std::vector<double> rank_products_;         // this rank's part of a constraint block's products
  std::vector<double> every_rank_;            // from_every_rank's answer; sum_in_rank_order's slices
  std::vector<int> slice_offsets_, send_counts_, receive_counts_, receive_offsets_;  // sum_in_rank_order's layout
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
  bool whole_ = true, previous_whole_ = true;  // u_n (u_(n-1)) right at every node, not only own and ghost ones
  std::int64_t whole_gathers_ = 0, driver_nodes_gathered_ = 0;
  double exchange_s_ = 0.0;
};

}  // namespace mtled

MTLED_PLUGIN(mtled::StepEngine, mtled::MpiBackend)
