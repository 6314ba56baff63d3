#include "lodestone/gpu/backend.h"

#include "device_query.h"
#include "lodestone/core/base/error.h"

namespace lodestone {
namespace gpu {

const char* toString(Backend backend) {
  switch (backend) {
    case Backend::Cpu:
      return "cpu";
    case Backend::Cuda:
      return "cuda";
    case Backend::Auto:
      return "auto";
  }
  return "unknown";
}

Backend parseBackend(const std::string& text) {
  if (text == "cpu") return Backend::Cpu;
  if (text == "cuda") return Backend::Cuda;
  if (text == "auto") return Backend::Auto;
  throw InvalidArgument(concat("backend must be \"cpu\", \"cuda\" or \"auto\", got \"", text, "\""));
}

bool cudaBuilt() { return detail::cudaCompiledIn(); }

bool deviceAvailable() {
  std::string status;
  return detail::queryDevice(status);
}

std::string backendStatus() {
  std::string status;
  detail::queryDevice(status);
  return status;
}

Backend resolveBackend(Backend requested, std::string* message) {
  if (message) message->clear();
  switch (requested) {
    case Backend::Cpu:
      return Backend::Cpu;
    case Backend::Cuda: {
      std::string status;
      if (!detail::queryDevice(status)) throw Error(concat("CUDA backend requested but not usable: ", status));
      return Backend::Cuda;
    }
    case Backend::Auto: {
      std::string status;
      if (detail::queryDevice(status)) return Backend::Cuda;
      if (message) *message = concat("no usable CUDA device (", status, "): running on the CPU");
      return Backend::Cpu;
    }
  }
  throw InvalidArgument(concat("unknown backend ", int(requested)));
}

}  // namespace gpu
}  // namespace lodestone
