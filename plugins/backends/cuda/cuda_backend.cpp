// `cuda`: the time step on an NVIDIA GPU. Everything precomputed in the reference configuration (the rows of both
// force passes, the weights, the laws' constants, the masses) and the state (u_n, u_(n-1), the prediction, the
// forces) stay on the device; a step is a few kernels (kernels.cu). Per step the host reads back the constraint
// products' rows, the step's sums and, for the drivers, u_n at the nodes they read, and sends the constraint
// multipliers; describe() counts those bytes. Laws: any whose plugin holds its device code (Material::device_law, the
// law's single source compiled for the GPU: the shipped Ogden and neo-Hookean); no volumetric treatment yet. Without a
// usable device the run stops at setup with exit 2.
#include <algorithm>
#include <chrono>
#include <climits>
#include <map>
#include <memory>

#include "device_layout.hpp"
#include "device_memory.hpp"
#include "kernels.hpp"
#include "mtled/constraints.hpp"
#include "mtled/errors.hpp"
#include "mtled/force_kernel.hpp"
#include "mtled/interfaces/backend.hpp"
#include "mtled/log.hpp"
#include "mtled/plugin.hpp"
#include "mtled/scope_timer.hpp"

namespace mtled {
namespace {

using cuda::check;
using cuda::DeviceBuffer;
using cuda::PinnedBuffer;

// Both force passes' rows on the device, in the precision the model stores them in.
class DeviceRows {
 public:
  virtual ~DeviceRows() = default;
  // f4 = f_int(u4) (records: the points' stress records, first_bad: the lowest inadmissible point).
  virtual void forces(const double* u4, double* f4, double* records, int* first_bad, cudaStream_t stream) const = 0;
  virtual std::int64_t bytes() const = 0;  // what one evaluation streams of them
};

template <class Real>
class DeviceRowsOf final : public DeviceRows {
 public:
  DeviceRowsOf(const cuda::DeviceLayout<Real>& layout, const std::vector<double>& weights,
               const std::vector<std::uint16_t>& materials, std::vector<DeviceLaw> laws, int device)
      : laws_(std::move(laws)), device_(device) {
    upload(layout.point_rows, points_);
    upload(layout.node_rows, nodes_);
    weight_.upload(weights);
    material_.upload(materials);
    point_rows_ = layout.points;
    node_rows_ = layout.nodes;
  }

  void forces(const double* u4, double* f4, double* records, int* first_bad, cudaStream_t stream) const override {
    cuda::deformation_gradients(cuda::PointPass<Real>{view(points_, point_rows_), u4, records}, stream);
    check(cudaGetLastError(), "launching the gradient pass");
    DeviceStressPass pass;
    pass.points = point_rows_;
    pass.weight = weight_.data();
    pass.material = material_.data();
    pass.records = records;
    pass.first_bad = first_bad;
    pass.device = device_;
    pass.stream = stream;
    for (std::size_t m = 0; m < laws_.size(); ++m) {
      pass.material_index = static_cast<std::uint16_t>(m);
      // Launched by the material plugin's own CUDA runtime, which reports its launch's error here.
      check(static_cast<cudaError_t>(laws_[m].stress_pass(laws_[m].law, pass)), "launching a law's stress pass");
    }
    cuda::nodal_forces(cuda::NodePass<Real>{view(nodes_, node_rows_), records, f4}, stream);
    check(cudaGetLastError(), "launching the node pass");
  }

  std::int64_t bytes() const override {
    const auto per_element = static_cast<std::int64_t>(sizeof(std::int32_t) + 3 * sizeof(Real));
    return (points_.elements + nodes_.elements) * per_element;
  }

 private:
  struct Rows {
    DeviceBuffer<std::int64_t> slice_begin;
    DeviceBuffer<std::int32_t> column, row;
    DeviceBuffer<Real> gx, gy, gz;
    std::int64_t elements = 0;
  };
  static void upload(const cuda::SlicedRows<Real>& from, Rows& to) {
    to.slice_begin.upload(from.slice_begin);
    to.column.upload(from.column);
    to.row.upload(from.row);
    to.gx.upload(from.gx);
    to.gy.upload(from.gy);
    to.gz.upload(from.gz);
    to.elements = from.elements();
  }
  static cuda::SlicedView<Real> view(const Rows& rows, std::int64_t count) {
    return {rows.slice_begin.data(), rows.column.data(), rows.gx.data(), rows.gy.data(), rows.gz.data(),
            rows.row.data(), count};
  }

