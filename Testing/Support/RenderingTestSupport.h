// Helpers shared by the rendering tests: a scratch folder per test and a look at a PNG's pixels.
#pragma once

#include "cementsph/rendering/ImageCompare.h"

#include <gtest/gtest.h>

#include "cementsph/rendering/ImageCompare.h"

#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPNGReader.h>
#include <vtkPointData.h>
#include <vtkUnsignedCharArray.h>

#include <array>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <set>
#include <string>
#include <tuple>
#include <vector>

namespace cementsph::rendering::test {

// An empty folder under the build tree named after the running test.
inline std::filesystem::path scratchFolder() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::filesystem::path dir = std::filesystem::path(CEMENTSPH_BINARY_DIR) / "Testing" / "Temporary" /
                              "rendering" / (std::string(info->test_suite_name()) + "." + info->name());
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

// A PNG read back, rows top-down, as RGB triples.
struct Picture {
  using Rgb = std::array<int, 3>;
  int width = 0, height = 0;
  std::vector<Rgb> pixels;
  Rgb at(int x, int y) const { return pixels[std::size_t(y) * std::size_t(width) + std::size_t(x)]; }
  // Darkness 0 (white) .. 1 (black): the ink of black text on white.
  double ink(int x, int y) const {
    const Rgb c = at(x, y);
    return 1.0 - (c[0] + c[1] + c[2]) / (3.0 * 255.0);
  }
};

inline Picture readPicture(const std::filesystem::path& png) {
  vtkNew<vtkPNGReader> reader;
  reader->SetFileName(png.string().c_str());
  reader->Update();
  vtkImageData* image = reader->GetOutput();
  int dims[3];
  image->GetDimensions(dims);
  Picture p;
  p.width = dims[0];
  p.height = dims[1];
  p.pixels.resize(std::size_t(dims[0]) * std::size_t(dims[1]));
  for (int y = 0; y < dims[1]; ++y)
    for (int x = 0; x < dims[0]; ++x)
      for (int c = 0; c < 3; ++c)
        p.pixels[std::size_t(y) * std::size_t(dims[0]) + std::size_t(x)][std::size_t(c)] =
            int(image->GetScalarComponentAsDouble(x, dims[1] - 1 - y, 0, c));
  return p;
}

// The headless case CI sees: no display at all.
inline void forgetDisplay() { unsetenv("DISPLAY"); }

struct PngSummary {
  int width = 0, height = 0;
  std::size_t distinctColours = 0;
  double nonWhiteFraction = 0.0;
};

inline PngSummary summarisePng(const std::filesystem::path& png) {
  vtkNew<vtkPNGReader> reader;
  reader->SetFileName(png.string().c_str());
  reader->Update();
  vtkImageData* image = reader->GetOutput();
  int dims[3] = {0, 0, 0};
  image->GetDimensions(dims);
  PngSummary s;
  s.width = dims[0];
  s.height = dims[1];
  auto* pixels = vtkUnsignedCharArray::SafeDownCast(image->GetPointData()->GetScalars());
  if (pixels == nullptr || pixels->GetNumberOfComponents() < 3) return s;
  std::set<std::tuple<int, int, int>> colours;
  std::size_t nonWhite = 0;
  for (vtkIdType p = 0; p < pixels->GetNumberOfTuples(); ++p) {
    const int r = pixels->GetValue(p * pixels->GetNumberOfComponents());
    const int g = pixels->GetValue(p * pixels->GetNumberOfComponents() + 1);
    const int b = pixels->GetValue(p * pixels->GetNumberOfComponents() + 2);
    colours.emplace(r, g, b);
    if (r < 250 || g < 250 || b < 250) ++nonWhite;
  }
  s.distinctColours = colours.size();
  s.nonWhiteFraction = static_cast<double>(nonWhite) / static_cast<double>(pixels->GetNumberOfTuples());
  return s;
}

// Compares a rendering with the baseline baselineDir/baselineName (imageDifference <= tolerance), or, with
// CEMENTSPH_UPDATE_BASELINES set, replaces the baseline with the rendering and skips the test (look at
// the picture before committing it).
inline void expectMatchesBaseline(const std::filesystem::path& rendered, const std::filesystem::path& baselineDir,
                                  const std::string& baselineName, double tolerance) {
  const std::filesystem::path baseline = baselineDir / baselineName;
  if (std::getenv("CEMENTSPH_UPDATE_BASELINES") != nullptr) {
    std::filesystem::create_directories(baselineDir);
    std::filesystem::copy_file(rendered, baseline, std::filesystem::copy_options::overwrite_existing);
    GTEST_SKIP() << "baseline " << baseline << " rewritten; inspect it before committing";
  }
  ASSERT_TRUE(std::filesystem::exists(baseline)) << baseline;
  const double difference = cementsph::rendering::imageDifference(rendered, baseline);
  std::cout << "difference from baseline " << baselineName << ": " << difference << "\n";
  EXPECT_LE(difference, tolerance) << rendered << " differs from " << baseline;
}

#ifdef CEMENTSPH_BASELINE_DIR
inline const std::filesystem::path kBaselineDir = CEMENTSPH_BASELINE_DIR;

// The same against Testing/Data/Baselines/<baselineName>.
inline void expectMatchesBaseline(const std::filesystem::path& rendered, const std::string& baselineName,
                                  double tolerance) {
  expectMatchesBaseline(rendered, kBaselineDir, baselineName, tolerance);
}
#endif

} // namespace cementsph::rendering::test
