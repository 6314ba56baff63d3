// The CUDA entry points when the library is built without CUDA: the backend
// reports "not built" and never selects the device.
#include "device_entry.h"
#include "device_query.h"
#include "field_backend.h"
#include "lodestone/core/base/error.h"
#include "mpm_backend.h"

namespace lodestone {
namespace gpu {
namespace detail {

namespace {
[[noreturn]] void notBuilt(const char* what) {
  throw Error(concat(what, ": the CUDA backend is not built (configure with a CUDA compiler)"));
}
}  // namespace

bool cudaCompiledIn() { return false; }

bool queryDevice(std::string& status) {
  status = "not built";
  return false;
}

std::unique_ptr<FieldBackend> makeDeviceFieldBackend() { notBuilt("gpu field solve"); }

std::unique_ptr<MpmBackend> makeDeviceMpm(const kernels::MpmDims&, const std::vector<MpmMaterialParams>&) {
  notBuilt("gpu MPM");
}

void deviceMagneticForce(const kernels::Dims&, const MagnetizationLaw<double>&, const MagneticForceInput&,
                         const MagneticForceOutput&) {
  notBuilt("gpu magnetic force");
}

}  // namespace detail
}  // namespace gpu
}  // namespace lodestone