  Rows points_, nodes_;
  std::int64_t point_rows_ = 0, node_rows_ = 0;
  DeviceBuffer<double> weight_;
  DeviceBuffer<std::uint16_t> material_;
  std::vector<DeviceLaw> laws_;  // one per material index
  int device_;
};

// A constraint block's Phi on the device, as of the block's revision.
struct DeviceBlock {
  long revision = -1;
  cuda::ConstraintView view;
  DeviceBuffer<std::int64_t> row_offsets, node_offsets;
  DeviceBuffer<std::int32_t> row_nodes, node_list, node_rows;
  DeviceBuffer<double> row_values, node_values, values;  // values: rows x k, the products and the multipliers
};

class CudaBackend final : public StepEngine {
 public:
  static void declare(ComponentDeclaration& d) {
    d.summary(
        "An NVIDIA GPU: the force kernel, the update, the constraint projection's products and the step's sums run "
        "on the device, where the state stays; built when CMake finds the CUDA toolkit. Runs any law whose plugin "
        "holds its device code (the shipped Ogden and neo-Hookean do), no volumetric treatment yet (docs/gpu.md).");
    d.integer("device")
        .unit("1")
        .non_negative()
        .defaults(0)
        .doc("which GPU (CUDA's device number, as nvidia-smi lists them)")
        .to<&Settings::device>();
    d.example({{"device", 0}});
  }

  // Finds the device at once, before the scene's mesh and model are built: a run that cannot use it stops in a
  // second, not after the setup.
  explicit CudaBackend(const Parameters& p) : pointer_(p.pointer()), device_(p.read<Settings>().device) {
    select_device();
  }

  ~CudaBackend() override {
    if (stream_ != nullptr) cudaStreamDestroy(stream_);
    for (cudaEvent_t e : {start_, stop_})
      if (e != nullptr) cudaEventDestroy(e);
  }

  void setup(const ForceKernel& kernel) override {
    check(cudaSetDevice(device_), "cudaSetDevice");
    const Discretisation& model = kernel.discretisation();
    if (kernel.volumetric_treatment() != nullptr)
      refuse("the cuda backend does not support a volumetric treatment yet: leave out /volumetric or run on the CPU "
             "(leave out /backend, or --backend cpu)");
    nodes_ = model.node_count();
    points_ = model.points().count();
    std::vector<double> weights(model.points().weights.begin(), model.points().weights.end());
    std::vector<std::uint16_t> materials(static_cast<std::size_t>(points_));
    std::vector<DeviceLaw> laws = read_laws(model, materials);
    const auto start = std::chrono::steady_clock::now();
    if (model.gradients().precision() == RowPrecision::single_precision)
      rows_ = std::make_unique<DeviceRowsOf<float>>(cuda::build_device_layout<float>(model), weights, materials,
                                                    std::move(laws), device_);
    else
      rows_ = std::make_unique<DeviceRowsOf<double>>(cuda::build_device_layout<double>(model), weights, materials,
                                                     std::move(laws), device_);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    precision_ = model.gradients().precision() == RowPrecision::single_precision ? "single" : "double";
    const std::size_t vector = 4 * (static_cast<std::size_t>(nodes_) + 1);  // and the zero sink node
    for (auto* v : {&u_, &u_previous_, &prediction_, &free_, &f_, &f_previous_, &f_ext_, &scratch_u_, &scratch_f_})
      v->resize(vector);
    mass_.resize(static_cast<std::size_t>(nodes_));
    staging_.resize(3 * static_cast<std::size_t>(nodes_));
    read_values_.resize(3 * static_cast<std::size_t>(nodes_));  // pinned once here, not as the drivers' reads grow
    read_list_.resize(static_cast<std::size_t>(nodes_));
    records_.resize(kDeviceRecord * (static_cast<std::size_t>(points_) + 1));  // and the zero sink record
    partials_.resize(cuda::kStepPartials * cuda::kReduceBlocks);
    evaluation_.resize(1);
    first_non_finite_.resize(1);
    sums_.resize(1);
    host_u_.resize(3 * static_cast<std::size_t>(nodes_));
    host_u_previous_.resize(3 * static_cast<std::size_t>(nodes_));
    log().info("cuda backend: {} ({}), rows in {} precision, {:.0f} MB on the device, laid out and copied in {:.2f} s",
               device_name_, capability_, precision_, static_cast<double>(rows_->bytes()) / 1e6, seconds);
  }

