#pragma once
// Memory a simulation needs, estimated from what it will hold before anything
// is allocated, and what the process holds, measured.
//
// The figures per node and per particle were measured as the peak resident
// memory of `lodestone run` on scenes that vary one count at a time
// (docs/benchmarks.md, "Memory"): with the process's own resident memory
// at the time of the estimate added, the estimate is within 20% of the
// measured peak (test lodestone_memory_estimate).
#include <string>

namespace lodestone {
namespace plugin {

/// Bytes per MPM grid node: mass, momentum and velocity, the stencil bins
/// and their offsets (measured: 63 B at 2.2M nodes).
constexpr double kMpmNodeBytes = 64;
/// Further bytes per MPM grid node when a material has surface tension (the
/// colour field).
constexpr double kSurfaceTensionNodeBytes = 8;
/// Bytes per node of the field solve's (padded) grid: n, phi, the applied
/// and total fields, M, B, the force, the Newton-PCG vectors and the
/// multigrid levels (measured: 356 B at 2.6M nodes).
constexpr double kFieldNodeBytes = 356;
/// Further bytes per material cell of the field solve (a cell with a corner
/// where n > 0): n and the applied field at its 8 Gauss points, its element
/// matrix, mean tensor and moments, its rows of the material stencil and
/// their single-precision copy in the multigrid. Fitted together with
/// kMagneticParticleBytes to the peaks of magnetic bodies from a compact cube
/// at 27 points a cell to a 2.4 cm slab and a 4 cm rod (docs/benchmarks.md,
/// "Memory"; heaptrack counts 1.1-1.3 KB of arrays a cell).
constexpr double kFieldMaterialCellBytes = 1300;
/// Bytes per material point: its state (position, velocity, C, F, J, mass,
/// volume, count, material, id, force: 260 B), its bin key and slot, and the
/// copy a reordering makes (measured: 392 B at 1.0M particles).
constexpr double kParticleBytes = 392;
/// Further bytes per magnetic material point: the magnetic stage's binning
/// of the points on the field grid, their forces and weights (fitted with
/// kFieldMaterialCellBytes).
constexpr double kMagneticParticleBytes = 150;
/// Further bytes per material point with surface tension (its capillary stress).
constexpr double kSurfaceTensionParticleBytes = 72;
/// Bytes per pixel of a frame preview: colour, depth, edge mask and the PNG
/// encoder's buffers (measured: 14 B at 640 x 480).
constexpr double kPreviewPixelBytes = 16;
/// Bytes per field-solve node while the field grids are written as OpenVDB
/// (measured: 28 B at 2.6M nodes).
constexpr double kFieldFileNodeBytes = 28;
/// Bytes per material point while its surface (level set, mesh or render
/// volume) is built (measured: 480-550 B at 0.11M-0.14M particles).
constexpr double kSurfaceParticleBytes = 560;

/// What a simulation holds at its largest.
struct MemoryCounts {
  double mpmNodes = 0;           ///< nodes of the MPM grid that hold memory: the runs the material reaches
  /// The bytes the MPM grid's pages take for those runs (mpmHeldBytes); 0:
  /// mpmNodes * kMpmNodeBytes (the whole grid or a partition's window, held whole).
  double mpmGridBytes = 0;
  double fieldNodes = 0;         ///< nodes of the field solve's grid (0: nothing magnetic ever)
  double fieldMaterialCells = 0;  ///< of its cells, those the magnetic material makes material cells
  double particles = 0;          ///< material points, the most the run has at once
  double magneticParticles = 0;  ///< of them, magnetic
  double capillaryParticles = 0;  ///< of them, of a material with surface tension (the colour field is on when > 0)
  double previewPixels = 0;       ///< pixels of a frame preview (0: none written)
  double fieldFileNodes = 0;      ///< field-solve nodes written as OpenVDB grids (0: none)
  double surfaceParticles = 0;    ///< material points whose surface is built (0: none)
};

/// The estimate by part, bytes.
struct MemoryEstimate {
  double mpmGrid = 0;    ///< the MPM grid
  double fieldGrid = 0;  ///< the field solve
  double particles = 0;  ///< the material points and their per-particle scratch
  double outputs = 0;    ///< frame files: previews, field grids, surfaces
  double process = 0;    ///< what the process already held (libraries, the scene), measured
  double total() const { return mpmGrid + fieldGrid + particles + outputs + process; }
  /// "1.2 GiB: MPM grid 0.13, field solve 0.98, particles 0.07, process 0.03 (GiB)".
  std::string describe() const;
};

/// The estimate of `counts`, with `processBytes` as what the process holds
/// besides them: e.g. residentBytes() once the scene's files (meshes, level
/// sets) are loaded, which counts the program and its libraries too.
MemoryEstimate estimateMemory(const MemoryCounts& counts, double processBytes = 0);

/// A conservative estimate, bytes, for a grid that may serve both the MPM and
/// the field solve, and magnetic particles at 8 a cell: nodes *
/// (kMpmNodeBytes + kFieldNodeBytes) + particles * (kParticleBytes +
/// kMagneticParticleBytes) + particles / 8 material cells.
double estimatedMemoryBytes(double nodes, double particles);

/// The part of the machine's memory a run may plan to use: the rest is the
/// system's and the estimate's margin (the measured peak is within 20% of
/// the estimate; a run planned at the whole memory was killed for memory).
constexpr double kUsableMemoryFraction = 0.8;

/// What an estimate is compared with, bytes: kUsableMemoryFraction of the
/// machine's physical memory or of the memory limit of the process's control
/// group (cgroup v2 memory.max or v1 memory.limit_in_bytes), whichever is
/// smaller; or the environment variable LODESTONE_MEMORY_LIMIT_GIB when it is
/// set (a positive number of GiB, taken as it is; anything else throws
/// InvalidArgument).
double memoryLimitBytes();
/// Where memoryLimitBytes() comes from, with its value: "18.8 GiB (80% of
/// this machine's memory, 23.5 GiB)", "6.4 GiB (80% of this process's control
/// group's limit, 8 GiB)" or "LODESTONE_MEMORY_LIMIT_GIB = 2 GiB".
std::string memoryLimitText();

/// The process's resident memory now, bytes (0 where it cannot be read).
double residentBytes();
/// The process's peak resident memory so far, bytes (0 where it cannot be read).
double peakResidentBytes();

}  // namespace plugin
}  // namespace lodestone
