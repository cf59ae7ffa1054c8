// imageDifference against exact oracles on tiny synthetic images.
#include "RenderingTestSupport.h"

#include "cementsph/rendering/ImageCompare.h"

#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPNGWriter.h>

#include <gtest/gtest.h>

#include <fstream>

using cementsph::rendering::imageDifference;
using cementsph::rendering::meanAbsoluteDifference;

namespace {
// A w x h RGB image whose left `blackColumns` columns are black and the rest white.
std::filesystem::path writeTestPng(const std::filesystem::path& file, int w, int h, int blackColumns) {
  vtkNew<vtkImageData> image;
  image->SetDimensions(w, h, 1);
  image->AllocateScalars(VTK_UNSIGNED_CHAR, 3);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      auto* px = static_cast<unsigned char*>(image->GetScalarPointer(x, y, 0));
      px[0] = px[1] = px[2] = x < blackColumns ? 0 : 255;
    }
  }
  vtkNew<vtkPNGWriter> writer;
  writer->SetFileName(file.string().c_str());
  writer->SetInputData(image);
  writer->Write();
  return file;
}
} // namespace

TEST(ImageCompare, ExactOracles) {
  const auto dir = cementsph::rendering::test::scratchFolder();
  const auto white = writeTestPng(dir / "white.png", 8, 4, 0);
  const auto black = writeTestPng(dir / "black.png", 8, 4, 8);
  const auto half = writeTestPng(dir / "half.png", 8, 4, 4);
  EXPECT_DOUBLE_EQ(imageDifference(white, white), 0.0);
  EXPECT_DOUBLE_EQ(imageDifference(white, black), 1.0);
  // Columns 0..3 are black in one and white everywhere near them in the other.
  EXPECT_DOUBLE_EQ(imageDifference(white, half), 0.5);
  EXPECT_DOUBLE_EQ(imageDifference(half, white), 0.5);
  EXPECT_DOUBLE_EQ(meanAbsoluteDifference(white, white), 0.0);
  EXPECT_DOUBLE_EQ(meanAbsoluteDifference(white, black), 1.0);
  EXPECT_DOUBLE_EQ(meanAbsoluteDifference(half, white), 0.5);
}

TEST(ImageCompare, OnePixelShiftIsNotADifference) {
  const auto dir = cementsph::rendering::test::scratchFolder();
  const auto edgeAt4 = writeTestPng(dir / "edge4.png", 8, 4, 4);
  const auto edgeAt5 = writeTestPng(dir / "edge5.png", 8, 4, 5);
  const auto edgeAt6 = writeTestPng(dir / "edge6.png", 8, 4, 6);
  EXPECT_DOUBLE_EQ(imageDifference(edgeAt4, edgeAt5), 0.0);
  EXPECT_DOUBLE_EQ(meanAbsoluteDifference(edgeAt4, edgeAt5), 0.125); // the strict measure does see it
  // Two pixels is a real change: column 4 (white, only black within one pixel in the other image) and
  // column 5 (black, only white nearby in the other) count, 2 of 8 columns.
  EXPECT_DOUBLE_EQ(imageDifference(edgeAt4, edgeAt6), 0.25);
}

TEST(ImageCompare, RejectsDifferentSizesAndNonPng) {
  const auto dir = cementsph::rendering::test::scratchFolder();
  const auto small = writeTestPng(dir / "small.png", 8, 4, 0);
  const auto large = writeTestPng(dir / "large.png", 8, 5, 0);
  EXPECT_THROW(imageDifference(small, large), std::runtime_error);
  std::ofstream(dir / "text.png") << "not a png\n";
  EXPECT_THROW(imageDifference(small, dir / "text.png"), std::runtime_error);
  EXPECT_THROW(imageDifference(small, dir / "missing.png"), std::runtime_error);
}