  json describe() const override {
    const double steps = std::max<double>(1.0, static_cast<double>(steps_));
    json out = {{"type", "cuda"},
                {"device", device_name_},
                {"compute_capability", capability_},
                {"precision", precision_},
                {"force_evaluations", evaluations_},
                {"engine_calls_s", engine_s_},
                {"host_to_device_bytes_per_step", static_cast<double>(bytes_up_) / steps},
                {"device_to_host_bytes_per_step", static_cast<double>(bytes_down_) / steps}};
    if (evaluations_ > 0) {
      const double seconds = kernel_ms_ / 1e3 / static_cast<double>(evaluations_);
      out["force_kernel_s"] = seconds;
      out["force_kernel_bytes"] = streamed_bytes();
      out["force_kernel_GB_per_s"] = static_cast<double>(streamed_bytes()) / seconds / 1e9;
    }
    return out;
  }

  void set_mass(std::span<const double> mass) override {
    check(cudaMemcpy(mass_.data(), mass.data(), mass.size_bytes(), cudaMemcpyHostToDevice), "copying the masses");
  }

  void set_state(std::span<const double> u, std::span<const double> u_previous) override {
    to_device(u, u_.data());
    to_device(u_previous, u_previous_.data());
    stale();
  }

  std::span<const double> displacement() override {
    const ScopeTimer timed(engine_s_);
    if (!u_on_host_) from_device(u_.data(), host_u_.span());
    u_on_host_ = true;
    return host_u_.span();
  }
  std::span<const double> previous_displacement() override {
    const ScopeTimer timed(engine_s_);
    if (!previous_on_host_) from_device(u_previous_.data(), host_u_previous_.span());
    previous_on_host_ = true;
    return host_u_previous_.span();
  }

  // The sums are queued behind the forces and read back with their inadmissible point in one copy.
  Index evaluate_forces(IncrementSums* sums) override {
    const ScopeTimer timed(engine_s_);
    f_.swap(f_previous_);
    queue_forces(u_.data(), f_.data());
    if (sums != nullptr)
      cuda::increment_sums(nodes_, u_.data(), u_previous_.data(), f_.data(), f_previous_.data(), mass_.data(),
                           partials_.data(), &evaluation_.data()->sums, stream_);
    const cuda::EvaluationDevice result = read_evaluation();
    if (sums != nullptr) {
      sums->stiffness = result.sums.stiffness;
      sums->inertia = result.sums.inertia;
    }
    return first_bad(result);
  }

  std::int64_t predict(const UpdateCoefficients& update, std::span<const double> f_ext) override {
    const ScopeTimer timed(engine_s_);
    if (!f_ext.empty()) to_device(f_ext, f_ext_.data());
    check(cudaMemsetAsync(first_non_finite_.data(), 0xff, sizeof(unsigned long long), stream_), "cudaMemsetAsync");
    cuda::predict(nodes_, u_.data(), u_previous_.data(), f_.data(), f_previous_.data(),
                  f_ext.empty() ? nullptr : f_ext_.data(), mass_.data(), update.alpha, update.beta, update.gamma,
                  prediction_.data(), free_.data(), first_non_finite_.data(), stream_);
    check(cudaGetLastError(), "launching the update");
    unsigned long long first = 0;
    download(first_non_finite_.data(), &first, sizeof(first));
    return first == ULLONG_MAX ? -1 : static_cast<std::int64_t>(first);
  }

