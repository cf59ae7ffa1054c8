// Volume IO: every format keeps origin, spacing and a non-identity direction; DICOM keeps HU;
// bad input gives a clear std::runtime_error naming the file; writes leave no partial files.
#include "SyntheticVolumes.h"
#include "cementsph/imaging/AtomicFile.h"
#include "cementsph/imaging/VolumeIO.h"

#include <gtest/gtest.h>
#include <itkImageFileWriter.h>
#include <itkNrrdImageIO.h>

#include <cmath>
#include <filesystem>
#include <fstream>

namespace fs = std::filesystem;
using namespace cementsph::imaging;
using cementsph::testing::Grid;
using cementsph::testing::makeImage;

namespace {

fs::path scratch(const std::string& name) {
  fs::path dir = fs::path(CEMENTSPH_BINARY_DIR) / "Testing" / "imaging-io" / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// 20 x 16 x 12 voxels, anisotropic spacing, rotated 30 degrees about z, values with a pattern.
ImageType::Pointer obliqueVolume() {
  Grid g;
  g.size = {20, 16, 12};
  g.spacing = {0.47, 0.47, 0.5};
  g.origin = {-12.5, 30.25, 101.0};
  const double c = std::cos(M_PI / 6), s = std::sin(M_PI / 6);
  g.direction = {c, -s, 0, s, c, 0, 0, 0, 1};
  auto image = makeImage(g);
  float* p = image->GetBufferPointer();
  for (std::size_t i = 0; i < image->GetLargestPossibleRegion().GetNumberOfPixels(); ++i)
    p[i] = static_cast<float>(static_cast<int>(i % 997) * 3 - 1000);
  return image;
}

void expectSameGeometry(const VolumeGeometry& a, const VolumeGeometry& b, double tol) {
  EXPECT_EQ(a.size, b.size);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(a.origin[i], b.origin[i], tol) << "origin " << i;
    EXPECT_NEAR(a.spacing[i], b.spacing[i], tol) << "spacing " << i;
  }
  for (int i = 0; i < 9; ++i) EXPECT_NEAR(a.direction[i], b.direction[i], tol) << "direction " << i;
}

bool onlyFinalFilesIn(const fs::path& dir) {
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().filename().string().find(".tmp-") != std::string::npos) return false;
  return true;
}

} // namespace

TEST(AtomicFile, TemporaryNameKeepsCompoundExtension) {
  EXPECT_EQ(fullExtension("/a/b/post.nii.gz"), ".nii.gz");
  EXPECT_EQ(fullExtension("/a/b.d/post.NRRD"), ".nrrd");
  EXPECT_EQ(fullExtension("/a/b/noext"), "");
  const std::string t = temporarySiblingPath("/a/b/post.nii.gz");
  EXPECT_EQ(t.rfind("/a/b/post.tmp-", 0), 0u) << t;
  EXPECT_EQ(fullExtension(t), ".nii.gz");
}

TEST(AtomicFile, FailedWriteLeavesNothing) {
  const fs::path dir = scratch("atomic");
  const std::string target = (dir / "out.json").string();
  EXPECT_THROW(writeAtomically(target,
                               [](const std::string& tmp) {
                                 std::ofstream(tmp) << "partial";
                                 throw std::runtime_error("disk on fire");
                               }),
               std::runtime_error);
  EXPECT_FALSE(fs::exists(target));
  EXPECT_TRUE(fs::is_empty(dir));
}

class FormatRoundTrip : public ::testing::TestWithParam<std::string> {};

TEST_P(FormatRoundTrip, KeepsGeometryAndValues) {
  const fs::path dir = scratch("roundtrip" + GetParam());
  const auto image = obliqueVolume();
  const std::string path = (dir / ("v" + GetParam())).string();
  writeVolume(image, path);
  ASSERT_TRUE(fs::exists(path));
  EXPECT_TRUE(onlyFinalFilesIn(dir));
  const auto back = readVolume(path);
  // NIfTI stores geometry as float32 quaternions: micrometre-level rounding is expected.
  expectSameGeometry(geometryOf(image), geometryOf(back), 1e-4);
  const std::size_t n = image->GetLargestPossibleRegion().GetNumberOfPixels();
  for (std::size_t i = 0; i < n; i += 37)
    ASSERT_FLOAT_EQ(image->GetBufferPointer()[i], back->GetBufferPointer()[i]) << i;
}

