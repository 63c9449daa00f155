// sim/vtk_flow_file.h: fields written by hand in the three formats. Trilinear
// (voxels) and linear (tetrahedra) interpolation reproduce a linear field
// exactly, so the interpolated velocity must match it to round-off; the
// refusals name the file.
#include "sim/vtk_flow_file.h"

#include <cmath>
#include <cstring>
#include <fstream>
#include <random>
#include <sstream>
#include <vector>

#include <gtest/gtest.h>

#include <vtkCellType.h>
#include <vtkDataSetWriter.h>
#include <vtkDoubleArray.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkUnstructuredGrid.h>

#include "tests/temp_dir.h"
#include "util/input_error.h"

namespace glasspiv {
namespace {

// v (m/s) = a + B x, x in m.
Eigen::Vector3d linear_field(const Eigen::Vector3d& x_m) {
  Eigen::Matrix3d b;
  b << 1, 2, -3, 0.5, -1, 4, 2, 0, 1;
  return Eigen::Vector3d(0.1, -0.2, 0.05) + b * x_m;
}

// A 5 x 4 x 3 grid, origin (0.01, -0.02, 0) m, spacing (0.01, 0.01, 0.005) m.
const Eigen::Vector3d kOrigin_m(0.01, -0.02, 0);
const Eigen::Vector3d kSpacing_m(0.01, 0.01, 0.005);
const int kDims[3] = {5, 4, 3};

Eigen::Vector3d grid_point_m(int i, int j, int k) {
  return kOrigin_m + Eigen::Vector3d(i * kSpacing_m.x(), j * kSpacing_m.y(), k * kSpacing_m.z());
}

std::string grid_values() {
  std::ostringstream out;
  out.precision(17);
  for (int k = 0; k < kDims[2]; ++k)
    for (int j = 0; j < kDims[1]; ++j)
      for (int i = 0; i < kDims[0]; ++i) {
        const Eigen::Vector3d v = linear_field(grid_point_m(i, j, k));
        out << v.x() << " " << v.y() << " " << v.z() << "\n";
      }
  return out.str();
}

void write(const std::string& path, const std::string& text) { std::ofstream(path, std::ios::binary) << text; }

std::string legacy_header() {
  std::ostringstream out;
  out.precision(17);
  out << "# vtk DataFile Version 3.0\nlinear field\nASCII\nDATASET STRUCTURED_POINTS\n"
      << "DIMENSIONS " << kDims[0] << " " << kDims[1] << " " << kDims[2] << "\n"
      << "ORIGIN " << kOrigin_m.x() << " " << kOrigin_m.y() << " " << kOrigin_m.z() << "\n"
      << "SPACING " << kSpacing_m.x() << " " << kSpacing_m.y() << " " << kSpacing_m.z() << "\n"
      << "POINT_DATA " << kDims[0] * kDims[1] * kDims[2] << "\n";
  return out.str();
}

std::string vti_file() {
  std::ostringstream out;
  out.precision(17);
  out << "<?xml version=\"1.0\"?>\n<VTKFile type=\"ImageData\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
      << "<ImageData WholeExtent=\"0 4 0 3 0 2\" Origin=\"" << kOrigin_m.x() << " " << kOrigin_m.y() << " "
      << kOrigin_m.z() << "\" Spacing=\"" << kSpacing_m.x() << " " << kSpacing_m.y() << " " << kSpacing_m.z()
      << "\">\n<Piece Extent=\"0 4 0 3 0 2\">\n<PointData Vectors=\"U\">\n"
      << "<DataArray type=\"Float64\" Name=\"U\" NumberOfComponents=\"3\" format=\"ascii\">\n"
      << grid_values() << "</DataArray>\n</PointData>\n<CellData/>\n</Piece>\n</ImageData>\n</VTKFile>\n";
  return out.str();
}

// The unit cube [0, 0.02]^3 m cut into six tetrahedra around its diagonal; point
// data the linear field, cell data the cell index as (i, 0, 0).
std::string vtu_file(bool cell_data) {
  std::ostringstream out;
  out.precision(17);
  const double h = 0.02;
  std::vector<Eigen::Vector3d> corners;
  for (int c = 0; c < 8; ++c) corners.emplace_back(h * (c & 1), h * ((c >> 1) & 1), h * ((c >> 2) & 1));
  const int tets[6][4] = {{0, 1, 3, 7}, {0, 1, 5, 7}, {0, 2, 3, 7}, {0, 2, 6, 7}, {0, 4, 5, 7}, {0, 4, 6, 7}};
  out << "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
      << "<UnstructuredGrid>\n<Piece NumberOfPoints=\"8\" NumberOfCells=\"6\">\n<Points>\n"
      << "<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n";
  for (const Eigen::Vector3d& p : corners) out << p.x() << " " << p.y() << " " << p.z() << "\n";
  out << "</DataArray>\n</Points>\n<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n";
  for (const auto& t : tets) out << t[0] << " " << t[1] << " " << t[2] << " " << t[3] << "\n";
  out << "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">4 8 12 16 20 24</DataArray>\n"
      << "<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">10 10 10 10 10 10</DataArray>\n</Cells>\n";
  if (cell_data) {
    out << "<CellData>\n<DataArray type=\"Float64\" Name=\"velocity\" NumberOfComponents=\"3\" format=\"ascii\">\n";
    for (int c = 0; c < 6; ++c) out << c << " 0 0\n";
    out << "</DataArray>\n</CellData>\n";
  } else {
    out << "<PointData>\n<DataArray type=\"Float64\" Name=\"velocity\" NumberOfComponents=\"3\" format=\"ascii\">\n";
    for (const Eigen::Vector3d& p : corners) {
      const Eigen::Vector3d v = linear_field(p);
      out << v.x() << " " << v.y() << " " << v.z() << "\n";
    }
    out << "</DataArray>\n</PointData>\n";
  }
  out << "</Piece>\n</UnstructuredGrid>\n</VTKFile>\n";
  return out.str();
}

// Random points strictly inside the box [lo, hi] (m), returned in mm.
std::vector<Eigen::Vector3d> points_mm(const Eigen::Vector3d& lo_m, const Eigen::Vector3d& hi_m, int n) {
  std::mt19937_64 engine(1);
  std::uniform_real_distribution<double> u(0.001, 0.999);
  std::vector<Eigen::Vector3d> out;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d f(u(engine), u(engine), u(engine));
    out.push_back(1000 * (lo_m + f.cwiseProduct(hi_m - lo_m)));
  }
  return out;
}

// |v| ~ 0.3 m/s, terms ~ 1e-2: 1e-13 m/s is a few hundred ulps of round-off in the weights.
void expect_linear(const Flow& flow, const std::vector<Eigen::Vector3d>& points) {
  for (const Eigen::Vector3d& p_mm : points)
    EXPECT_NEAR((flow.velocity_m_per_s(p_mm, 0) - linear_field(p_mm / 1000)).norm(), 0, 1e-13) << p_mm.transpose();
}

TEST(VtkFlowFile, ImageDataIsTrilinearInBothFormats) {
  TempDir dir("sim_vtk");
  write(dir.file("field.vtk"), legacy_header() + "VECTORS velocity double\n" + grid_values());
  write(dir.file("field.vti"), vti_file());
  const Eigen::Vector3d hi_m = grid_point_m(4, 3, 2);
  for (const std::string name : {"field.vtk", "field.vti"}) {
    const auto flow = read_vtk_flow(dir.file(name));
    EXPECT_EQ(flow->array_name(), name == "field.vtk" ? "velocity" : "U");
    expect_linear(*flow, points_mm(kOrigin_m, hi_m, 200));
    // The grid's corners count as inside; beyond the grid the velocity is zero.
    EXPECT_TRUE(flow->covers(1000 * kOrigin_m));
    EXPECT_TRUE(flow->covers(1000 * hi_m));
    EXPECT_FALSE(flow->covers(1000 * hi_m + Eigen::Vector3d(0.01, 0, 0)));
    EXPECT_EQ(flow->velocity_m_per_s(1000 * hi_m + Eigen::Vector3d(1, 0, 0), 0), Eigen::Vector3d::Zero());
  }
}

TEST(VtkFlowFile, UnstructuredTetrahedraAreLinearAndCellDataConstant) {
  TempDir dir("sim_vtk");
  write(dir.file("points.vtu"), vtu_file(false));
  write(dir.file("cells.vtu"), vtu_file(true));
  const auto flow = read_vtk_flow(dir.file("points.vtu"));
  expect_linear(*flow, points_mm(Eigen::Vector3d::Zero(), Eigen::Vector3d::Constant(0.02), 200));
  // Cell data: the velocity is one of the cell indices, exactly.
  VtkFlowOptions options;
  options.m_per_s_per_file_velocity = 0.5;
  const auto cells = read_vtk_flow(dir.file("cells.vtu"), options);
  for (const Eigen::Vector3d& p : points_mm(Eigen::Vector3d::Zero(), Eigen::Vector3d::Constant(0.02), 50)) {
    const Eigen::Vector3d v = cells->velocity_m_per_s(p, 0);
    EXPECT_EQ(v.x() * 2, std::round(v.x() * 2));
    EXPECT_EQ(v.tail<2>(), Eigen::Vector2d::Zero());
  }
}

// A NaN velocity (legacy binary: big-endian doubles) is refused naming the file and the array.
TEST(VtkFlowFile, NanIsRefusedNamingTheFile) {
  TempDir dir("sim_vtk");
  std::string header = legacy_header();
  header.replace(header.find("ASCII"), 5, "BINARY");
  std::string data;
  const int n = kDims[0] * kDims[1] * kDims[2];
  for (int i = 0; i < 3 * n; ++i) {
    const double v = i == 31 ? std::nan("") : 0.25;
    unsigned char bytes[8];
    std::memcpy(bytes, &v, 8);
    for (int b = 7; b >= 0; --b) data.push_back(static_cast<char>(bytes[b]));
  }
  const std::string path = dir.file("nan.vtk");
  write(path, header + "VECTORS U double\n" + data + "\n");
  try {
    read_vtk_flow(path);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), path);
    EXPECT_EQ(e.field(), "U");
    EXPECT_NE(e.problem().find("point 10"), std::string::npos) << e.problem();
  }
}

