// The snapshots' own VTP writer (PolyDataIO.h, writePolyDataUncompressed) against VTK's reader: every value it
// wrote must come back from vtkXMLPolyDataReader, an independent implementation of the format, bit for bit.
#include "cementsph/imaging/PolyDataIO.h"

#include <gtest/gtest.h>
#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkFloatArray.h>
#include <vtkIntArray.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkStringArray.h>
#include <vtkTypeInt32Array.h>
#include <vtkUnsignedCharArray.h>
#include <vtkXMLPPolyDataReader.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include <unistd.h>

namespace fs = std::filesystem;
using namespace cementsph;

namespace {

fs::path scratch(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("cementsph-polydata-writer-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir / name;
}

// n points with vertex cells (32-bit cell storage, as the snapshots), two triangles, and arrays of five types.
vtkSmartPointer<vtkPolyData> sample(vtkIdType n) {
  auto data = vtkSmartPointer<vtkPolyData>::New();
  auto points = vtkSmartPointer<vtkPoints>::New();
  points->SetDataTypeToFloat();
  points->SetNumberOfPoints(n);
  for (vtkIdType i = 0; i < n; ++i) points->SetPoint(i, 0.1 * double(i), std::sin(double(i)), -1e3 / double(i + 1));
  data->SetPoints(points);
  auto offsets = vtkSmartPointer<vtkTypeInt32Array>::New(), connectivity = vtkSmartPointer<vtkTypeInt32Array>::New();
  offsets->SetNumberOfValues(n + 1);
  connectivity->SetNumberOfValues(n);
  for (vtkIdType i = 0; i <= n; ++i) offsets->SetValue(i, vtkTypeInt32(i));
  for (vtkIdType i = 0; i < n; ++i) connectivity->SetValue(i, vtkTypeInt32(n - 1 - i)); // not the identity
  auto verts = vtkSmartPointer<vtkCellArray>::New();
  verts->SetData(offsets, connectivity);
  data->SetVerts(verts);
  if (n >= 4) {
    auto polys = vtkSmartPointer<vtkCellArray>::New(); // 64-bit storage (VTK's default)
    const vtkIdType a[3] = {0, 1, 2}, b[3] = {1, 3, 2};
    polys->InsertNextCell(3, a);
    polys->InsertNextCell(3, b);
    data->SetPolys(polys);
  }
  auto pressure = vtkSmartPointer<vtkFloatArray>::New();
  pressure->SetName("pressure_pa");
  pressure->SetNumberOfValues(n);
  auto velocity = vtkSmartPointer<vtkFloatArray>::New();
  velocity->SetName("darcy_velocity_m_per_s");
  velocity->SetNumberOfComponents(3);
  velocity->SetNumberOfTuples(n);
  auto volume = vtkSmartPointer<vtkDoubleArray>::New();
  volume->SetName("cement_volume_mm3");
  volume->SetNumberOfValues(n);
  auto label = vtkSmartPointer<vtkUnsignedCharArray>::New();
  label->SetName("label <&\">");
  label->SetNumberOfValues(n);
  for (vtkIdType i = 0; i < n; ++i) {
    pressure->SetValue(i, float(1e5 / double(i + 3)));
    for (int c = 0; c < 3; ++c) velocity->SetComponent(i, c, float(1e-6 * double(c - i)));
    volume->SetValue(i, 0.1 + 1e-13 * double(i));
    label->SetValue(i, static_cast<unsigned char>(i % 251));
  }
  data->GetPointData()->AddArray(pressure);
  data->GetPointData()->AddArray(velocity);
  data->GetPointData()->AddArray(volume);
  data->GetPointData()->AddArray(label);
  data->GetPointData()->SetActiveScalars("pressure_pa");
  if (n >= 4) {
    auto area = vtkSmartPointer<vtkIntArray>::New();
    area->SetName("cell_id");
    area->SetNumberOfValues(n + 2);
    for (vtkIdType i = 0; i < n + 2; ++i) area->SetValue(i, int(7 * i - 3));
    data->GetCellData()->AddArray(area);
  }
  auto density = vtkSmartPointer<vtkDoubleArray>::New();
  density->SetName("density_kg_per_m3");
  density->SetNumberOfValues(1);
  density->SetValue(0, 1100.0);
  data->GetFieldData()->AddArray(density);
  return data;
}

void expectSameArrays(vtkFieldData* want, vtkFieldData* got, const char* what) {
  ASSERT_EQ(got->GetNumberOfArrays(), want->GetNumberOfArrays()) << what;
  for (int k = 0; k < want->GetNumberOfArrays(); ++k) {
    vtkDataArray* a = want->GetArray(k);
    if (!a) continue; // not numeric (a string array): the caller checks it
    vtkDataArray* b = got->GetArray(a->GetName());
    ASSERT_NE(b, nullptr) << what << " " << a->GetName();
    EXPECT_EQ(b->GetDataType(), a->GetDataType()) << a->GetName();
    ASSERT_EQ(b->GetNumberOfComponents(), a->GetNumberOfComponents()) << a->GetName();
    ASSERT_EQ(b->GetNumberOfTuples(), a->GetNumberOfTuples()) << a->GetName();
    for (vtkIdType i = 0; i < a->GetNumberOfValues(); ++i)
      ASSERT_EQ(b->GetVariantValue(i), a->GetVariantValue(i)) << a->GetName() << " value " << i;
  }
}

void expectSameCells(vtkCellArray* want, vtkCellArray* got, const char* what) {
  ASSERT_EQ(got->GetNumberOfCells(), want->GetNumberOfCells()) << what;
  ASSERT_EQ(got->GetNumberOfConnectivityIds(), want->GetNumberOfConnectivityIds()) << what;
  for (vtkIdType c = 0; c <= want->GetNumberOfCells(); ++c)
    ASSERT_EQ(got->GetOffsetsArray()->GetTuple1(c), want->GetOffsetsArray()->GetTuple1(c)) << what << " offset " << c;
  for (vtkIdType i = 0; i < want->GetNumberOfConnectivityIds(); ++i)
    ASSERT_EQ(got->GetConnectivityArray()->GetTuple1(i), want->GetConnectivityArray()->GetTuple1(i)) << what << " " << i;
}

} // namespace

// Every point, cell and array value the raw writer wrote comes back from VTK's reader exactly (tolerance: none),
// for a snapshot-like cloud and for an empty one (a run's first snapshot can hold no cement).
TEST(PolyDataWriter, VtksReaderReadsBackEveryValueOfTheRawFile) {
  for (vtkIdType n : {vtkIdType(0), vtkIdType(1), vtkIdType(1000)}) {
    SCOPED_TRACE("points " + std::to_string(n));
    const auto want = sample(n);
    const fs::path path = scratch("points-" + std::to_string(n) + ".vtp");
    imaging::writePolyDataUncompressed(want, path.string());
    const auto got = imaging::readPolyData(path.string());
    ASSERT_EQ(got->GetNumberOfPoints(), n);
    for (vtkIdType i = 0; i < n; ++i)
      for (int a = 0; a < 3; ++a)
        ASSERT_EQ(got->GetPoint(i)[a], want->GetPoint(i)[a]) << "point " << i;
    expectSameCells(want->GetVerts(), got->GetVerts(), "verts");
    expectSameCells(want->GetPolys(), got->GetPolys(), "polys");
    expectSameArrays(want->GetPointData(), got->GetPointData(), "point data");
    expectSameArrays(want->GetCellData(), got->GetCellData(), "cell data");
    expectSameArrays(want->GetFieldData(), got->GetFieldData(), "field data");
    if (n > 0) {
      ASSERT_NE(got->GetPointData()->GetScalars(), nullptr);
      EXPECT_STREQ(got->GetPointData()->GetScalars()->GetName(), "pressure_pa");
    }
    // Raw and uncompressed: the file holds the values' bytes (here 25 bytes a point for the arrays, 12 for the
    // point, 8 for its vertex), so it is at least that long.
    EXPECT_GE(fs::file_size(path), std::uintmax_t(n) * (25 + 12 + 8));
  }
}

// What the raw writer does not take (a string array) goes to VTK's writer: the file is still read back whole.
TEST(PolyDataWriter, AnArrayTheRawWriterCannotTakeGoesToVtksWriter) {
  const auto want = sample(10);
  // VTK's writer puts names into its XML unescaped (it wrote an unreadable file for "label <&\">").
  want->GetPointData()->GetArray("label <&\">")->SetName("label");
  auto names = vtkSmartPointer<vtkStringArray>::New();
  names->SetName("names");
  names->SetNumberOfValues(10);
  for (vtkIdType i = 0; i < 10; ++i) names->SetValue(i, "p" + std::to_string(i));
  want->GetPointData()->AddArray(names);
  const fs::path path = scratch("strings.vtp");
  imaging::writePolyDataUncompressed(want, path.string());
  const auto got = imaging::readPolyData(path.string());
  ASSERT_EQ(got->GetNumberOfPoints(), 10);
  auto* back = vtkStringArray::SafeDownCast(got->GetPointData()->GetAbstractArray("names"));
  ASSERT_NE(back, nullptr);
  EXPECT_EQ(back->GetValue(9), "p9");
  expectSameArrays(want->GetPointData(), got->GetPointData(), "point data");
}

// An unnamed array and a global-ids designation are not the raw writer's: VTK's writer takes the file, and what
// the reader gives back holds every value.
TEST(PolyDataWriter, AnUnnamedArrayGoesToVtksWriter) {
  const auto want = sample(10);
  auto unnamed = vtkSmartPointer<vtkDoubleArray>::New();
  unnamed->SetNumberOfValues(10);
  for (vtkIdType i = 0; i < 10; ++i) unnamed->SetValue(i, 0.5 * double(i));
  want->GetPointData()->AddArray(unnamed);
  want->GetPointData()->GetArray("label <&\">")->SetName("label");
  const fs::path path = scratch("unnamed.vtp");
  imaging::writePolyDataUncompressed(want, path.string());
  // VTK's writer LZ4-compresses: the file is smaller than the raw values (10 points x 53 bytes and more).
  std::ifstream file(path, std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("compressor"), std::string::npos) << "not VTK's writer";
  const auto got = imaging::readPolyData(path.string());
  ASSERT_EQ(got->GetPointData()->GetNumberOfArrays(), 5);
}

// A directory that does not exist: one error naming the file, nothing left behind.
TEST(PolyDataWriter, AnUnwritablePathThrowsNamingIt) {
  const fs::path path = scratch("no-such-dir") / "points.vtp";
  try {
    imaging::writePolyDataUncompressed(sample(5), path.string());
    FAIL() << "no error";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("points.vtp"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(path));
  fs::remove_all(scratch("").parent_path()); // the suite's scratch folder (the last test)
}

// A snapshot as the union of pieces written before (writePolyDataPieces, issue 23): VTK's own parallel reader
// (vtkXMLPPolyDataReader, not ours) reads the .pvtp as every piece's points and arrays, appended in the order
// named, value for value; a piece with no points (an interval in which no voxel took cement) adds nothing.
TEST(PolyDataWriter, VtksParallelReaderReadsThePiecesAsOneDataset) {
  const vtkIdType sizes[3] = {5, 0, 7};
  std::vector<vtkSmartPointer<vtkPolyData>> pieces;
  std::vector<std::string> names;
  for (int k = 0; k < 3; ++k) {
    auto piece = sample(sizes[k]);
    // Points, vertices and point arrays, as the snapshots' pieces (sample's triangles and their cell array only
    // where it has four points or more would make the pieces differ).
    piece->SetPolys(nullptr);
    piece->GetCellData()->Initialize();
    // Shift the points so that each piece's are its own.
    for (vtkIdType i = 0; i < piece->GetNumberOfPoints(); ++i) {
      double x[3];
      piece->GetPoint(i, x);
      x[0] += 100.0 * k;
      piece->GetPoints()->SetPoint(i, x);
    }
    names.push_back("piece-" + std::to_string(k) + ".vtp");
    imaging::writePolyDataUncompressed(piece, scratch(names.back()).string());
    pieces.push_back(piece);
  }
  const fs::path union_ = scratch("union.pvtp");
  imaging::writePolyDataPieces(union_.string(), pieces[0], names);
  auto reader = vtkSmartPointer<vtkXMLPPolyDataReader>::New();
  reader->SetFileName(union_.string().c_str());
  reader->Update();
  ASSERT_EQ(reader->GetErrorCode(), 0);
  vtkPolyData* got = reader->GetOutput();
  ASSERT_EQ(got->GetNumberOfPoints(), 12);
  EXPECT_EQ(got->GetNumberOfVerts(), 12);
  vtkIdType at = 0;
  for (int k = 0; k < 3; ++k)
    for (vtkIdType i = 0; i < sizes[k]; ++i, ++at) {
      for (int a = 0; a < 3; ++a) ASSERT_EQ(got->GetPoint(at)[a], pieces[std::size_t(k)]->GetPoint(i)[a]) << k << " " << i;
      for (const char* name : {"pressure_pa", "cement_volume_mm3", "darcy_velocity_m_per_s"}) {
        vtkDataArray *want = pieces[std::size_t(k)]->GetPointData()->GetArray(name), *have = got->GetPointData()->GetArray(name);
        ASSERT_NE(have, nullptr) << name;
        ASSERT_EQ(have->GetNumberOfComponents(), want->GetNumberOfComponents()) << name;
        for (int c = 0; c < want->GetNumberOfComponents(); ++c)
          ASSERT_EQ(have->GetComponent(at, c), want->GetComponent(i, c)) << name << " piece " << k << " point " << i;
      }
    }
  // Ours reads it the same way (by the extension), and a piece gone is an error naming the file, not fewer points.
  EXPECT_EQ(imaging::readPolyData(union_.string())->GetNumberOfPoints(), 12);
  fs::remove(scratch(names[2]));
  try {
    const auto partial = imaging::readPolyData(union_.string());
    ADD_FAILURE() << "read " << partial->GetNumberOfPoints() << " points without its third piece";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(union_.string()), std::string::npos) << e.what();
  }
  // A prototype array without a name cannot be declared: one clear error, no file.
  auto unnamed = sample(2);
  auto extra = vtkSmartPointer<vtkFloatArray>::New();
  extra->SetNumberOfValues(2);
  unnamed->GetPointData()->AddArray(extra);
  const fs::path bad = scratch("bad.pvtp");
  EXPECT_THROW(imaging::writePolyDataPieces(bad.string(), unnamed, names), std::invalid_argument);
  EXPECT_FALSE(fs::exists(bad));
}
