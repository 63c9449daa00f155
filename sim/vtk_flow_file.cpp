#include "sim/vtk_flow_file.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>
#include <vector>

#include <vtkCallbackCommand.h>
#include <vtkCellData.h>
#include <vtkCommand.h>
#include <vtkDataArray.h>
#include <vtkDataSet.h>
#include <vtkDataSetReader.h>
#include <vtkGenericCell.h>
#include <vtkIdList.h>
#include <vtkLogger.h>
#include <vtkNew.h>
#include <vtkObjectFactory.h>
#include <vtkOutputWindow.h>
#include <vtkPointData.h>
#include <vtkPointSet.h>
#include <vtkPoints.h>
#include <vtkSmartPointer.h>
#include <vtkStaticCellLocator.h>
#include <vtkXMLImageDataReader.h>
#include <vtkXMLUnstructuredGridReader.h>

#include "util/input_error.h"
#include "util/input_file.h"

namespace glasspiv {
namespace {

// VTK's messages, whoever raises them (the reader, its parser, an array it
// fills), go to the output window, and VTK's logger prints them in colour on
// stderr. Both are silenced once for the process; the window hands the errors
// and warnings raised on this thread during a read to that read's sink, so that
// they become one InputError line.
struct VtkMessages {
  std::string first;
};
thread_local VtkMessages* current_messages = nullptr;

class CollectingOutputWindow : public vtkOutputWindow {
 public:
  static CollectingOutputWindow* New();
  vtkTypeMacro(CollectingOutputWindow, vtkOutputWindow);
  void DisplayText(const char*) override {}
  void DisplayDebugText(const char*) override {}
  void DisplayErrorText(const char* text) override { record(text); }
  void DisplayWarningText(const char* text) override { record(text); }
  void DisplayGenericWarningText(const char* text) override { record(text); }

 private:
  static void record(const char* text) {
    if (current_messages && current_messages->first.empty() && text) current_messages->first = text;
  }
};
vtkStandardNewMacro(CollectingOutputWindow);

void silence_vtk_output() {
  static std::once_flag once;
  std::call_once(once, [] {
    vtkLogger::SetStderrVerbosity(vtkLogger::VERBOSITY_OFF);
    vtkNew<CollectingOutputWindow> window;
    vtkOutputWindow::SetInstance(window);
  });
}

// While alive, this thread's VTK messages land in `messages`.
class CollectMessages {
 public:
  explicit CollectMessages(VtkMessages* messages) : previous_(current_messages) {
    silence_vtk_output();
    current_messages = messages;
  }
  ~CollectMessages() { current_messages = previous_; }
  CollectMessages(const CollectMessages&) = delete;
  CollectMessages& operator=(const CollectMessages&) = delete;

 private:
  VtkMessages* previous_;
};

// Observers on the reader: its own errors reach the sink without the window.
struct ErrorSink {
  static void record(vtkObject*, unsigned long, void* client, void* call) {
    auto* messages = static_cast<VtkMessages*>(client);
    if (messages->first.empty() && call) messages->first = static_cast<const char*>(call);
  }
};

// The message's last non-empty line, without VTK's "Class (0x...): " prefix,
// printable ASCII only (a file's bytes can reach VTK's message), at most 200 characters.
std::string trimmed(const std::string& text) {
  std::vector<std::string> lines;
  std::string line;
  std::istringstream in(text);
  while (std::getline(in, line)) {
    while (!line.empty() && std::isspace(static_cast<unsigned char>(line.back()))) line.pop_back();
    if (!line.empty()) lines.push_back(line);
  }
  std::string s = lines.empty() ? "" : lines.back();
  const auto prefix = s.find("): ");
  if (prefix != std::string::npos && s.find(" (0x") != std::string::npos && s.find(" (0x") < prefix)
    s = s.substr(prefix + 3);
  std::string out;
  for (char c : s) out += (c >= 0x20 && c < 0x7f) ? c : '?';
  if (out.size() > 200) out = out.substr(0, 200) + "...";
  return out.empty() ? "no reason given" : out;
}

// --- the sizes a file declares, checked before VTK allocates anything -------

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// A decimal number as VTK's ASCII reader (operator>>) reads it whole: sign,
// digits with at most one point, an optional exponent; finite. Not nan, inf or
// hexadecimal (a stream stops inside those and leaves the value unread).
bool finite_decimal(const std::string& w) {
  std::size_t i = 0;
  if (i < w.size() && (w[i] == '+' || w[i] == '-')) ++i;
  std::size_t digits = 0;
  while (i < w.size() && std::isdigit(static_cast<unsigned char>(w[i]))) ++i, ++digits;
  if (i < w.size() && w[i] == '.') {
    ++i;
    while (i < w.size() && std::isdigit(static_cast<unsigned char>(w[i]))) ++i, ++digits;
  }
  if (digits == 0) return false;
  if (i < w.size() && (w[i] == 'e' || w[i] == 'E')) {
    ++i;
    if (i < w.size() && (w[i] == '+' || w[i] == '-')) ++i;
    std::size_t exponent = 0;
    while (i < w.size() && std::isdigit(static_cast<unsigned char>(w[i]))) ++i, ++exponent;
    if (exponent == 0) return false;
  }
  return i == w.size() && std::isfinite(std::strtod(w.c_str(), nullptr));
}

// Whole number >= 0 from a header token; -1 if it is not one.
long long count_of(const std::string& token) {
  if (token.empty() || token.size() > 18) return -1;
  for (char c : token)
    if (!std::isdigit(static_cast<unsigned char>(c))) return -1;
  return std::stoll(token);
}

// A legacy file walked section by section as VTK's reader would read it: each
// data section's declared values must fit in the bytes left in the file
// (binary) or be that many finite numbers (ASCII), and all of them together
// within kMaxVtkFlowBytes (counted as doubles). Throws InputError(path, section, ...).
class LegacyVtkCheck {
 public:
  explicit LegacyVtkCheck(const std::string& path) : path_(path), in_(path, std::ios::binary) {
    std::error_code ec;
    size_ = std::filesystem::file_size(path, ec);
    if (!in_ || ec) throw InputError(path, "", "cannot be opened");
  }