TEST(VtkFlowFile, UnreadableFilesAreRefusedNamingTheFile) {
  TempDir dir("sim_vtk");
  write(dir.file("garbage.vtu"), "not xml at all");
  write(dir.file("field.txt"), "1 2 3");
  std::string scalars;  // a pressure field only: no velocity
  for (int i = 0; i < kDims[0] * kDims[1] * kDims[2]; ++i) scalars += "1 ";
  write(dir.file("novel.vtk"), legacy_header() + "SCALARS p double 1\nLOOKUP_TABLE default\n" + scalars + "\n");
  for (const std::string name : {"missing.vti", "garbage.vtu", "field.txt", "novel.vtk"}) {
    try {
      read_vtk_flow(dir.file(name));
      FAIL() << name;
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), dir.file(name));
    }
  }
  write(dir.file("field.vtk"), legacy_header() + "VECTORS velocity double\n" + grid_values());
  VtkFlowOptions options;
  options.array = "W";
  EXPECT_THROW(read_vtk_flow(dir.file("field.vtk"), options), InputError);
}

// The slab must lie in the data, except where solids are.
TEST(VtkFlowFile, FieldNotCoveringTheSheetIsRefused) {
  TempDir dir("sim_vtk");
  write(dir.file("field.vtk"), legacy_header() + "VECTORS velocity double\n" + grid_values());
  const auto flow = read_vtk_flow(dir.file("field.vtk"));
  // Data: x 10..50 mm, y -20..10 mm, z 0..10 mm.
  Sheet sheet;
  sheet.origin_mm = Eigen::Vector3d(30, -5, 5);
  sheet.extent_mm = {30, 20};
  sheet.thickness_mm = 2;
  check_covers_slab(*flow, sheet, 1.5, 2, SolidInteriors());
  try {
    check_covers_slab(*flow, sheet, 1.5, 6, SolidInteriors());  // 30 + 12 > 40 mm
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), dir.file("field.vtk"));
  }
  // A box solid where the slab leaves the data: no data needed there.
  // s from 33 - 19 = 14 to 33 + 19 = 52 mm with a 4 mm margin; the wall fills x > 50 mm.
  sheet.origin_mm.x() = 33;
  const std::vector<Shape> wall = {Box{Eigen::Vector3d(55, -5, 5), Eigen::Matrix3d::Identity(),
                                       Eigen::Vector3d(5 - 1e-3, 30, 30)}};
  EXPECT_THROW(check_covers_slab(*flow, sheet, 1.5, 4, SolidInteriors()), InputError);
  check_covers_slab(*flow, sheet, 1.5, 4, SolidInteriors(wall));
}

