// Volume IO: every format keeps origin, spacing and a non-identity direction; DICOM keeps HU;
// bad input gives a clear std::runtime_error naming the file; writes leave no partial files; the NRRD gzip
// written with libdeflate (NrrdGzip, at the end).
#include "SyntheticVolumes.h"
#include "cementsph/imaging/AtomicFile.h"
#include "cementsph/imaging/VolumeIO.h"

#include <gtest/gtest.h>
#include <itkImageFileWriter.h>
#include <itkImageRegionIterator.h>
#include <itkNrrdImageIO.h>
#include <zlib.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <locale>
#include <sstream>
#include <string>
#include <vector>

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

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// A CT-like volume: 61 x 47 x 33 (no size a power of two), oblique, of HU noise that deflates poorly.
ImageType::Pointer noisyCt() {
  Grid g;
  g.size = {61, 47, 33};
  g.spacing = {0.6, 0.6, 1.25};
  g.origin = {-20.0, 15.5, -7.25};
  const double c = std::cos(0.4), s = std::sin(0.4); // oblique: rotated about x, as a tilted gantry
  g.direction = {1, 0, 0, 0, c, -s, 0, s, c};
  auto image = makeImage(g);
  float* p = image->GetBufferPointer();
  unsigned state = 12345u;
  for (std::size_t i = 0; i < image->GetLargestPossibleRegion().GetNumberOfPixels(); ++i) {
    state = state * 1664525u + 1013904223u; // a linear congruential generator: reproducible noise
    p[i] = -1000.0f + static_cast<float>(state >> 20) * 0.37f;
  }
  return image;
}

struct Payload {
  std::string header;
  std::vector<unsigned char> inflated;
  int status = 0;           // zlib's last inflate() status
  std::size_t leftOver = 0; // input bytes after the gzip member's end
};

// Inflates the file's payload with zlib (gzip wrapper: windowBits 15 + 16), one member.
Payload inflateWithZlib(const fs::path& file, std::size_t expectedBytes) {
  const std::string bytes = slurp(file);
  Payload out;
  const std::size_t blank = bytes.find("\n\n");
  if (blank == std::string::npos) return out;
  out.header = bytes.substr(0, blank + 2);
  z_stream z{};
  if (inflateInit2(&z, 15 + 16) != Z_OK) return out;
  out.inflated.resize(expectedBytes + 1); // one spare byte: more data than the voxels would show
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(bytes.data() + blank + 2));
  z.avail_in = static_cast<uInt>(bytes.size() - blank - 2);
  z.next_out = out.inflated.data();
  z.avail_out = static_cast<uInt>(out.inflated.size());
  out.status = inflate(&z, Z_FINISH);
  out.inflated.resize(z.total_out);
  out.leftOver = z.avail_in;
  inflateEnd(&z);
  return out;
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

// The gzip NRRD volumes writeVolume and writeMask write (src/NrrdGzip.h: the header ITK's writer would give,
// the voxels deflated by libdeflate). Checked with two decoders that share no code with libdeflate: zlib's
// inflate on the payload (one gzip member, the voxels' bytes exactly, nothing after it) and ITK's NRRD reader
// (Teem) through readVolume; and the header against the one ITK's own NRRD writer gives the same image.

TEST(NrrdGzip, AFloatVolumesPayloadIsOneGzipMemberOfItsVoxels) {
  const fs::path dir = scratch("gzip-float");
  const auto image = noisyCt();
  const fs::path path = dir / "ct.nrrd";
  writeVolume(image, path.string());
  EXPECT_TRUE(onlyFinalFilesIn(dir)); // ITK's raw file removed
  const std::size_t n = image->GetLargestPossibleRegion().GetNumberOfPixels();
  const Payload p = inflateWithZlib(path, n * sizeof(float));
  EXPECT_NE(p.header.find("\nencoding: gzip\n"), std::string::npos) << p.header;
  EXPECT_EQ(p.header.find("encoding: raw"), std::string::npos);
  EXPECT_EQ(p.status, Z_STREAM_END);
  EXPECT_EQ(p.leftOver, 0u);
  ASSERT_EQ(p.inflated.size(), n * sizeof(float));
  EXPECT_EQ(std::memcmp(p.inflated.data(), image->GetBufferPointer(), p.inflated.size()), 0);
  // Smaller than the voxels (the noise's 12 random bits of 32 leave room), as a compressed file should be.
  EXPECT_LT(fs::file_size(path), n * sizeof(float));

  // ITK's reader (Teem's gzip) gives every voxel and the geometry back.
  const auto back = readVolume(path.string());
  ASSERT_EQ(back->GetLargestPossibleRegion().GetNumberOfPixels(), n);
  EXPECT_EQ(std::memcmp(back->GetBufferPointer(), image->GetBufferPointer(), n * sizeof(float)), 0);
  for (unsigned a = 0; a < 3; ++a) {
    EXPECT_NEAR(back->GetSpacing()[a], image->GetSpacing()[a], 1e-12);
    EXPECT_NEAR(back->GetOrigin()[a], image->GetOrigin()[a], 1e-12);
    for (unsigned b = 0; b < 3; ++b) EXPECT_NEAR(back->GetDirection()[a][b], image->GetDirection()[a][b], 1e-12);
  }
}