  void run() {
    std::string line;
    if (!std::getline(in_, line) || lower(line).find("# vtk datafile version") != 0)
      throw InputError(path_, "", "not a legacy VTK file (its first line is not '# vtk DataFile Version')");
    const std::string version = line.substr(std::string("# vtk datafile version").size());
    major_version_ = std::atoi(version.c_str());
    std::getline(in_, line);  // title
    const std::vector<std::string> format = next_line();
    if (format.empty() || (lower(format[0]) != "ascii" && lower(format[0]) != "binary"))
      throw InputError(path_, "", "the third line must be ASCII or BINARY");
    binary_ = lower(format[0]) == "binary";
    for (std::vector<std::string> t = next_line(); !t.empty(); t = next_line()) section(t);
  }

 private:
  // The next non-blank line's words; empty at the end of the file.
  std::vector<std::string> next_line() {
    std::string line;
    while (std::getline(in_, line)) {
      std::istringstream words(line);
      std::vector<std::string> out;
      for (std::string w; words >> w;) out.push_back(w);
      if (!out.empty()) return out;
    }
    return {};
  }

  [[noreturn]] void refuse(const std::string& section, const std::string& problem) const {
    throw InputError(path_, section, problem);
  }

  long long count(const std::vector<std::string>& t, std::size_t i, const std::string& section) const {
    const long long n = i < t.size() ? count_of(t[i]) : -1;
    if (n < 0) refuse(section, "needs a whole number of items (word " + std::to_string(i + 1) + ")");
    if (n > kMaxVtkFlowItems)
      refuse(section, "declares " + std::to_string(n) + " items, over the limit of " +
                          std::to_string(kMaxVtkFlowItems) + " (docs/limits.md)");
    return n;
  }

  static int binary_bytes(const std::string& type) {
    const std::string t = lower(type);
    if (t == "char" || t == "unsigned_char") return 1;
    if (t == "short" || t == "unsigned_short") return 2;
    if (t == "int" || t == "unsigned_int" || t == "float" || t == "vtkidtype") return 4;
    if (t == "long" || t == "unsigned_long" || t == "double" || t == "vtktypeint64" || t == "vtktypeuint64") return 8;
    return 0;
  }

  // `values` numbers of `type`: counted against the memory limit, then skipped
  // (binary: they must fit in the file) or read (ASCII: each a finite number).
  void data(long long values, const std::string& type, const std::string& section) {
    const int bytes = binary_bytes(type);
    if (bytes == 0) refuse(section, "data type '" + type + "' is not one a flow file can hold (numbers only)");
    values_ += values;
    if (static_cast<double>(values_) * 8 > kMaxVtkFlowBytes)
      refuse(section, "the file declares " + std::to_string(values_) + " values so far, over " +
                          std::to_string(kMaxVtkFlowBytes >> 20) + " MiB as doubles (docs/limits.md)");
    if (binary_) {
      const std::uint64_t at = static_cast<std::uint64_t>(in_.tellg());
      const std::uint64_t need = static_cast<std::uint64_t>(values) * static_cast<std::uint64_t>(bytes);
      if (!in_ || at > size_ || need > size_ - at)
        refuse(section, "declares " + std::to_string(values) + " values (" + std::to_string(need) + " bytes) but " +
                            std::to_string(in_ ? size_ - std::min(at, size_) : 0) +
                            " bytes are left in the file: truncated or a short data section");
      in_.seekg(static_cast<std::streamoff>(need), std::ios::cur);
      return;
    }
    std::string word;
    for (long long i = 0; i < values; ++i) {
      if (!(in_ >> word))
        refuse(section, "ends after " + std::to_string(i) + " of its " + std::to_string(values) +
                            " values: truncated or a short data section");
      if (!finite_decimal(word))
        refuse(section, "value " + std::to_string(i + 1) + " of " + std::to_string(values) + " is '" +
                            trimmed(word.substr(0, 40)) + "', not a finite number");
    }
  }