// The value a refusal must not be: a read that exits normally, or any text
// VTK itself prints. Each file is refused with one InputError naming it and
// nothing on stderr (VTK's output window and logger are silenced).
void expect_refused_quietly(const std::string& path, const std::string& problem_has) {
  testing::internal::CaptureStderr();
  try {
    read_vtk_flow(path);
    ADD_FAILURE() << path << ": no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), path);
    EXPECT_NE(e.problem().find(problem_has), std::string::npos) << e.problem();
    for (char c : std::string(e.what())) EXPECT_TRUE(c >= 0x20 && c < 0x7f) << "byte " << int(c) << " in " << e.what();
  }
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
}

// Big-endian doubles, as legacy binary files hold them.
std::string big_endian(const std::vector<double>& values) {
  std::string out;
  for (double v : values) {
    unsigned char bytes[8];
    std::memcpy(bytes, &v, 8);
    for (int b = 7; b >= 0; --b) out.push_back(static_cast<char>(bytes[b]));
  }
  return out;
}

// Truncated files and short data sections: VTK's legacy reader would leave the
// missing values as memory it never filled (valgrind: uninitialised reads) and
// use them as velocities; the declared sizes are checked against the file first.
TEST(VtkFlowFile, TruncatedOrShortDataIsRefusedBeforeVtkReadsIt) {
  TempDir dir("sim_vtk");
  const int n = kDims[0] * kDims[1] * kDims[2];
  std::string binary = legacy_header();
  binary.replace(binary.find("ASCII"), 5, "BINARY");
  const std::string all = big_endian(std::vector<double>(3 * static_cast<std::size_t>(n), 0.25));
  // Binary: the last vector cut off, and the file cut in the middle of a value.
  write(dir.file("short.vtk"), binary + "VECTORS U double\n" + all.substr(0, all.size() - 24) + "\n");
  expect_refused_quietly(dir.file("short.vtk"), "bytes are left");
  write(dir.file("cut.vtk"), binary + "VECTORS U double\n" + all.substr(0, all.size() / 2 + 3));
  expect_refused_quietly(dir.file("cut.vtk"), "bytes are left");
  // A short binary section followed by another section: the walk lands in the data.
  write(dir.file("shifted.vtk"), binary + "VECTORS U double\n" + all.substr(0, all.size() - 48) + "\nSCALARS p double 1\n");
  expect_refused_quietly(dir.file("shifted.vtk"), "");
  // ASCII: two values missing, the file cut after a few lines.
  std::string values = grid_values();
  const std::size_t last_line = values.find_last_of('\n', values.size() - 2);
  write(dir.file("short_ascii.vtk"), legacy_header() + "VECTORS U double\n" + values.substr(0, last_line) + " 1\n");
  expect_refused_quietly(dir.file("short_ascii.vtk"), "ends after");
  write(dir.file("cut_ascii.vtk"), legacy_header() + "VECTORS U double\n" + values.substr(0, 100));
  expect_refused_quietly(dir.file("cut_ascii.vtk"), "ends after");
}

