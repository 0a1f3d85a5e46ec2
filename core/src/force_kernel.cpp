#include "mtled/force_kernel.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "force_passes.hpp"

namespace mtled {

ForceKernel::ForceKernel(const Discretisation& discretisation, std::shared_ptr<VolumetricTreatment> volumetric)
    : discretisation_(discretisation), volumetric_(std::move(volumetric)) {
  const std::size_t padded = 4 * (static_cast<std::size_t>(discretisation_.node_count()) + 1);
  padded_u_.assign(padded, 0.0);
  thread_forces_.resize(static_cast<std::size_t>(team().size()));
  for (auto& buffer : thread_forces_) buffer.assign(padded, 0.0);
  thread_first_bad_.assign(thread_forces_.size(), std::numeric_limits<Index>::max());
  if (volumetric_) volumetric_->setup(*this);
}

ForceKernel::~ForceKernel() = default;

// A team task: thread `thread`'s share of the kernel's slots (GradientRows::slot), each filled from its node.
void ForceKernel::pad_displacement(std::span<const double> u, int thread) const {
  const auto [begin, end] = ThreadTeam::share(discretisation_.node_count(), thread, team().size());
  for (std::int64_t s = begin; s < end; ++s) {
    const auto i = static_cast<std::size_t>(rows().node_at_slot(static_cast<Index>(s)));
    for (std::size_t c = 0; c < 3; ++c) padded_u_[4 * static_cast<std::size_t>(s) + c] = u[3 * i + c];
  }
}

std::span<const PointRange> ForceKernel::thread_slots(std::span<const PointRange> ranges) const {
  for (const auto& [asked, slots] : thread_slots_)
    if (std::equal(ranges.begin(), ranges.end(), asked.begin(), asked.end())) return slots;
  const int threads = team().size();
  std::vector<PointRange> slots(static_cast<std::size_t>(threads), PointRange{0, 0});
  for (int thread = 0; thread < threads; ++thread) {
    Index lowest = std::numeric_limits<Index>::max(), highest = -1;
    ThreadTeam::for_each_piece_of_share(ranges, thread, threads, [&](Index begin, Index end) {
      for (Index row = begin; row < end; ++row)
        for (int k = 0; k < rows().size(row); ++k) {
          lowest = std::min(lowest, rows().entry_slot(row, k));
          highest = std::max(highest, rows().entry_slot(row, k));
        }
    });
    if (highest >= 0) slots[static_cast<std::size_t>(thread)] = {lowest, highest + 1};
  }
  thread_slots_.emplace_back(std::vector<PointRange>(ranges.begin(), ranges.end()), std::move(slots));
  return thread_slots_.back().second;
}

// A team task: sums the per-thread buffers in a fixed order over thread `thread`'s share of the nodes, each buffer
// only where its thread wrote (elsewhere it held zeros: the sums are those of every buffer, bit for bit).
void ForceKernel::reduce_thread_forces(std::span<double> f, int thread, std::span<const PointRange> slots) const {
  const auto [begin, end] = ThreadTeam::share(discretisation_.node_count(), thread, team().size());
  for (std::int64_t i = begin; i < end; ++i) {
    const Index s = rows().slot(static_cast<Index>(i));
    double sum[3] = {0.0, 0.0, 0.0};
    for (std::size_t t = 0; t < thread_forces_.size(); ++t) {
      if (s < slots[t].first || s >= slots[t].second) continue;
      const double* record = thread_forces_[t].data() + 4 * static_cast<std::size_t>(s);
      for (std::size_t c = 0; c < 3; ++c) sum[c] += record[c];
    }
    for (std::size_t c = 0; c < 3; ++c) f[3 * static_cast<std::size_t>(i) + c] = sum[c];
  }
}

// Zeroes the slots a thread's share writes into (the padding's sink slot with them: its padded entries add there).
void ForceKernel::clear_thread_forces(int thread, std::span<const PointRange> slots) const {
  AlignedVector<double>& local = thread_forces_[static_cast<std::size_t>(thread)];
  const PointRange range = slots[static_cast<std::size_t>(thread)];
  std::fill(local.begin() + 4 * range.first, local.begin() + 4 * range.second, 0.0);
  std::fill(local.end() - 4, local.end(), 0.0);
}

// The forces of integration points begin .. end - 1 into f4, in batches of consecutive points with one
// material. Returns the first inadmissible point, or the largest Index.
Index ForceKernel::accumulate_forces(Index begin, Index end, double* f4, const std::function<void()>* progress) const {
  constexpr int kCapacity = StressBatch::kCapacity;
  constexpr Index kPointsBetweenProgress = 2048;  // about a tenth of a millisecond of the kernel
  const IntegrationPoints& points = discretisation_.points();
  const IntegrationCorrection& correction = discretisation_.basis()->correction;
  Index first_bad = std::numeric_limits<Index>::max();
  Index since_progress = 0;
  StressBatch batch{};
  double P[9][kCapacity];
  double weights[kCapacity];
  bool skip[kCapacity];
  for (Index first = begin; first < end; first += batch.count) {
    const std::uint16_t material = points.material_index[first];
    int count = 1;
    while (count < kCapacity && first + count < end && points.material_index[first + count] == material) ++count;
    batch.count = count;
    force_passes::gather(rows(), padded_u_.data(), first, batch);
    discretisation_.material(first).stress_batch(batch);
    for (int p = 0; p < kCapacity; ++p) {
      weights[p] = p < count ? points.weights[first + p] : 0.0;
      skip[p] = p < count && !batch.admissible[p];
      if (skip[p]) first_bad = std::min(first_bad, first + p);
    }
    force_passes::first_piola(batch, weights, P);
    force_passes::scatter(rows(), correction.at_slots.data(), correction.means.data(), first, count, P, skip, f4);
    if (progress != nullptr && (since_progress += count) >= kPointsBetweenProgress) {
      (*progress)();
      since_progress = 0;
    }
  }
  return first_bad;
}

Index ForceKernel::internal_forces(std::span<const double> u, std::span<double> f) const {
  if (volumetric_) return volumetric_->internal_forces(*this, u, f);
  return internal_forces(u, f, discretisation_.points().every());
}

std::vector<PointRange> ForceKernel::points_read(std::span<const PointRange> ranges) const {
  if (volumetric_) return volumetric_->points_read(*this, ranges);
  return {ranges.begin(), ranges.end()};
}

Index ForceKernel::internal_forces(std::span<const double> u, std::span<double> f, std::span<const PointRange> ranges,
                                   const std::function<void()>& progress) const {
  if (volumetric_) {
    if (!volumetric_->sums_over_ranges())
      throw std::logic_error(
          "ForceKernel::internal_forces over ranges of points with a volumetric treatment that sums "
          "only over every point");
    return volumetric_->internal_forces(*this, u, f, ranges);
  }
  std::vector<Index>& first_bad = thread_first_bad_;
  const std::span<const PointRange> slots = thread_slots(ranges);
  team().run([&](int thread) {
    AlignedVector<double>& local = thread_forces_[static_cast<std::size_t>(thread)];
    clear_thread_forces(thread, slots);
    pad_displacement(u, thread);
    team().barrier();
    // Contiguous shares of the ranges' points, so that each thread's batches are consecutive points.
    const std::function<void()>* calls = thread == 0 && progress ? &progress : nullptr;
    Index bad = std::numeric_limits<Index>::max();
    ThreadTeam::for_each_piece_of_share(ranges, thread, team().size(), [&](Index begin, Index end) {
      bad = std::min(bad, accumulate_forces(begin, end, local.data(), calls));
    });
    first_bad[static_cast<std::size_t>(thread)] = bad;
    team().barrier();
    reduce_thread_forces(f, thread, slots);
  });
  const Index bad = *std::min_element(first_bad.begin(), first_bad.end());
  return bad == std::numeric_limits<Index>::max() ? -1 : bad;
}

Index ForceKernel::stress_deformation_gradients(std::span<const double> u, std::span<Mat3> F) const {
  if (volumetric_) return volumetric_->stress_deformation_gradients(*this, u, F);
  return deformation_gradients(u, F);
}

Index ForceKernel::deformation_gradients(std::span<const double> u, std::span<Mat3> F) const {
  return deformation_gradients(u, F, discretisation_.points().every());
}

Index ForceKernel::deformation_gradients(std::span<const double> u, std::span<Mat3> F,
                                         std::span<const PointRange> ranges) const {
  std::vector<Index>& first_bad = thread_first_bad_;
  team().run([&](int thread) {
    Index& thread_bad = first_bad[static_cast<std::size_t>(thread)];
    thread_bad = std::numeric_limits<Index>::max();
    pad_displacement(u, thread);
    team().barrier();
    StressBatch batch{};
    ThreadTeam::for_each_piece_of_share(ranges, thread, team().size(), [&](Index begin, Index end) {
      for (Index first = begin; first < end; first += batch.count) {
        batch.count = std::min<Index>(StressBatch::kCapacity, end - first);
        force_passes::gather(rows(), padded_u_.data(), first, batch);
        for (int p = 0; p < batch.count; ++p) {
          F[first + p] = batch.deformation_gradient(p);
          const double J = F[first + p].determinant();
          if (!(J > 0.0) || !std::isfinite(J) || !F[first + p].allFinite())
            thread_bad = std::min(thread_bad, first + p);
        }
      }
    });
  });
  const Index bad = *std::min_element(first_bad.begin(), first_bad.end());
  return bad == std::numeric_limits<Index>::max() ? -1 : bad;
}

void ForceKernel::scatter_stresses(std::span<const Mat3> weighted_stress, std::span<double> f) const {
  scatter_stresses(weighted_stress, f, discretisation_.points().every());
}

void ForceKernel::scatter_stresses(std::span<const Mat3> weighted_stress, std::span<double> f,
                                   std::span<const PointRange> ranges) const {
  const IntegrationCorrection& correction = discretisation_.basis()->correction;
  const std::span<const PointRange> slots = thread_slots(ranges);
  team().run([&](int thread) {
    AlignedVector<double>& local = thread_forces_[static_cast<std::size_t>(thread)];
    clear_thread_forces(thread, slots);
    double P[9][StressBatch::kCapacity];
    const bool skip[StressBatch::kCapacity] = {};
    ThreadTeam::for_each_piece_of_share(ranges, thread, team().size(), [&](Index begin, Index end) {
      for (Index first = begin; first < end; first += StressBatch::kCapacity) {
        const int count = std::min<Index>(StressBatch::kCapacity, end - first);
        for (int p = 0; p < count; ++p)
          for (int c = 0; c < 9; ++c) P[c][p] = weighted_stress[first + p](c / 3, c % 3);
        force_passes::scatter(rows(), correction.at_slots.data(), correction.means.data(), first, count, P, skip,
                              local.data());
      }
    });
    team().barrier();
    reduce_thread_forces(f, thread, slots);
  });
}

std::int64_t ForceKernel::streamed_bytes_per_force_evaluation() const {
  const std::int64_t real = rows().precision() == RowPrecision::single_precision ? 4 : 8;
  // Rows with their own test gradients stream them too, and read no corrections (xi per node, the mean per point).
  const bool stored_tests = rows().has_own_test_gradients();
  const std::int64_t gradients = (stored_tests ? 2 : 1) * 3 * real;
  const std::int64_t row_bytes =
      rows().blocks() * GradientRows::kBlock * (static_cast<std::int64_t>(sizeof(Index)) + gradients);
  const std::int64_t points = discretisation_.points().count() * (8 + (stored_tests ? 0 : 3 * 8) + 2);
  // u (and xi); the force buffers; u in, f out
  const std::int64_t per_node = 4 * 8 * ((stored_tests ? 1 : 2) + 3 * team().size()) + 3 * 8 * 2;
  return row_bytes + points + (static_cast<std::int64_t>(discretisation_.node_count()) + 1) * per_node;
}

double ForceKernel::strain_energy(std::span<const double> u) const {
  if (volumetric_) return volumetric_->strain_energy(*this, u);
  const Discretisation& d = discretisation_;
  const Index n = d.points().count();
  double energy = 0.0;
#pragma omp parallel for schedule(static) reduction(+ : energy)
  for (Index ip = 0; ip < n; ++ip)
    energy += d.points().weights[ip] * d.material(ip).energy(d.deformation_gradient(ip, u));
  return energy;
}

}  // namespace mtled
