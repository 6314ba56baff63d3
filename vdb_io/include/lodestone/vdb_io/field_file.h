#pragma once
// VDB files of the magnetic stage's nodal fields (see docs/vdb.md for the
// grid names, units, vector types and metadata keys). No OpenVDB types here.
#include <cstdint>
#include <memory>
#include <string>

#include "lodestone/core/sources/field_source.h"
#include "lodestone/core/base/grid.h"
#include "lodestone/core/stage/magnetic_stage.h"
#include "lodestone/core/base/vec3.h"

namespace lodestone {

/// Which fields writeFieldsVdb writes (grid names in brackets).
struct VdbFieldChoice {
  bool density = true;        ///< [n]     micro-particle density, 1/m^3
  bool potential = true;      ///< [phi]   magnetic scalar potential, A
  bool field = true;          ///< [H]     magnetic field, A/m
  bool magnetization = true;  ///< [M]     magnetization, A/m
  bool induction = true;      ///< [B]     magnetic induction, T
  bool force = true;          ///< [force] force density t = div T, N/m^3
  bool mass = false;          ///< [mass]  MPM node mass, kg (needs VdbWriteOptions::mpm.mass)
  bool velocity = false;      ///< [velocity] MPM node velocity, m/s (needs VdbWriteOptions::mpm.velocity)
};

/// MPM grid data a host adds to a field file. They live on the MPM grid,
/// which need not be the field grid (each grid of a file has its own
/// transform). A null `data` means absent.
struct VdbMpmGrids {
  GridView<const double> mass;     ///< node mass, kg
  GridView<const Vec3d> velocity;  ///< node velocity, m/s
};

/// Options of writeFieldsVdb.
struct VdbWriteOptions {
  VdbFieldChoice fields;
  bool doublePrecision = false;  ///< DoubleGrid / Vec3dGrid instead of float
  /// Absolute sparsity tolerance per grid, in that grid's unit (0: only exact
  /// zeros stay inactive).
  double toleranceDensity = 0, tolerancePotential = 0, toleranceField = 0,
         toleranceMagnetization = 0, toleranceInduction = 0, toleranceForce = 0;
  /// Also write the names other tools look for: [density] (= n, fog volume;
  /// Blender shows the alphabetically first grid, Houdini's Volume SOPs
  /// default to it) and [vel] (= velocity, when given; Blender's and
  /// Houdini's velocity name). The copies share their source's transform.
  bool displayAliases = false;
  VdbMpmGrids mpm;  ///< source of the mass and velocity grids
};

/// File-level metadata written with the grids.
struct VdbFrameMetadata {
  std::int64_t frame = 0;       ///< [frame]
  double time = 0;              ///< [time_s] simulation time, s
  std::string lawDescription;   ///< [law] empty: the stage's material description
  std::string solverSummary;    ///< [solver_report] e.g. MagneticStageReport::summary()
};

/// Writes the chosen fields of the stage's last run to one .vdb file,
/// atomically (temporary file in the same directory, then rename).
/// Throws InvalidArgument naming the file on failure; the target is untouched then.
void writeFieldsVdb(const std::string& path, const MagneticForceStage& stage,
                    const VdbFrameMetadata& metadata, const VdbWriteOptions& options = {});

/// Reads grid `gridName` (FloatGrid or DoubleGrid) into a dense grid on `spec`
/// (exact by index when the file's transform matches spec, else trilinear).
DenseGrid<double> readScalarField(const std::string& path, const std::string& gridName,
                                  const GridSpec& spec);
/// The micro-particle density n (1/m^3) of grid `gridName` (FloatGrid or
/// DoubleGrid) on `spec`, as readScalarField, for hosts that do their own
/// particle-to-grid transfer and call MagneticForceStage::runOnDensity.
/// Throws InvalidArgument naming the file, the grid and the node when a value
/// is negative or not finite.
DenseGrid<double> readDensityVdb(const std::string& path, const GridSpec& spec, const std::string& gridName = "n");
/// Reads grid `gridName` (Vec3fGrid or Vec3dGrid) into a dense grid on `spec`.
DenseGrid<Vec3d> readVec3Field(const std::string& path, const std::string& gridName,
                               const GridSpec& spec);

/// An applied field H (A/m) read from a vector grid of a .vdb file. Values are
/// trilinear in world space over the voxel centres; inactive voxels count as
/// `background`, so inside the active region the grid's values are
/// interpolated, far outside it the field is `background`, and the cell on
/// the rim blends the two. Time-independent; immutable and thread-safe.
class VdbFieldSource : public FieldSource {
 public:
  /// Throws InvalidArgument naming the file and grid when it cannot be read.
  VdbFieldSource(const std::string& path, const std::string& gridName, const Vec3d& background = {});

  Vec3d field(const Vec3d& x, double t) const override;
  std::string describe() const override;
  std::unique_ptr<FieldSource> clone() const override;

  const Vec3d& background() const;
  std::size_t activeVoxelCount() const;

  struct Impl;

 private:
  std::shared_ptr<const Impl> impl_;
};

}  // namespace lodestone