// A literal nan (or any word that is not a finite number) in an ASCII section.
TEST(VtkFlowFile, AsciiNanOrWordIsRefusedNamingTheSection) {
  TempDir dir("sim_vtk");
  std::string values = grid_values();
  for (const std::string bad : {"nan", "-inf", "1e999", "x", "0x1p3"}) {
    std::string v = values;
    v.replace(v.find(' '), 0, " " + bad);  // one value more in the first line, the rest shifted
    v = v.substr(0, v.rfind(' '));         // and one less at the end: the count is right
    const std::string path = dir.file("bad.vtk");
    write(path, legacy_header() + "VECTORS U double\n" + v + "\n");
    testing::internal::CaptureStderr();
    try {
      read_vtk_flow(path);
      ADD_FAILURE() << bad << ": no error";
    } catch (const InputError& e) {
      EXPECT_EQ(e.field(), "VECTORS U") << e.what();
      EXPECT_NE(e.problem().find("not a finite number"), std::string::npos) << e.what();
    }
    EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
  }
}

// A 9 KB file that declares 2.5e8 points (6 GB as VTK reads it): refused from its header, before VTK
// allocates gigabytes; and one that declares more than the limit outright.
TEST(VtkFlowFile, DeclaredSizesAreCheckedBeforeAllocating) {
  TempDir dir("sim_vtk");
  const std::string points_header =
      "# vtk DataFile Version 3.0\nhuge\nBINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS 250000000 float\n";
  write(dir.file("huge.vtk"), points_header + std::string(9000, '\0'));
  expect_refused_quietly(dir.file("huge.vtk"), "over the limit");
  write(dir.file("large.vtk"), "# vtk DataFile Version 3.0\nlarge\nBINARY\nDATASET UNSTRUCTURED_GRID\n"
                               "POINTS 1000000 float\n" + std::string(9000, '\0'));
  expect_refused_quietly(dir.file("large.vtk"), "12000000 bytes) but 9000 bytes are left");
  write(dir.file("over.vtk"), "# vtk DataFile Version 3.0\nhuge\nBINARY\nDATASET STRUCTURED_POINTS\n"
                              "DIMENSIONS 100000 100000 100000\nORIGIN 0 0 0\nSPACING 1 1 1\nPOINT_DATA 8\n");
  expect_refused_quietly(dir.file("over.vtk"), "limit");
  write(dir.file("over.vti"),
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"ImageData\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
        "<ImageData WholeExtent=\"0 99999 0 99999 0 99999\" Origin=\"0 0 0\" Spacing=\"1 1 1\">\n"
        "<Piece Extent=\"0 99999 0 99999 0 99999\">\n<PointData Vectors=\"U\">\n"
        "<DataArray type=\"Float64\" Name=\"U\" NumberOfComponents=\"3\" format=\"ascii\">\n0 0 0\n"
        "</DataArray>\n</PointData>\n</Piece>\n</ImageData>\n</VTKFile>\n");
  expect_refused_quietly(dir.file("over.vti"), "limit");
}

