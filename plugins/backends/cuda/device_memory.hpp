#pragma once
// Owning handles of device and page-locked host memory, and the check every CUDA call goes through.
#include <cuda_runtime.h>
#include <fmt/format.h>

#include <cstddef>
#include <span>
#include <stdexcept>
#include <utility>
#include <vector>

namespace mtled::cuda {

// Throws std::runtime_error naming the call and CUDA's own message.
inline void check(cudaError_t status, const char* what) {
  if (status != cudaSuccess)
    throw std::runtime_error(fmt::format("CUDA: {} failed: {} ({})", what, cudaGetErrorString(status),
                                         cudaGetErrorName(status)));
}

template <class T>
class DeviceBuffer {
 public:
  DeviceBuffer() = default;
  explicit DeviceBuffer(std::size_t size) { resize(size); }
  ~DeviceBuffer() { cudaFree(data_); }
  DeviceBuffer(const DeviceBuffer&) = delete;
  DeviceBuffer& operator=(const DeviceBuffer&) = delete;
  DeviceBuffer(DeviceBuffer&& other) noexcept { swap(other); }
  DeviceBuffer& operator=(DeviceBuffer&& other) noexcept {
    swap(other);
    return *this;
  }
  void swap(DeviceBuffer& other) noexcept {
    std::swap(data_, other.data_);
    std::swap(size_, other.size_);
  }

  // Zero-filled.
  void resize(std::size_t size) {
    cudaFree(data_);
    data_ = nullptr;
    size_ = size;
    if (size == 0) return;
    check(cudaMalloc(reinterpret_cast<void**>(&data_), size * sizeof(T)), "cudaMalloc");
    check(cudaMemset(data_, 0, size * sizeof(T)), "cudaMemset");
  }
  void upload(const std::vector<T>& values) {
    resize(values.size());
    if (!values.empty())
      check(cudaMemcpy(data_, values.data(), values.size() * sizeof(T), cudaMemcpyHostToDevice), "cudaMemcpy to the device");
  }

  T* data() { return data_; }
  const T* data() const { return data_; }
  std::size_t size() const { return size_; }
  std::size_t bytes() const { return size_ * sizeof(T); }

 private:
  T* data_ = nullptr;
  std::size_t size_ = 0;
};

// Host memory the device copies to and from at full speed.
template <class T>
class PinnedBuffer {
 public:
  PinnedBuffer() = default;
  ~PinnedBuffer() { cudaFreeHost(data_); }
  PinnedBuffer(const PinnedBuffer&) = delete;
  PinnedBuffer& operator=(const PinnedBuffer&) = delete;

  void resize(std::size_t size) {
    if (size <= capacity_) {
      size_ = size;
      return;
    }
    cudaFreeHost(data_);
    data_ = nullptr;
    check(cudaMallocHost(reinterpret_cast<void**>(&data_), size * sizeof(T)), "cudaMallocHost");
    size_ = capacity_ = size;
  }
  T* data() { return data_; }
  std::span<T> span() { return {data_, size_}; }
  std::size_t size() const { return size_; }

 private:
  T* data_ = nullptr;
  std::size_t size_ = 0, capacity_ = 0;
};

}  // namespace mtled::cuda
