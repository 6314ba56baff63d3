// Device discovery: the first visible device, checked to run this build's
// kernels (an image for its architecture), queried once per process.
#include <cuda_runtime.h>

#include <cstdio>
#include <mutex>
#include <string>

#include "device_query.h"

namespace lodestone {
namespace gpu {
namespace detail {

namespace {
__global__ void probeKernel(int* out) { *out = 1; }

struct DeviceAnswer {
  bool usable = false;
  std::string status;
};

DeviceAnswer ask() {
  DeviceAnswer a;
  int count = 0;
  const cudaError_t e = cudaGetDeviceCount(&count);
  if (e != cudaSuccess) {
    a.status = std::string("built, no device: ") + cudaGetErrorString(e);
    cudaGetLastError();
    return a;
  }
  if (count == 0) {
    a.status = "built, no device";
    return a;
  }
  int device = 0;
  cudaGetDevice(&device);
  cudaDeviceProp prop{};
  if (cudaGetDeviceProperties(&prop, device) != cudaSuccess) {
    a.status = std::string("built, no device: ") + cudaGetErrorString(cudaGetLastError());
    return a;
  }
  char line[512];
  std::snprintf(line, sizeof line, "device %d: %s (sm_%d%d, %.1f GiB)", device, prop.name, prop.major, prop.minor,
                double(prop.totalGlobalMem) / (1024.0 * 1024.0 * 1024.0));
  cudaFuncAttributes attr{};
  const cudaError_t k = cudaFuncGetAttributes(&attr, probeKernel);
  if (k != cudaSuccess) {
    cudaGetLastError();
    a.status =
        std::string("built, no device: ") + line + " cannot run this build's kernels (" + cudaGetErrorString(k) + ")";
    return a;
  }
  a.usable = true;
  a.status = line;
  return a;
}
}  // namespace

bool cudaCompiledIn() { return true; }

bool queryDevice(std::string& status) {
  static std::once_flag once;
  static DeviceAnswer answer;
  std::call_once(once, [] { answer = ask(); });
  status = answer.status;
  return answer.usable;
}

}  // namespace detail
}  // namespace gpu
}  // namespace lodestone