// VTK's own errors (an XML file cut short) become the one InputError; nothing
// of VTK's coloured, multi-line report reaches stderr.
TEST(VtkFlowFile, VtkErrorsBecomeOneLineAndStderrStaysQuiet) {
  TempDir dir("sim_vtk");
  const std::string vti = vti_file();
  write(dir.file("cut.vti"), vti.substr(0, vti.size() / 2) + "\x1b[31m\x01");
  expect_refused_quietly(dir.file("cut.vti"), "");
}

// What VTK itself writes passes the section walk: legacy ASCII and binary, an
// unstructured grid (VTK 5 OFFSETS and CONNECTIVITY, CELL_TYPES, metadata) with
// two point arrays and image data, read back to the written velocities.
TEST(VtkFlowFile, FilesVtkWritesAreRead) {
  TempDir dir("sim_vtk");
  vtkNew<vtkUnstructuredGrid> grid;
  vtkNew<vtkPoints> points;
  const double h = 0.02;
  for (const Eigen::Vector3d& p : {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(h, 0, 0), Eigen::Vector3d(0, h, 0),
                                   Eigen::Vector3d(0, 0, h)})
    points->InsertNextPoint(p.x(), p.y(), p.z());
  grid->SetPoints(points);
  const vtkIdType tet[4] = {0, 1, 2, 3};
  grid->InsertNextCell(VTK_TETRA, 4, tet);
  vtkNew<vtkDoubleArray> u, p;
  u->SetName("U");
  u->SetNumberOfComponents(3);
  p->SetName("p");
  for (vtkIdType i = 0; i < 4; ++i) {
    double x[3];
    points->GetPoint(i, x);
    const Eigen::Vector3d v = linear_field(Eigen::Vector3d(x[0], x[1], x[2]));
    u->InsertNextTuple3(v.x(), v.y(), v.z());
    p->InsertNextValue(1.5 * static_cast<double>(i));
  }
  grid->GetPointData()->AddArray(u);
  grid->GetPointData()->AddArray(p);
  vtkNew<vtkImageData> image;
  image->SetDimensions(kDims[0], kDims[1], kDims[2]);
  image->SetOrigin(kOrigin_m.x(), kOrigin_m.y(), kOrigin_m.z());
  image->SetSpacing(kSpacing_m.x(), kSpacing_m.y(), kSpacing_m.z());
  vtkNew<vtkDoubleArray> w;
  w->SetName("velocity");
  w->SetNumberOfComponents(3);
  for (int k = 0; k < kDims[2]; ++k)
    for (int j = 0; j < kDims[1]; ++j)
      for (int i = 0; i < kDims[0]; ++i) {
        const Eigen::Vector3d v = linear_field(grid_point_m(i, j, k));
        w->InsertNextTuple3(v.x(), v.y(), v.z());
      }
  image->GetPointData()->AddArray(w);
  for (bool binary : {false, true})
    for (vtkDataSet* data : {static_cast<vtkDataSet*>(grid.GetPointer()), static_cast<vtkDataSet*>(image.GetPointer())}) {
      const std::string path = dir.file(std::string(binary ? "binary_" : "ascii_") + data->GetClassName() + ".vtk");
      vtkNew<vtkDataSetWriter> writer;
      writer->SetInputData(data);
      writer->SetFileName(path.c_str());
      if (binary) writer->SetFileTypeToBinary();
      ASSERT_EQ(writer->Write(), 1) << path;
      const auto flow = read_vtk_flow(path);
      const Eigen::Vector3d at_m = data == grid.GetPointer() ? Eigen::Vector3d(0.004, 0.005, 0.006)
                                                              : grid_point_m(2, 1, 1) + 0.3 * kSpacing_m;
      const Eigen::Vector3d v = flow->velocity_m_per_s(1000 * at_m, 0);
      EXPECT_LT((v - linear_field(at_m)).norm(), 1e-9) << path;
    }
}

}  // namespace
}  // namespace glasspiv