  void section(const std::vector<std::string>& t) {
    const std::string key = lower(t[0]);
    const std::string name = t[0];
    if (key == "dataset") return;
    if (key == "origin" || key == "spacing" || key == "aspect_ratio") {
      for (std::size_t i = 1; i < 4; ++i)
        if (i >= t.size() || !finite_decimal(t[i])) refuse(name, "needs 3 finite numbers");
      return;
    }
    if (key == "dimensions") {
      double points = 1;
      for (std::size_t i = 1; i < 4; ++i) points *= static_cast<double>(std::max(1LL, count(t, i, name)));
      if (points > kMaxVtkFlowItems)
        refuse(name, "declares " + std::to_string(static_cast<long long>(points)) + " points, over the limit of " +
                         std::to_string(kMaxVtkFlowItems) + " (docs/limits.md)");
      return;
    }
    if (key == "points") return data(3 * count(t, 1, name), t.size() > 2 ? t[2] : "", name);
    if (key == "x_coordinates" || key == "y_coordinates" || key == "z_coordinates")
      return data(count(t, 1, name), t.size() > 2 ? t[2] : "", name);
    if (key == "cells" || key == "vertices" || key == "lines" || key == "polygons" || key == "triangle_strips") {
      const long long n = count(t, 1, name), size = count(t, 2, name);
      if (major_version_ < 5) return data(size, "int", name);
      for (int part = 0; part < 2; ++part) {
        const std::vector<std::string> sub = next_line();
        const std::string want = part == 0 ? "offsets" : "connectivity";
        if (sub.empty() || lower(sub[0]) != want) refuse(name, "needs " + want + " next (VTK 5 layout)");
        data(part == 0 ? n : size, sub.size() > 1 ? sub[1] : "", name + " " + sub[0]);
      }
      return;
    }
    if (key == "cell_types") return data(count(t, 1, name), "int", name);
    if (key == "point_data" || key == "cell_data") {
      attribute_count_ = count(t, 1, name);
      return;
    }
    if (key == "scalars") {
      const long long components = t.size() > 3 ? count(t, 3, name) : 1;
      const std::streampos at = in_.tellg();
      const std::vector<std::string> next = next_line();
      if (next.empty() || lower(next[0]) != "lookup_table") in_.seekg(at);
      return data(attribute_count_ * components, t.size() > 2 ? t[2] : "", name + " " + (t.size() > 1 ? t[1] : ""));
    }
    if (key == "lookup_table") return data(4 * count(t, 2, name), binary_ ? "unsigned_char" : "float", name);
    if (key == "color_scalars")
      return data(attribute_count_ * count(t, 2, name), binary_ ? "unsigned_char" : "float", name);
    if (key == "vectors" || key == "normals")
      return data(3 * attribute_count_, t.size() > 2 ? t[2] : "", name + " " + (t.size() > 1 ? t[1] : ""));
    if (key == "texture_coordinates")
      return data(count(t, 2, name) * attribute_count_, t.size() > 3 ? t[3] : "", name);
    if (key == "tensors" || key == "tensors6")
      return data((key == "tensors" ? 9 : 6) * attribute_count_, t.size() > 2 ? t[2] : "", name);
    if (key == "global_ids" || key == "pedigree_ids")
      return data(attribute_count_, t.size() > 2 ? t[2] : "", name);
    if (key == "field") {
      const long long arrays = count(t, 2, name);
      for (long long a = 0; a < arrays; ++a) {
        const std::vector<std::string> array = next_line();
        if (array.size() < 4) refuse(name, "array " + std::to_string(a + 1) + " needs NAME COMPONENTS TUPLES TYPE");
        const std::string field = name + " " + array[0];
        const long long components = count(array, 1, field), tuples = count(array, 2, field);
        if (static_cast<double>(components) * static_cast<double>(tuples) > kMaxVtkFlowItems)
          refuse(field, "declares " + std::to_string(components) + " x " + std::to_string(tuples) +
                            " values, over the limit (docs/limits.md)");
        data(components * tuples, array[3], field);
      }
      return;
    }
    if (key == "metadata") {  // INFORMATION and COMPONENT_NAMES lines up to a blank line
      std::string line;
      while (std::getline(in_, line) && line.find_first_not_of(" \t\r") != std::string::npos) {
      }
      return;
    }
    refuse(trimmed(name.substr(0, 40)), "is not a section of a legacy VTK file a flow can come from");
  }

