#pragma once
// Device discovery, implemented by device_query.cu (CUDA built) or
// no_cuda.cpp (not built).
#include <string>

namespace lodestone {
namespace gpu {
namespace detail {

/// True when the CUDA backend was compiled in.
bool cudaCompiledIn();
/// True when a device can be used; `status` receives backendStatus()'s line.
/// The query runs once per process; later calls return the cached answer.
bool queryDevice(std::string& status);

}  // namespace detail
}  // namespace gpu
}  // namespace lodestone