  void set_prediction(std::span<const double> u) override {
    to_device(u, prediction_.data());
    check(cudaMemcpyAsync(free_.data(), prediction_.data(), prediction_.bytes(), cudaMemcpyDeviceToDevice, stream_),
          "copying the prediction");
  }
  void prediction(std::span<double> out) override { from_device(prediction_.data(), out); }

  void constrained_values(const ConstraintBlock& block, std::vector<double>& out) override {
    const ScopeTimer timed(engine_s_);
    DeviceBlock& device = on_device(block);
    cuda::constrained_values(device.view, prediction_.data(), device.values.data(), stream_);
    check(cudaGetLastError(), "launching the constraint rows");
    out.resize(device.values.size());
    download(device.values.data(), out.data(), device.values.bytes());
  }

  void add_correction(const ConstraintBlock& block, const std::vector<double>& y) override {
    const ScopeTimer timed(engine_s_);
    DeviceBlock& device = on_device(block);
    upload(y.data(), device.values.data(), y.size() * sizeof(double));
    cuda::add_correction(device.view, device.values.data(), prediction_.data(), stream_);
    check(cudaGetLastError(), "launching the constraint correction");
  }

  StepSums commit(bool, double beta) override {
    const ScopeTimer timed(engine_s_);
    cuda::step_sums(nodes_, prediction_.data(), free_.data(), u_.data(), u_previous_.data(), mass_.data(), beta,
                    partials_.data(), sums_.data(), stream_);
    check(cudaGetLastError(), "launching the step's sums");
    cuda::StepSumsDevice host{};
    download(sums_.data(), &host, sizeof(host));
    u_previous_.swap(u_);
    u_.swap(prediction_);
    stale();
    ++steps_;
    return {host.largest_increment,
            host.largest_displacement,
            host.projection_energy,
            host.kinetic_product,
            static_cast<Index>(host.fastest_node),
            host.largest_residual_step};
  }

  Index internal_forces(std::span<const double> u, std::span<double> f) override {
    const ScopeTimer timed(engine_s_);
    to_device(u, scratch_u_.data());
    queue_forces(scratch_u_.data(), scratch_f_.data());
    const Index bad = first_bad(read_evaluation());
    from_device(scratch_f_.data(), f);
    return bad;
  }

  // The drivers read a few dozen nodes of u_n each step (the needle's neighbourhood): gathered on the device and
  // copied back alone, 24 bytes a node, instead of all of u_n.
  bool spreads_nodes() const override { return true; }
  std::span<const double> displacement_at(std::span<const Index> nodes) override {
    if (u_on_host_ || nodes.empty()) return host_u_.span();
    const ScopeTimer timed(engine_s_);
    const auto count = static_cast<std::int32_t>(nodes.size());
    if (!std::equal(nodes.begin(), nodes.end(), nodes_read_.begin(), nodes_read_.end())) {
      nodes_read_.assign(nodes.begin(), nodes.end());
      upload(nodes_read_.data(), read_list_.data(), nodes.size_bytes());
    }
    cuda::gather(count, read_list_.data(), u_.data(), staging_.data(), stream_);
    check(cudaGetLastError(), "launching the gather");
    download(staging_.data(), read_values_.data(), 3 * nodes.size() * sizeof(double));
    const std::span<double> u = host_u_.span();
    for (std::size_t k = 0; k < nodes.size(); ++k)
      for (std::size_t c = 0; c < 3; ++c)
        u[3 * static_cast<std::size_t>(nodes[k]) + c] = read_values_.data()[3 * k + c];
    return u;
  }

 private:
  struct Settings {
    int device = 0;
  };
  [[noreturn]] void refuse(const std::string& message) const { throw InputError(pointer_, message); }