  std::string path_;
  std::ifstream in_;
  std::uint64_t size_ = 0;
  bool binary_ = false;
  int major_version_ = 3;
  long long attribute_count_ = 0;
  long long values_ = 0;
};

// XML files: the points and cells the pieces declare (NumberOfPoints,
// NumberOfCells, WholeExtent, read from the text before the first data), within
// kMaxVtkFlowItems. Compressed data can be far smaller than what it holds, so
// the file size says nothing here.
void check_xml_sizes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string head(1 << 16, '\0');
  in.read(&head[0], static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(in.gcount()));
  for (const char* attribute : {"NumberOfPoints=\"", "NumberOfCells=\"", "WholeExtent=\""}) {
    for (std::size_t at = head.find(attribute); at != std::string::npos; at = head.find(attribute, at + 1)) {
      const std::size_t from = at + std::strlen(attribute), to = head.find('"', from);
      if (to == std::string::npos) break;
      std::istringstream words(head.substr(from, to - from));
      std::vector<double> v;
      for (double x; words >> x;) v.push_back(x);
      double items = v.empty() ? 0 : v[0];
      if (v.size() == 6) items = (v[1] - v[0] + 1) * (v[3] - v[2] + 1) * (v[5] - v[4] + 1);
      if (!(items <= kMaxVtkFlowItems))
        throw InputError(path, std::string(attribute, std::strlen(attribute) - 2),
                         "declares " + trimmed(head.substr(from, std::min<std::size_t>(to - from, 80))) +
                             ", over the limit of " + std::to_string(kMaxVtkFlowItems) +
                             " points or cells (docs/limits.md)");
    }
  }
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
  if (ext != ".vti" && ext != ".vtu" && ext != ".vtk")
    throw InputError(path, "", "unknown extension '" + ext + "' (expected .vti, .vtu or .vtk)");

  if (ext == ".vtk") LegacyVtkCheck(path).run();
  if (ext == ".vti" || ext == ".vtu") check_xml_sizes(path);

  VtkMessages messages;
  const CollectMessages collect(&messages);
  vtkNew<vtkCallbackCommand> on_error;
  on_error->SetCallback(&ErrorSink::record);
  on_error->SetClientData(&messages);
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
    if (reader->GetErrorCode() != 0 || !messages.first.empty())
      throw InputError(path, "", "VTK cannot read it: " + trimmed(messages.first));
    data = vtkDataSet::SafeDownCast(reader->GetOutputDataObject(0));
  } else if (ext == ".vtk") {
    vtkNew<vtkDataSetReader> reader;
    reader->AddObserver(vtkCommand::ErrorEvent, on_error);
    reader->AddObserver(vtkCommand::WarningEvent, on_error);
    reader->SetFileName(path.c_str());
    reader->ReadAllVectorsOn();
    reader->ReadAllScalarsOn();
    reader->Update();
    if (reader->GetErrorCode() != 0 || !messages.first.empty())
      throw InputError(path, "", "VTK cannot read it: " + trimmed(messages.first));
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
  // Every point or cell has its velocity: an array shorter than that would be
  // read past its end.
  const vtkIdType expected = flow->point_data_ ? data->GetNumberOfPoints() : data->GetNumberOfCells();
  if (velocity->GetNumberOfTuples() != expected)
    throw InputError(path, flow->array_name_,
                     "holds " + std::to_string(velocity->GetNumberOfTuples()) + " vectors for " +
                         std::to_string(expected) + (flow->point_data_ ? " points" : " cells"));
  if (auto* point_set = vtkPointSet::SafeDownCast(data); point_set && point_set->GetPoints()) {
    vtkDataArray* points = point_set->GetPoints()->GetData();
    for (vtkIdType i = 0; i < points->GetNumberOfTuples(); ++i)
      for (int c = 0; c < 3; ++c)
        if (!std::isfinite(points->GetComponent(i, c)))
          throw InputError(path, "points", "NaN or infinite coordinate at point " + std::to_string(i));
  }
  double bounds[6];
  data->GetBounds(bounds);
  for (double b : bounds)
    if (!std::isfinite(b)) throw InputError(path, "points", "the field's extent is not finite");
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