TEST(NrrdGzip, AMasksPayloadIsOneGzipMemberOfItsLabels) {
  const fs::path dir = scratch("gzip-mask");
  auto mask = MaskType::New();
  MaskType::SizeType size;
  size[0] = 29;
  size[1] = 31;
  size[2] = 17;
  mask->SetRegions(MaskType::RegionType(size));
  mask->Allocate();
  std::size_t i = 0;
  for (itk::ImageRegionIterator<MaskType> it(mask, mask->GetLargestPossibleRegion()); !it.IsAtEnd(); ++it, ++i)
    it.Set(static_cast<unsigned char>((i * 7919) % 5 == 0 ? i % 4 : 0));
  const fs::path path = dir / "labels.nrrd";
  writeMask(mask, path.string());
  EXPECT_TRUE(onlyFinalFilesIn(dir));
  const std::size_t n = mask->GetLargestPossibleRegion().GetNumberOfPixels();
  const Payload p = inflateWithZlib(path, n);
  EXPECT_NE(p.header.find("\nencoding: gzip\n"), std::string::npos) << p.header;
  EXPECT_EQ(p.status, Z_STREAM_END);
  EXPECT_EQ(p.leftOver, 0u);
  ASSERT_EQ(p.inflated.size(), n);
  EXPECT_EQ(std::memcmp(p.inflated.data(), mask->GetBufferPointer(), n), 0);
}

TEST(NrrdGzip, UncompressedWritesStayRaw) {
  const fs::path dir = scratch("gzip-raw");
  const auto image = noisyCt();
  const fs::path path = dir / "ct.nrrd";
  writeVolume(image, path.string(), /*compress=*/false);
  const std::string bytes = slurp(path);
  EXPECT_NE(bytes.find("\nencoding: raw\n"), std::string::npos);
  const std::size_t n = image->GetLargestPossibleRegion().GetNumberOfPixels() * sizeof(float);
  ASSERT_GT(bytes.size(), n);
  EXPECT_EQ(std::memcmp(bytes.data() + bytes.size() - n, image->GetBufferPointer(), n), 0);
}

// The header, field by field, against the one ITK's NRRD writer gives the same oblique image (written raw):
// the same fields in the same order, the same values (numbers to 1e-15 relative), but the encoding.
TEST(NrrdGzip, TheHeaderIsTheOneItksWriterGives) {
  const fs::path dir = scratch("gzip-header");
  const auto image = noisyCt();
  writeVolume(image, (dir / "ours.nrrd").string());
  writeVolume(image, (dir / "itk.nrrd").string(), /*compress=*/false); // ITK's NrrdImageIO
  auto headerLines = [](const fs::path& p) {
    const std::string bytes = slurp(p);
    std::vector<std::string> lines;
    std::istringstream in(bytes.substr(0, bytes.find("\n\n")));
    for (std::string line; std::getline(in, line);) lines.push_back(line);
    return lines;
  };
  auto numbers = [](const std::string& line) {
    std::vector<double> v;
    std::string cleaned = line.substr(line.find(':') + 1);
    for (char& ch : cleaned)
      if (ch == '(' || ch == ')' || ch == ',') ch = ' ';
    std::istringstream in(cleaned);
    in.imbue(std::locale::classic());
    for (double x; in >> x;) v.push_back(x);
    return v;
  };
  const auto ours = headerLines(dir / "ours.nrrd"), itk = headerLines(dir / "itk.nrrd");
  ASSERT_EQ(ours.size(), itk.size());
  int numeric = 0;
  for (std::size_t i = 0; i < ours.size(); ++i) {
    const std::string key = itk[i].substr(0, itk[i].find(':'));
    ASSERT_EQ(ours[i].substr(0, ours[i].find(':')), key) << "line " << i;
    if (key == "encoding") {
      EXPECT_EQ(itk[i], "encoding: raw");
      EXPECT_EQ(ours[i], "encoding: gzip");
    } else if (key == "space directions" || key == "space origin") {
      const auto a = numbers(ours[i]), b = numbers(itk[i]);
      ASSERT_EQ(a.size(), key == "space origin" ? 3u : 9u) << ours[i];
      ASSERT_EQ(a.size(), b.size()) << itk[i];
      for (std::size_t k = 0; k < a.size(); ++k) EXPECT_NEAR(a[k], b[k], 1e-15 * (1 + std::abs(b[k]))) << key << " " << k;
      ++numeric;
    } else {
      EXPECT_EQ(ours[i], itk[i]);
    }
  }
  EXPECT_EQ(numeric, 2);
}

// A write that cannot happen (its folder is missing) is one error, and leaves nothing.
TEST(NrrdGzip, AWriteThatCannotHappenLeavesNothing) {
  const fs::path dir = scratch("gzip-unwritable");
  EXPECT_THROW(writeVolume(noisyCt(), (dir / "missing" / "ct.nrrd").string()), std::runtime_error);
  EXPECT_TRUE(fs::is_empty(dir));
}
