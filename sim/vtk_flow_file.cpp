#include "sim/vtk_flow_file.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <vector>

#include <vtkCallbackCommand.h>
#include <vtkCellData.h>
#include <vtkCommand.h>
#include <vtkDataArray.h>
#include <vtkDataSet.h>
#include <vtkDataSetReader.h>
#include <vtkGenericCell.h>
#include <vtkIdList.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkSmartPointer.h>
#include <vtkStaticCellLocator.h>
#include <vtkXMLImageDataReader.h>
#include <vtkXMLUnstructuredGridReader.h>

#include "util/input_error.h"
#include "util/input_file.h"

namespace glasspiv {
namespace {

// Collects VTK's error messages (instead of VTK printing them) so that they
// become one InputError.
struct ErrorSink {
  std::string first;
  static void record(vtkObject*, unsigned long, void* client, void* call) {
    auto* sink = static_cast<ErrorSink*>(client);
    if (sink->first.empty() && call) sink->first = static_cast<const char*>(call);
  }
};

std::string trimmed(std::string s) {
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
  const auto cut = s.find_last_of('\n');
  return cut == std::string::npos ? s : s.substr(cut + 1);
}

vtkDataArray* velocity_array(vtkDataSetAttributes* attributes, const std::string& name) {
  if (!attributes) return nullptr;
  if (!name.empty()) return attributes->GetArray(name.c_str());
  for (const char* known : {"U", "velocity", "Velocity"})
    if (vtkDataArray* a = attributes->GetArray(known)) return a;
  vtkDataArray* only = nullptr;
  for (int i = 0; i < attributes->GetNumberOfArrays(); ++i) {
    vtkDataArray* a = attributes->GetArray(i);
    if (a && a->GetNumberOfComponents() == 3) {
      if (only) return nullptr;  // ambiguous: the caller must name it
      only = a;
    }
  }
  return only;
}

}  // namespace

VtkFlow::~VtkFlow() {
  if (locator_) locator_->Delete();
  if (data_) data_->Delete();
}

long long VtkFlow::find_cell(const Eigen::Vector3d& point_mm, vtkGenericCell* cell, double* weights) const {
  double x[3];
  for (int a = 0; a < 3; ++a) x[a] = point_mm[a] / options_.mm_per_file_length;
  double pcoords[3];
  return locator_->FindCell(x, 0.0, cell, pcoords, weights);
}

bool VtkFlow::covers(const Eigen::Vector3d& point_mm) const {
  vtkNew<vtkGenericCell> cell;
  std::vector<double> weights(static_cast<std::size_t>(std::max(max_cell_size_, 1)));
  return find_cell(point_mm, cell, weights.data()) >= 0;
}

Eigen::Vector3d VtkFlow::velocity_m_per_s(const Eigen::Vector3d& point_mm, double) const {
  // A cell object and weights per call: the locator's FindCell is thread-safe with them.
  vtkNew<vtkGenericCell> cell;
  std::vector<double> weights(static_cast<std::size_t>(std::max(max_cell_size_, 1)));
  const long long id = find_cell(point_mm, cell, weights.data());
  if (id < 0) return Eigen::Vector3d::Zero();
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  double tuple[3];
  if (!point_data_) {
    velocity_->GetTuple(id, tuple);
    v = Eigen::Vector3d(tuple[0], tuple[1], tuple[2]);
  } else {
    vtkIdList* points = cell->GetPointIds();
    for (vtkIdType i = 0; i < points->GetNumberOfIds(); ++i) {
      velocity_->GetTuple(points->GetId(i), tuple);
      v += weights[static_cast<std::size_t>(i)] * Eigen::Vector3d(tuple[0], tuple[1], tuple[2]);
    }
  }
  return options_.m_per_s_per_file_velocity * v;
}

std::shared_ptr<const VtkFlow> read_vtk_flow(const std::string& path, const VtkFlowOptions& options) {
  if (!(options.mm_per_file_length > 0) || !std::isfinite(options.mm_per_file_length) ||
      !std::isfinite(options.m_per_s_per_file_velocity))
    throw InputError(path, "", "length and velocity units must be finite, the length unit > 0");
  check_input_file(path);  // a regular file (a fifo would block the VTK reader)
  const std::string ext = std::filesystem::path(path).extension().string();

  ErrorSink sink;
  vtkNew<vtkCallbackCommand> on_error;
  on_error->SetCallback(&ErrorSink::record);
  on_error->SetClientData(&sink);
  vtkSmartPointer<vtkDataSet> data;
  if (ext == ".vti" || ext == ".vtu") {
    vtkSmartPointer<vtkXMLReader> reader;
    if (ext == ".vti")
      reader = vtkSmartPointer<vtkXMLImageDataReader>::New();
    else
      reader = vtkSmartPointer<vtkXMLUnstructuredGridReader>::New();
    reader->AddObserver(vtkCommand::ErrorEvent, on_error);
    reader->AddObserver(vtkCommand::WarningEvent, on_error);
    if (!reader->CanReadFile(path.c_str())) throw InputError(path, "", "not a VTK XML " + ext + " file");
    reader->SetFileName(path.c_str());
    reader->Update();
    if (reader->GetErrorCode() != 0 || !sink.first.empty())
      throw InputError(path, "", "VTK cannot read it: " + trimmed(sink.first));
    data = vtkDataSet::SafeDownCast(reader->GetOutputDataObject(0));
  } else if (ext == ".vtk") {
    vtkNew<vtkDataSetReader> reader;
    reader->AddObserver(vtkCommand::ErrorEvent, on_error);
    reader->AddObserver(vtkCommand::WarningEvent, on_error);
    reader->SetFileName(path.c_str());
    reader->ReadAllVectorsOn();
    reader->ReadAllScalarsOn();
    reader->Update();
    if (reader->GetErrorCode() != 0 || !sink.first.empty())
      throw InputError(path, "", "VTK cannot read it: " + trimmed(sink.first));
    data = reader->GetOutput();
  } else {
    throw InputError(path, "", "unknown extension '" + ext + "' (expected .vti, .vtu or .vtk)");
  }
  if (!data || data->GetNumberOfCells() == 0) throw InputError(path, "", "the file holds no cells");

  std::shared_ptr<VtkFlow> flow(new VtkFlow());
  flow->file_ = path;
  flow->options_ = options;
  flow->point_data_ = true;
  vtkDataArray* velocity = velocity_array(data->GetPointData(), options.array);
  if (!velocity) {
    velocity = velocity_array(data->GetCellData(), options.array);
    flow->point_data_ = false;
  }
  const std::string field = options.array.empty() ? "velocity" : options.array;
  if (!velocity)
    throw InputError(path, field,
                     options.array.empty() ? "no velocity array (U, velocity, Velocity or a single 3-component array)"
                                           : "no such point or cell array");
  if (velocity->GetNumberOfComponents() != 3) throw InputError(path, field, "the array is not 3-component");
  flow->array_name_ = velocity->GetName() ? velocity->GetName() : "";
  for (vtkIdType i = 0; i < velocity->GetNumberOfTuples(); ++i)
    for (int c = 0; c < 3; ++c)
      if (!std::isfinite(velocity->GetComponent(i, c)))
        throw InputError(path, flow->array_name_,
                         "NaN or infinite velocity at " + std::string(flow->point_data_ ? "point " : "cell ") +
                             std::to_string(i));

  data->Register(nullptr);
  flow->data_ = data;
  flow->velocity_ = velocity;
  flow->max_cell_size_ = data->GetMaxCellSize();
  flow->locator_ = vtkStaticCellLocator::New();
  flow->locator_->SetDataSet(data);
  flow->locator_->BuildLocator();
  return flow;
}

void check_covers_slab(const VtkFlow& flow, const Sheet& sheet, double half_depth_mm, double margin_mm,
                       const SolidInteriors& solids, int samples_per_side) {
  const int n = std::max(samples_per_side, 2);
  const double half_s = sheet.extent_mm[0] / 2 + margin_mm, half_t = sheet.extent_mm[1] / 2 + margin_mm;
  const Eigen::Vector3d normal = sheet.normal();
  for (int k = 0; k < 5; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const double s = -half_s + 2 * half_s * i / (n - 1), t = -half_t + 2 * half_t * j / (n - 1);
        const double z = -half_depth_mm + 2 * half_depth_mm * k / 4;
        const Eigen::Vector3d p = sheet.origin_mm + s * sheet.s_axis + t * sheet.t_axis + z * normal;
        if (!solids.inside(p) && !flow.covers(p))
          throw InputError(flow.file(), flow.array_name(),
                           "the field does not cover the tracers' slab: no data at (" + std::to_string(p.x()) + ", " +
                               std::to_string(p.y()) + ", " + std::to_string(p.z()) + ") mm");
      }
}

}  // namespace glasspiv
