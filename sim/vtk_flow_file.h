#pragma once
// CFD velocity fields from VTK files: .vti (image data), .vtu (unstructured
// grid) and legacy .vtk (any dataset), read with VTK. The field is steady (time
// is ignored). Point data are interpolated within the cell holding the point by
// the cell's own shape functions (trilinear in voxels and hexahedra, linear in
// tetrahedra); cell data are constant per cell. Outside every cell the velocity
// is zero (solids are holes in a CFD mesh); check_covers_slab refuses a field
// with holes in the tracers' slab other than the solids. docs/simulation.md.
#include <memory>
#include <string>

#include <Eigen/Core>

#include "render/scene.h"
#include "sim/flows.h"

class vtkDataSet;
class vtkDataArray;
class vtkGenericCell;
class vtkStaticCellLocator;

namespace glasspiv {

// What a flow file may declare, checked before VTK allocates (docs/limits.md):
// points, cells and the values of any one section; and, in a legacy file, all
// its values together as doubles.
constexpr long long kMaxVtkFlowItems = 50'000'000;
constexpr long long kMaxVtkFlowBytes = 2LL << 30;

struct VtkFlowOptions {
  // The velocity array: "" picks a point-data array named U, velocity or Velocity,
  // else the only 3-component point-data array, else the same among the cell data.
  std::string array;
  double mm_per_file_length = 1000;     // file coordinates in m (CFD's usual SI)
  double m_per_s_per_file_velocity = 1;  // file velocities in m/s
};

class VtkFlow final : public Flow {
 public:
  ~VtkFlow() override;
  Eigen::Vector3d velocity_m_per_s(const Eigen::Vector3d& point_mm, double time_s) const override;
  // Whether point_mm lies in a cell of the data.
  bool covers(const Eigen::Vector3d& point_mm) const;
  const std::string& file() const { return file_; }
  const std::string& array_name() const { return array_name_; }

 private:
  friend std::shared_ptr<const VtkFlow> read_vtk_flow(const std::string& path, const VtkFlowOptions& options);
  VtkFlow() = default;
  // The cell holding the point (-1: none) into *cell, the interpolation weights of its points.
  long long find_cell(const Eigen::Vector3d& point_mm, vtkGenericCell* cell, double* weights) const;
  std::string file_, array_name_;
  VtkFlowOptions options_;
  vtkDataSet* data_ = nullptr;  // owned (reference counted by VTK)
  vtkDataArray* velocity_ = nullptr;
  bool point_data_ = true;
  int max_cell_size_ = 0;
  vtkStaticCellLocator* locator_ = nullptr;
};

// Reads the file (by its extension: .vti, .vtu, .vtk). Before VTK reads it, the
// sizes it declares are checked against the limits above, and a legacy file is
// walked section by section: every data section must hold its declared values
// (binary: within the file's bytes; ASCII: that many finite numbers), so a
// truncated file, a short section or a 'nan' is refused instead of read as
// memory VTK never filled. VTK's own messages are kept off the terminal: its
// first error becomes the problem. Throws InputError(path, field, problem) when
// it cannot be read, declares more than the limits, holds no cells, has no (or
// no such) 3-component velocity array, an array shorter than its points or
// cells, or any point coordinate or velocity component NaN or infinite.
std::shared_ptr<const VtkFlow> read_vtk_flow(const std::string& path, const VtkFlowOptions& options = {});

// Throws InputError(flow.file(), array, ...) unless the field covers the slab
// that tracers are seeded in (TracerSeeding: the sheet's extent grown by
// margin_mm, +-half_depth_mm across), tested at samples_per_side x
// samples_per_side x 5 points spanning it, corners and faces included; points
// inside a solid need no data.
void check_covers_slab(const VtkFlow& flow, const Sheet& sheet, double half_depth_mm, double margin_mm,
                       const SolidInteriors& solids, int samples_per_side = 41);

}  // namespace glasspiv
