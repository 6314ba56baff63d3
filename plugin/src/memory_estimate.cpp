#include "lodestone/plugin/memory_estimate.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

#if __has_include(<unistd.h>)
#include <unistd.h>
#endif
#if __has_include(<sys/resource.h>)
#include <sys/resource.h>
#endif

#include "lodestone/core/base/error.h"

namespace lodestone::plugin {

namespace {
constexpr double kGiB = 1024.0 * 1024.0 * 1024.0;
constexpr const char* kLimitVariable = "LODESTONE_MEMORY_LIMIT_GIB";

/// A positive number of GiB in the environment variable, or 0.
double limitOverrideGiB() {
  const char* text = std::getenv(kLimitVariable);
  if (!text || !*text) return 0;
  char* end = nullptr;
  const double gib = std::strtod(text, &end);
  require(end && *end == '\0' && std::isfinite(gib) && gib > 0, kLimitVariable,
          " must be a positive number of GiB, got '", text, "'");
  return gib;
}

/// The first number in the file at `path` (bytes), or 0 when it holds none
/// ("max": no limit) or cannot be read.
double numberInFile(const char* path) {
  std::ifstream in(path);
  double v = 0;
  if (!(in >> v) || !(v > 0)) return 0;
  return v;
}

/// The memory limit of this process's control group, bytes, or 0 for none.
double cgroupLimitBytes() {
  std::ifstream cgroups("/proc/self/cgroup");
  std::string line;
  while (std::getline(cgroups, line)) {
    // "0::/path" (v2) or "N:memory:/path" (v1).
    const auto first = line.find(':'), second = line.find(':', first + 1);
    if (first == std::string::npos || second == std::string::npos) continue;
    const std::string controllers = line.substr(first + 1, second - first - 1), path = line.substr(second + 1);
    const bool v2 = controllers.empty();
    if (!v2 && controllers.find("memory") == std::string::npos) continue;
    // The group's own file where it is mounted at its path, else the root's.
    for (const std::string& dir : {std::string(v2 ? "/sys/fs/cgroup" : "/sys/fs/cgroup/memory") + path,
                                   std::string(v2 ? "/sys/fs/cgroup" : "/sys/fs/cgroup/memory")}) {
      const double limit = numberInFile((dir + (v2 ? "/memory.max" : "/memory.limit_in_bytes")).c_str());
      // cgroup v1 says "no limit" as a huge number (about 2^63).
      if (limit > 0 && limit < 1e18) return limit;
    }
  }
  return 0;
}

std::string gib(double bytes) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", bytes / kGiB);
  return text;
}
}  // namespace

std::string MemoryEstimate::describe() const {
  std::string s = gib(total()) + " GiB: MPM grid " + gib(mpmGrid);
  if (fieldGrid > 0) s += ", field solve " + gib(fieldGrid);
  s += ", particles " + gib(particles);
  if (outputs > 0) s += ", frame files " + gib(outputs);
  if (process > 0) s += ", process " + gib(process);
  return s + " (GiB)";
}

MemoryEstimate estimateMemory(const MemoryCounts& c, double processBytes) {
  MemoryEstimate e;
  e.mpmGrid = c.mpmGridBytes > 0 ? c.mpmGridBytes
                                  : c.mpmNodes * (kMpmNodeBytes + (c.capillaryParticles > 0 ? kSurfaceTensionNodeBytes : 0.0));
  e.fieldGrid = c.fieldNodes * kFieldNodeBytes + c.fieldMaterialCells * kFieldMaterialCellBytes;
  e.particles = c.particles * kParticleBytes + c.magneticParticles * kMagneticParticleBytes +
                c.capillaryParticles * kSurfaceTensionParticleBytes;
  e.outputs = c.previewPixels * kPreviewPixelBytes + c.fieldFileNodes * kFieldFileNodeBytes +
              c.surfaceParticles * kSurfaceParticleBytes;
  e.process = processBytes;
  return e;
}

double estimatedMemoryBytes(double nodes, double particles) {
  MemoryCounts c;
  c.mpmNodes = c.fieldNodes = nodes;
  c.particles = c.magneticParticles = particles;
  c.fieldMaterialCells = std::min(nodes, particles / 8);
  return estimateMemory(c).total();
}

namespace {
// The machine's physical memory or the control group's limit, whichever is
// smaller, bytes, and which of the two it is.
struct MachineMemory {
  double bytes = 0;
  bool controlGroup = false;
};

MachineMemory machineMemory() {
  double physical = 16 * kGiB;  // unknown: a modest machine
#if defined(_SC_PHYS_PAGES) && defined(_SC_PAGE_SIZE)
  const long pages = sysconf(_SC_PHYS_PAGES), pageSize = sysconf(_SC_PAGE_SIZE);
  if (pages > 0 && pageSize > 0) physical = double(pages) * double(pageSize);
#endif
  const double group = cgroupLimitBytes();
  if (group > 0 && group <= physical) return {group, true};
  return {physical, false};
}
}  // namespace

double memoryLimitBytes() {
  if (const double gibs = limitOverrideGiB(); gibs > 0) return gibs * kGiB;
  return kUsableMemoryFraction * machineMemory().bytes;
}

std::string memoryLimitText() {
  if (const double gibs = limitOverrideGiB(); gibs > 0) return concat(kLimitVariable, " = ", gib(gibs * kGiB), " GiB");
  const MachineMemory machine = machineMemory();
  const char* of = machine.controlGroup ? "this process's control group's limit" : "this machine's memory";
  return concat(gib(kUsableMemoryFraction * machine.bytes), " GiB (", int(std::lround(100 * kUsableMemoryFraction)),
                "% of ", of, ", ", gib(machine.bytes), " GiB)");
}

double residentBytes() {
#if defined(_SC_PAGE_SIZE)
  std::ifstream statm("/proc/self/statm");
  double size = 0, resident = 0;
  if (statm >> size >> resident) return resident * double(sysconf(_SC_PAGE_SIZE));
#endif
  return 0;
}

double peakResidentBytes() {
#if __has_include(<sys/resource.h>)
  rusage usage{};
  if (getrusage(RUSAGE_SELF, &usage) == 0) return double(usage.ru_maxrss) * 1024.0;  // Linux: KiB
#endif
  return 0;
}

}  // namespace lodestone::plugin