INSTANTIATE_TEST_SUITE_P(Formats, FormatRoundTrip,
                         ::testing::Values(".nrrd", ".mha", ".nii", ".nii.gz"),
                         [](const auto& paramInfo) {
                           std::string n = paramInfo.param.substr(1);
                           for (auto& ch : n)
                             if (ch == '.') ch = '_';
                           return n;
                         });

class DicomRoundTrip : public ::testing::TestWithParam<double> {};

// HU survive a DICOM series through Rescale Intercept (0, and -1024 as scanners store it).
TEST_P(DicomRoundTrip, KeepsHUAndGeometry) {
  const fs::path dir = scratch("dicom" + std::to_string(static_cast<int>(-GetParam())));
  const auto image = obliqueVolume();
  writeDicomSeries(image, (dir / "series").string(), GetParam());
  EXPECT_EQ(std::distance(fs::directory_iterator(dir / "series"), fs::directory_iterator{}), 12);
  const auto back = readVolume((dir / "series").string());
  expectSameGeometry(geometryOf(image), geometryOf(back), 1e-4);
  const std::size_t n = image->GetLargestPossibleRegion().GetNumberOfPixels();
  for (std::size_t i = 0; i < n; ++i)
    ASSERT_FLOAT_EQ(image->GetBufferPointer()[i], back->GetBufferPointer()[i]) << "voxel " << i;
}

INSTANTIATE_TEST_SUITE_P(Intercepts, DicomRoundTrip, ::testing::Values(0.0, -1024.0));

TEST(VolumeIO, MissingFileIsAClearError) {
  try {
    readVolume("/nonexistent/pre.nrrd");
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/pre.nrrd"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("no such file"), std::string::npos);
  }
}

TEST(VolumeIO, CorruptFileIsAClearError) {
  const fs::path dir = scratch("corrupt");
  for (const char* name : {"junk.nrrd", "junk.mha", "junk.nii.gz", "junk.nii", "junk.xyz"}) {
    std::ofstream(dir / name) << "this is not an image at all\n";
    EXPECT_THROW(readVolume((dir / name).string()), std::runtime_error) << name;
  }
}

TEST(VolumeIO, TruncatedFileIsAClearError) {
  const fs::path dir = scratch("truncated");
  const auto image = obliqueVolume();
  for (const char* name : {"t.nrrd", "t.mha", "t.nii", "t.nii.gz"}) {
    const fs::path path = dir / name;
    writeVolume(image, path.string());
    fs::resize_file(path, fs::file_size(path) * 2 / 3);
    EXPECT_THROW(readVolume(path.string()), std::runtime_error) << name;
  }
}

TEST(VolumeIO, TwoDimensionalImageIsRejected) {
  const fs::path dir = scratch("twod");
  using Image2 = itk::Image<float, 2>;
  auto flat = Image2::New();
  Image2::RegionType region;
  region.SetSize({{32, 32}});
  flat->SetRegions(region);
  flat->Allocate();
  flat->FillBuffer(1.0f);
  auto writer = itk::ImageFileWriter<Image2>::New();
  writer->SetImageIO(itk::NrrdImageIO::New());
  writer->SetFileName((dir / "flat.nrrd").string());
  writer->SetInput(flat);
  writer->Update();
  try {
    readVolume((dir / "flat.nrrd").string());
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("not a 3-D volume"), std::string::npos) << e.what();
  }
  // A single-slice 3-D file is just as flat.
  Grid g;
  g.size = {16, 16, 1};
  writeVolume(makeImage(g), (dir / "slice.nrrd").string());
  EXPECT_THROW(readVolume((dir / "slice.nrrd").string()), std::runtime_error);
}

TEST(VolumeIO, UnknownOutputExtensionWritesNothing) {
  const fs::path dir = scratch("badext");
  EXPECT_THROW(writeVolume(obliqueVolume(), (dir / "v.png").string()), std::runtime_error);
  EXPECT_TRUE(fs::is_empty(dir));
}

TEST(VolumeGeometry, OverlapOfDisjointBoxesIsZero) {
  Grid g;
  g.size = {10, 10, 10};
  auto a = makeImage(g);
  g.origin = {100, 0, 0};
  auto b = makeImage(g);
  EXPECT_EQ(overlapVolumeMm3(geometryOf(a), geometryOf(b)), 0.0);
  g.origin = {5, 0, 0};
  auto c = makeImage(g);
  EXPECT_NEAR(overlapVolumeMm3(geometryOf(a), geometryOf(c)), 5.0 * 10 * 10, 1e-9);
}
