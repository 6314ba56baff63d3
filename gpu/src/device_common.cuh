#pragma once
// Small CUDA utilities of the backend: error checks that throw
// lodestone::Error, an owning device buffer, a grid-stride for-each over
// extended lambdas, and a deterministic two-pass sum (fixed launch shape,
// fixed tree order: the same inputs give the same bits on the same device).
#include <cuda_runtime.h>

#include <cstddef>
#include <string>
#include <utility>

#include "lodestone/core/base/error.h"

namespace lodestone {
namespace gpu {
namespace detail {

inline void cudaCheck(cudaError_t e, const char* what) {
  if (e != cudaSuccess) throw Error(concat("CUDA error in ", what, ": ", cudaGetErrorString(e)));
}
#define LODESTONE_CUDA_CHECK(call) ::lodestone::gpu::detail::cudaCheck((call), #call)

template <typename T>
class DeviceBuffer {
 public:
  DeviceBuffer() = default;
  explicit DeviceBuffer(std::size_t n) { resize(n); }
  ~DeviceBuffer() { release(); }
  DeviceBuffer(const DeviceBuffer&) = delete;
  DeviceBuffer& operator=(const DeviceBuffer&) = delete;
  DeviceBuffer(DeviceBuffer&& o) noexcept : p_(std::exchange(o.p_, nullptr)), n_(std::exchange(o.n_, 0)) {}
  DeviceBuffer& operator=(DeviceBuffer&& o) noexcept {
    if (this != &o) {
      release();
      p_ = std::exchange(o.p_, nullptr);
      n_ = std::exchange(o.n_, 0);
    }
    return *this;
  }
  /// Reallocates (contents lost) when the size changes.
  void resize(std::size_t n) {
    if (n == n_) return;
    release();
    if (n > 0) LODESTONE_CUDA_CHECK(cudaMalloc(reinterpret_cast<void**>(&p_), n * sizeof(T)));
    n_ = n;
  }
  void upload(const T* host, std::size_t n) {
    resize(n);
    if (n > 0) LODESTONE_CUDA_CHECK(cudaMemcpy(p_, host, n * sizeof(T), cudaMemcpyHostToDevice));
  }
  void download(T* host, std::size_t n) const {
    if (n > 0) LODESTONE_CUDA_CHECK(cudaMemcpy(host, p_, n * sizeof(T), cudaMemcpyDeviceToHost));
  }
  void zero() {
    if (n_ > 0) LODESTONE_CUDA_CHECK(cudaMemset(p_, 0, n_ * sizeof(T)));
  }
  T* data() { return p_; }
  const T* data() const { return p_; }
  std::size_t size() const { return n_; }

 private:
  void release() {
    if (p_) cudaFree(p_);
    p_ = nullptr;
    n_ = 0;
  }
  T* p_ = nullptr;
  std::size_t n_ = 0;
};

constexpr int kThreads = 256;

template <typename Fn>
__global__ void forEachKernel(std::size_t n, Fn fn) {
  for (std::size_t m = std::size_t(blockIdx.x) * blockDim.x + threadIdx.x; m < n;
       m += std::size_t(gridDim.x) * blockDim.x)
    fn(m);
}

/// fn(m) for m in [0, n) on the device (asynchronous; errors checked at launch).
template <typename Fn>
void forEach(std::size_t n, Fn fn) {
  if (n == 0) return;
  const std::size_t blocks = (n + kThreads - 1) / kThreads;
  const unsigned grid = unsigned(blocks < 65535u * 16u ? blocks : 65535u * 16u);
  forEachKernel<<<grid, kThreads>>>(n, fn);
  LODESTONE_CUDA_CHECK(cudaGetLastError());
}

constexpr int kReduceBlocks = 1024;

/// Partial sums of value(m) over a grid-stride range, one per block.
template <typename Fn>
__global__ void partialSumKernel(std::size_t n, Fn value, double* partial) {
  __shared__ double s[kThreads];
  double acc = 0;
  for (std::size_t m = std::size_t(blockIdx.x) * blockDim.x + threadIdx.x; m < n;
       m += std::size_t(gridDim.x) * blockDim.x)
    acc += value(m);
  s[threadIdx.x] = acc;
  __syncthreads();
  for (int w = kThreads / 2; w > 0; w /= 2) {
    if (int(threadIdx.x) < w) s[threadIdx.x] += s[threadIdx.x + w];
    __syncthreads();
  }
  if (threadIdx.x == 0) partial[blockIdx.x] = s[0];
}

template <int Blocks>
__global__ void finalSumKernel(const double* partial, int count, double* out) {
  __shared__ double s[Blocks];
  s[threadIdx.x] = int(threadIdx.x) < count ? partial[threadIdx.x] : 0.0;
  __syncthreads();
  for (int w = Blocks / 2; w > 0; w /= 2) {
    if (int(threadIdx.x) < w) s[threadIdx.x] += s[threadIdx.x + w];
    __syncthreads();
  }
  if (threadIdx.x == 0) *out = s[0];
}

/// Deterministic sum of value(m), m in [0, n), returned to the host.
class Reducer {
 public:
  Reducer() : partial_(kReduceBlocks), result_(1) {}
  template <typename Fn>
  double sum(std::size_t n, Fn value) {
    if (n == 0) return 0.0;
    const std::size_t need = (n + kThreads - 1) / kThreads;
    const int blocks = int(need < std::size_t(kReduceBlocks) ? need : std::size_t(kReduceBlocks));
    partialSumKernel<<<blocks, kThreads>>>(n, value, partial_.data());
    LODESTONE_CUDA_CHECK(cudaGetLastError());
    finalSumKernel<kReduceBlocks><<<1, kReduceBlocks>>>(partial_.data(), blocks, result_.data());
    LODESTONE_CUDA_CHECK(cudaGetLastError());
    double out = 0;
    result_.download(&out, 1);
    return out;
  }

 private:
  DeviceBuffer<double> partial_, result_;
};

}  // namespace detail
}  // namespace gpu
}  // namespace lodestone
