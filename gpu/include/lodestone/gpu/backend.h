#pragma once
// Which backend runs the field solve and the MPM kernels: the CPU (the host
// reference implementation of lodestone::gpu, serial and dependency-free),
// the CUDA device, or `auto` (the device when one is present, else the CPU
// with a message saying why). Plain C++: callable whether or not CUDA was
// built.
#include <string>

namespace lodestone {
namespace gpu {

enum class Backend : int {
  Cpu = 0,   ///< host reference implementation (serial loops)
  Cuda = 1,  ///< the CUDA device (throws if not built or no device)
  Auto = 2   ///< Cuda when a device is usable, else Cpu
};

/// "cpu", "cuda", "auto".
const char* toString(Backend backend);
/// Parses "cpu", "cuda" or "auto"; throws lodestone::InvalidArgument naming the text otherwise.
Backend parseBackend(const std::string& text);

/// True when this library was compiled with the CUDA backend.
bool cudaBuilt();
/// True when the CUDA backend is built and a device can be used.
bool deviceAvailable();

/// One line: "not built" (compiled without CUDA), "built, no device" (with
/// the CUDA runtime's reason when it gives one, after a colon), or
/// "device N: <name> (sm_XY, <memory> GiB)".
std::string backendStatus();

/// The backend `requested` resolves to: Cpu stays Cpu; Cuda throws
/// lodestone::Error with backendStatus() when no device is usable; Auto picks
/// Cuda when a device is usable, else Cpu and writes the reason to *message
/// (when message != nullptr; it is cleared otherwise).
Backend resolveBackend(Backend requested, std::string* message = nullptr);

}  // namespace gpu
}  // namespace lodestone