  void select_device() {
    int count = 0;
    const cudaError_t status = cudaGetDeviceCount(&count);
    if (status != cudaSuccess || count == 0)
      refuse(fmt::format("no usable CUDA device ({}): the cuda backend needs an NVIDIA GPU and its driver; run on the "
                         "CPU instead: leave out /backend, or --backend cpu",
                         status != cudaSuccess ? cudaGetErrorString(status) : "none found"));
    if (device_ >= count)
      refuse(fmt::format("/device = {} but {} CUDA device(s) are present, numbered from 0", device_, count));
    check(cudaSetDevice(device_), "cudaSetDevice");
    cudaDeviceProp properties{};
    check(cudaGetDeviceProperties(&properties, device_), "cudaGetDeviceProperties");
    device_name_ = properties.name;
    capability_ = fmt::format("{}.{}", properties.major, properties.minor);
    check(cudaStreamCreate(&stream_), "cudaStreamCreate");  // ordered with the default stream's copies
    check(cudaEventCreate(&start_), "cudaEventCreate");
    check(cudaEventCreate(&stop_), "cudaEventCreate");
  }

  // One law per distinct material of the model, in the order met; materials[p] = point p's law.
  std::vector<DeviceLaw> read_laws(const Discretisation& model, std::vector<std::uint16_t>& materials) const {
    std::vector<const Material*> seen;
    std::vector<DeviceLaw> laws;
    for (Index p = 0; p < points_; ++p) {
      const Material* material = &model.material(p);
      auto it = std::find(seen.begin(), seen.end(), material);
      if (it == seen.end()) {
        laws.push_back(material->device_law());
        if (laws.back().stress_pass == nullptr)
          refuse(fmt::format(
              "the material of mesh region \"{}\" has no code for the device (its plugin was built without CUDA, or "
              "its law is not written in the arithmetic of mtled/law/arithmetic-inl.h): run on the CPU (leave out "
              "/backend, or --backend cpu)",
              model.mesh().region_names[model.points().material_index[static_cast<std::size_t>(p)]]));
        seen.push_back(material);
        it = seen.end() - 1;
      }
      materials[static_cast<std::size_t>(p)] = static_cast<std::uint16_t>(it - seen.begin());
    }
    return laws;
  }

  // Queues the forces of u4 into f4, timed by events around the kernels; read_evaluation() waits for them.
  void queue_forces(const double* u4, double* f4) {
    int* lowest_bad = &evaluation_.data()->first_bad;
    check(cudaMemsetAsync(lowest_bad, 0x7f, sizeof(int), stream_), "cudaMemsetAsync");
    check(cudaEventRecord(start_, stream_), "cudaEventRecord");
    rows_->forces(u4, f4, records_.data(), lowest_bad, stream_);
    check(cudaEventRecord(stop_, stream_), "cudaEventRecord");
  }
  cuda::EvaluationDevice read_evaluation() {
    cuda::EvaluationDevice result{};
    download(evaluation_.data(), &result, sizeof(result));
    float ms = 0.0f;
    check(cudaEventElapsedTime(&ms, start_, stop_), "cudaEventElapsedTime");
    kernel_ms_ += ms;
    ++evaluations_;
    return result;
  }
  static Index first_bad(const cuda::EvaluationDevice& result) {
    return result.first_bad >= 0x7f7f7f7f ? -1 : result.first_bad;
  }

  std::int64_t streamed_bytes() const {
    const std::int64_t vectors = 4 * (static_cast<std::int64_t>(nodes_) + 1) * 8;
    return rows_->bytes() + static_cast<std::int64_t>(points_) * (2 * kDeviceRecord * 8 + 8 + 2) + 2 * vectors;
  }

  DeviceBlock& on_device(const ConstraintBlock& block) {
    if (block.revision != blocks_revision_) {  // rebuilt: every block is new
      blocks_.clear();
      blocks_revision_ = block.revision;
    }
    DeviceBlock& device = blocks_[&block];
    if (device.revision == block.revision) return device;
    device.revision = block.revision;
    device.row_offsets.upload(block.row_offsets);
    device.row_nodes.upload(block.row_nodes);
    device.row_values.upload(block.row_values);
    device.node_list.upload(block.nodes);
    device.node_offsets.upload(block.node_offsets);
    device.node_rows.upload(block.node_rows);
    device.node_values.upload(block.node_values);
    device.values.resize(static_cast<std::size_t>(block.rows) * block.components.size());
    cuda::ConstraintView& v = device.view;
    v.rows = block.rows;
    v.nodes = static_cast<std::int64_t>(block.nodes.size());
    v.k = static_cast<int>(block.components.size());
    for (int j = 0; j < v.k; ++j) v.components[j] = block.components[static_cast<std::size_t>(j)];
    v.row_offsets = device.row_offsets.data();
    v.row_nodes = device.row_nodes.data();
    v.row_values = device.row_values.data();
    v.node_list = device.node_list.data();
    v.node_offsets = device.node_offsets.data();
    v.node_rows = device.node_rows.data();
    v.node_values = device.node_values.data();
    bytes_up_ += static_cast<long long>(block.row_values.size() * 20 + block.node_values.size() * 20);
    return device;
  }

  // Host vectors hold 3 doubles per node, the device's 4: one contiguous transfer through a 3-per-node staging
  // vector on the device, and a kernel that spreads or gathers it (a strided copy of 24-byte rows is far slower).
  void to_device(std::span<const double> host, double* device) {
    check(cudaMemcpyAsync(staging_.data(), host.data(), host.size_bytes(), cudaMemcpyHostToDevice, stream_),
          "copying a vector to the device");
    cuda::unpack(nodes_, staging_.data(), device, stream_);
    check(cudaGetLastError(), "launching the unpacking");
    check(cudaStreamSynchronize(stream_), "cudaStreamSynchronize");  // the host's vector may change next
    bytes_up_ += static_cast<long long>(host.size_bytes());
  }
  void from_device(const double* device, std::span<double> host) {
    cuda::pack(nodes_, device, staging_.data(), stream_);
    check(cudaGetLastError(), "launching the packing");
    download(staging_.data(), host.data(), host.size_bytes());
  }
  void upload(const void* host, void* device, std::size_t bytes) {
    check(cudaMemcpyAsync(device, host, bytes, cudaMemcpyHostToDevice, stream_), "cudaMemcpyAsync to the device");
    bytes_up_ += static_cast<long long>(bytes);
  }
  // Waits for everything queued before it: the one point where the host learns a result.
  void download(const void* device, void* host, std::size_t bytes) {
    check(cudaMemcpyAsync(host, device, bytes, cudaMemcpyDeviceToHost, stream_), "cudaMemcpyAsync from the device");
    check(cudaStreamSynchronize(stream_), "cudaStreamSynchronize");
    bytes_down_ += static_cast<long long>(bytes);
  }
  void stale() { u_on_host_ = previous_on_host_ = false; }

  std::string pointer_;
  int device_;
  std::string device_name_, capability_, precision_;
  cudaStream_t stream_ = nullptr;
  cudaEvent_t start_ = nullptr, stop_ = nullptr;
  Index nodes_ = 0, points_ = 0;
  std::unique_ptr<DeviceRows> rows_;
  DeviceBuffer<double> u_, u_previous_, prediction_, free_, f_, f_previous_, f_ext_, scratch_u_, scratch_f_;
  DeviceBuffer<double> mass_, records_, partials_, staging_;
  DeviceBuffer<std::int32_t> read_list_;  // the nodes displacement_at last gathered
  DeviceBuffer<unsigned long long> first_non_finite_;
  DeviceBuffer<cuda::EvaluationDevice> evaluation_;
  DeviceBuffer<cuda::StepSumsDevice> sums_;
  PinnedBuffer<double> host_u_, host_u_previous_, read_values_;
  std::vector<Index> nodes_read_;
  bool u_on_host_ = false, previous_on_host_ = false;
  std::map<const ConstraintBlock*, DeviceBlock> blocks_;
  long blocks_revision_ = -1;
  long long bytes_up_ = 0, bytes_down_ = 0, steps_ = 0, evaluations_ = 0;
  double kernel_ms_ = 0.0;
  double engine_s_ = 0.0;  // the host's time inside the engine's calls (the device's work and the copies)
};

}  // namespace
}  // namespace mtled

MTLED_PLUGIN(mtled::StepEngine, mtled::CudaBackend)
