// Issue 20, item 6: slice pictures a planning engineer can read. cement_slices.png (writeCementSlices) and
// slices.png (renderSliceComparison) carry plane names, patient-direction letters on the panels' edges, a scale
// bar, and for cement_slices.png the cannula tip and trajectory, leak classes in colour with a legend and the
// vertebra's outline. Every position is checked against a value the test computes itself from the CT's grid:
// the panels are found by their pixels (the CT is one known grey), the letters by comparing the ink beside an edge
// with the glyph FreeType draws for the expected letter and for its opposite.
#include "RenderingTestSupport.h"

#include "cementsph/rendering/CementSlices.h"
#include "cementsph/rendering/SliceComparison.h"

#include <gtest/gtest.h>

#include <vtkFreeTypeTools.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPNGReader.h>
#include <vtkPointData.h>
#include <vtkDataArray.h>
#include <vtkSmartPointer.h>
#include <vtkStdString.h>
#include <vtkTextProperty.h>

#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <vector>

using namespace cementsph::rendering;
using cementsph::rendering::test::scratchFolder;

namespace {

using cementsph::rendering::test::Picture;
using cementsph::rendering::test::readPicture;
using Rgb = Picture::Rgb;

std::size_t differingPixels(const Picture& a, const Picture& b) {
  std::size_t differing = 0;
  for (std::size_t n = 0; n < std::min(a.pixels.size(), b.pixels.size()); ++n) differing += a.pixels[n] != b.pixels[n];
  return differing;
}

struct Rect {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0; // [x0, x1) x [y0, y1)
  int width() const { return x1 - x0; }
  int height() const { return y1 - y0; }
};

// The panels: maximal runs of columns holding a vertical run of at least 10 pixels of the CT's grey (anti-aliased
// text has neutral greys too, never ten of one value in a column), each with the extent of those runs.
std::vector<Rect> findPanels(const Picture& p, Rgb grey) {
  std::vector<Rect> panels;
  std::optional<Rect> open;
  for (int x = 0; x <= p.width; ++x) {
    int top = -1, bottom = -1;
    if (x < p.width)
      for (int y = 0, run = 0; y < p.height; ++y) {
        run = p.at(x, y) == grey ? run + 1 : 0;
        if (run >= 10) {
          if (top < 0) top = y - run + 1;
          bottom = y + 1;
        }
      }
    if (top >= 0) {
      if (!open) open = Rect{x, top, x + 1, bottom};
      open->x1 = x + 1;
      open->y0 = std::min(open->y0, top);
      open->y1 = std::max(open->y1, bottom);
    } else if (open) {
      panels.push_back(*open);
      open.reset();
    }
  }
  return panels;
}

// The glyph FreeType draws for a letter: the ink (0..1) in its tight box, row by row from the top.
struct Glyph {
  int width = 0, height = 0;
  std::vector<double> ink;
};

Glyph tight(const std::vector<double>& ink, int w, int h) {
  int x0 = w, y0 = h, x1 = -1, y1 = -1;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      if (ink[std::size_t(y * w + x)] > 0.1) x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
  Glyph g;
  if (x1 < 0) return g;
  g.width = x1 - x0 + 1;
  g.height = y1 - y0 + 1;
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) g.ink.push_back(ink[std::size_t(y * w + x)]);
  return g;
}

Glyph renderText(const std::string& text, int fontPx, bool bold) {
  vtkNew<vtkTextProperty> property;
  property->SetFontFamilyToArial();
  property->SetFontSize(fontPx);
  property->SetBold(bold);
  property->SetColor(0, 0, 0);
  vtkNew<vtkImageData> image;
  int size[2];
  EXPECT_TRUE(vtkFreeTypeTools::GetInstance()->RenderString(property, vtkStdString(text), 72, image, size));
  int extent[6];
  image->GetExtent(extent);
  std::vector<double> ink(static_cast<std::size_t>(size[0]) * static_cast<std::size_t>(size[1]));
  for (int y = 0; y < size[1]; ++y)
    for (int x = 0; x < size[0]; ++x)
      ink[std::size_t(y * size[0] + x)] =
          image->GetScalarComponentAsDouble(extent[0] + x, extent[2] + size[1] - 1 - y, 0, 3) / 255.0;
  return tight(ink, size[0], size[1]);
}

Glyph renderLetter(char letter, int fontPx) { return renderText(std::string(1, letter), fontPx, true); }

Glyph inkIn(const Picture& p, Rect r) {
  r.x0 = std::max(0, r.x0), r.y0 = std::max(0, r.y0), r.x1 = std::min(p.width, r.x1), r.y1 = std::min(p.height, r.y1);
  std::vector<double> ink;
  for (int y = r.y0; y < r.y1; ++y)
    for (int x = r.x0; x < r.x1; ++x) ink.push_back(p.ink(x, y));
  return tight(ink, r.width(), r.height());
}

// Mean |ink difference| of two glyphs aligned at their boxes' top-left corners (1 where the boxes differ).
double glyphDifference(const Glyph& a, const Glyph& b) {
  if (a.width != b.width || a.height != b.height || a.ink.empty()) return 1.0;
  double sum = 0;
  for (std::size_t n = 0; n < a.ink.size(); ++n) sum += std::abs(a.ink[n] - b.ink[n]);
  return sum / double(a.ink.size());
}

// The letter in box is `expected`, not `opposite`: the ink there is FreeType's glyph of expected (to within the
// rounding of the blend, 0.01 mean) and differs from the opposite letter's.
void expectLetter(const Picture& p, const Rect& box, char expected, char opposite, int fontPx, const std::string& where) {
  const Glyph found = inkIn(p, box);
  const double toExpected = glyphDifference(found, renderLetter(expected, fontPx));
  const double toOpposite = glyphDifference(found, renderLetter(opposite, fontPx));
  EXPECT_LT(toExpected, 0.01) << where << ": the ink there is not '" << expected << "' (" << found.width << " x "
                              << found.height << " px)";
  EXPECT_GT(toOpposite, 0.05) << where << ": the ink there also looks like '" << opposite << "'";
}

// The four edge letters of a panel, given the panels' extents (neighbours bound the side boxes).
void expectEdgeLetters(const Picture& p, const std::vector<Rect>& panels, std::size_t i, const std::string& letters,
                       int fontPx) {
  static const auto opposite = [](char c) {
    const std::string a = "LRAPSI", b = "RLPAIS";
    return b[a.find(c)];
  };
  const Rect& r = panels[i];
  const int band = fontPx + 4; // the letter rows above and below the panel
  const int leftEnd = i > 0 ? (panels[i - 1].x1 + r.x0) / 2 : 0;
  const int rightEnd = i + 1 < panels.size() ? (r.x1 + panels[i + 1].x0) / 2 : p.width;
  const int midY = (r.y0 + r.y1) / 2, midX = (r.x0 + r.x1) / 2;
  const std::string name = "panel " + std::to_string(i);
  expectLetter(p, {leftEnd, midY - band, r.x0, midY + band}, letters[0], opposite(letters[0]), fontPx, name + " left");
  expectLetter(p, {r.x1, midY - band, rightEnd, midY + band}, letters[1], opposite(letters[1]), fontPx, name + " right");
  expectLetter(p, {midX - band, r.y0 - band, midX + band, r.y0}, letters[2], opposite(letters[2]), fontPx, name + " top");
  expectLetter(p, {midX - band, r.y1, midX + band, r.y1 + band}, letters[3], opposite(letters[3]), fontPx, name + " bottom");
}

// The longest horizontal run of black pixels in rows [y0, y1) and columns [x0, x1).
int longestBlackRun(const Picture& p, int x0, int x1, int y0, int y1) {
  int best = 0;
  for (int y = std::max(0, y0); y < std::min(p.height, y1); ++y) {
    int run = 0;
    for (int x = std::max(0, x0); x < std::min(p.width, x1); ++x) {
      run = p.at(x, y) == Rgb{0, 0, 0} ? run + 1 : 0;
      best = std::max(best, run);
    }
  }
  return best;
}

// The centroid of the pixels of one colour inside a rectangle (pixel centres at +0.5); count 0 when none.
struct Centroid {
  double x = 0, y = 0;
  int count = 0;
};
Centroid centroidOf(const Picture& p, const Rect& r, Rgb colour) {
  Centroid c;
  for (int y = r.y0; y < r.y1; ++y)
    for (int x = r.x0; x < r.x1; ++x)
      if (p.at(x, y) == colour) c.x += x + 0.5, c.y += y + 0.5, ++c.count;
  if (c.count) c.x /= c.count, c.y /= c.count;
  return c;
}

bool contains(const Picture& p, const Rect& r, Rgb colour) { return centroidOf(p, r, colour).count > 0; }

// The test CT: 40 x 30 x 24 voxels of 0.8 x 0.8 x 1.5 mm (the panels get different pixel scales), 300 HU
// everywhere (the bone window's level: grey 128 after rounding 127.5).
constexpr int kNx = 40, kNy = 30, kNz = 24;
constexpr double kSpacing[3] = {0.8, 0.8, 1.5};
const Rgb kLevelGrey{128, 128, 128};

// How the test CT's voxels are stored, each the same physical grid: as given (LPS, identity direction); mirrored in
// x (index x runs towards the patient's right, from x = 31.2 mm down to 0); permuted (index x runs to superior, y to
// posterior, z to the patient's left: 24 x 30 x 40 voxels of 1.5 x 0.8 x 0.8 mm).
enum class Stored { Lps, MirroredX, Permuted };

vtkSmartPointer<vtkImageData> volume(int type, double value, Stored stored = Stored::Lps) {
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->SetDimensions(kNx, kNy, kNz);
  image->SetSpacing(kSpacing[0], kSpacing[1], kSpacing[2]);
  if (stored == Stored::MirroredX) {
    image->SetOrigin((kNx - 1) * kSpacing[0], 0, 0);
    image->SetDirectionMatrix(-1, 0, 0, 0, 1, 0, 0, 0, 1);
  } else if (stored == Stored::Permuted) {
    image->SetDimensions(kNz, kNy, kNx);
    image->SetSpacing(kSpacing[2], kSpacing[1], kSpacing[0]);
    image->SetDirectionMatrix(0, 0, 1, 0, 1, 0, 1, 0, 0); // columns: index x -> +z, y -> +y, z -> +x
  }
  image->AllocateScalars(type, 1);
  image->GetPointData()->GetScalars()->Fill(value);
  return image;
}

// Sets the voxels whose centres lie in the box [lo, hi] (mm, patient frame) to value.
void paintBox(vtkImageData* image, const std::array<double, 3>& lo, const std::array<double, 3>& hi, double value) {
  int d[3];
  image->GetDimensions(d);
  for (int k = 0; k < d[2]; ++k)
    for (int j = 0; j < d[1]; ++j)
      for (int i = 0; i < d[0]; ++i) {
        double p[3];
        image->TransformIndexToPhysicalPoint(i, j, k, p);
        if (p[0] >= lo[0] && p[0] <= hi[0] && p[1] >= lo[1] && p[1] <= hi[1] && p[2] >= lo[2] && p[2] <= hi[2])
          image->SetScalarComponentFromDouble(i, j, k, 0, value);
      }
}

// The physical point (mm) of a continuous index in an identity-direction CT at the origin, and back.
double toIndex(double mm, int axis) { return mm / kSpacing[axis]; }

// Where a point at continuous index (i, j, k) lands on each panel (continuous pixel coordinates, pixel centres at
// +0.5), given the panel rectangles found in the picture: axial x right, y down; coronal x right, z up; sagittal y
// right, z up. Each voxel is the panel's extent divided by the voxel count on that axis.
std::array<double, 2> onPanel(const Rect& r, double right, int rightCount, double vertical, int verticalCount, bool up) {
  const double x = r.x0 + (right + 0.5) * r.width() / rightCount;
  const double down = (vertical + 0.5) * r.height() / verticalCount;
  return {x, up ? r.y1 - down : r.y0 + down};
}

} // namespace

TEST(LabelledCementSlices, ConventionalViewsLetteredFromTheDirectionMatrixHoweverTheCTIsStored) {
  const auto dir = scratchFolder();
  CementSlicesOptions o;
  // One patient: 300 HU with a white marker (1050 HU and above is white in the bone window) at the patient's left,
  // anterior and superior: x 22..28.4, y 2..7, z 23.5..31 mm. The slices cross inside it.
  const std::array<double, 3> centre{25.0, 4.5, 27.0};
  const Rgb white{255, 255, 255};
  auto picture = [&](Stored stored, const std::filesystem::path& png) {
    auto ct = volume(VTK_FLOAT, 300.0, stored);
    paintBox(ct, {22, 2, 23.5}, {28.4, 7, 31}, 1050.0); // no voxel centre on a face: storage-independent
    writeCementSlices(ct, volume(VTK_UNSIGNED_CHAR, 0, stored), centre, png, o);
    return readPicture(png);
  };
  const Picture lps = picture(Stored::Lps, dir / "lps.png");
  const auto panels = findPanels(lps, kLevelGrey);
  ASSERT_EQ(panels.size(), 3u);
  // Radiological views of an LPS CT (x to the patient's left, y posterior, z superior): axial with the patient's
  // right on the picture's left and anterior up; coronal right on the left, superior up; sagittal anterior on the
  // left, superior up.
  expectEdgeLetters(lps, panels, 0, "RLAP", o.fontPx);
  expectEdgeLetters(lps, panels, 1, "RLSI", o.fontPx);
  expectEdgeLetters(lps, panels, 2, "APSI", o.fontPx);
  // The marker where those letters say: on the L and A side of the axial panel, L and S of the coronal, A and S
  // of the sagittal (its white pixels' centroid right or left of and above the panel's middle).
  const bool towardsRight[3] = {true, true, false};
  for (std::size_t i = 0; i < 3; ++i) {
    const Centroid c = centroidOf(lps, panels[i], white);
    ASSERT_GT(c.count, 100) << "no marker on panel " << i;
    EXPECT_EQ(c.x > 0.5 * (panels[i].x0 + panels[i].x1), towardsRight[i]) << "panel " << i;
    EXPECT_LT(c.y, 0.5 * (panels[i].y0 + panels[i].y1)) << "panel " << i;
  }
  // The plane names: text (ink) in the title row above each panel.
  for (const Rect& r : panels) EXPECT_GT(inkIn(lps, {r.x0 - 10, r.y0 - 2 * (o.fontPx + 6), r.x1, r.y0 - o.fontPx - 6}).width, 20);
  // The same patient stored mirrored in x, or with its axes permuted (the same physical grid): the same picture,
  // pixel for pixel, letters included.
  for (const auto& [stored, name] : {std::make_pair(Stored::MirroredX, "mirrored.png"), std::make_pair(Stored::Permuted, "permuted.png")}) {
    const Picture other = picture(stored, dir / name);
    ASSERT_EQ(other.width, lps.width) << name;
    ASSERT_EQ(other.height, lps.height) << name;
    EXPECT_EQ(differingPixels(other, lps), 0u) << name << " differs from the LPS CT's picture";
  }
}

TEST(LabelledCementSlices, ScaleBarIsTenMillimetresAtEachPanelsScale) {
  const auto dir = scratchFolder();
  CementSlicesOptions o;
  writeCementSlices(volume(VTK_FLOAT, 300.0), volume(VTK_UNSIGNED_CHAR, 0), {16, 12, 18}, dir / "bar.png", o);
  const Picture p = readPicture(dir / "bar.png");
  const auto panels = findPanels(p, kLevelGrey);
  ASSERT_EQ(panels.size(), 3u);
  // Horizontal axes: x (0.8 mm, 40 voxels), x, y (0.8 mm, 30 voxels). Pixels per voxel: the panel's width over
  // its voxel count; 10 mm is 10 / 0.8 voxels.
  const int across[3] = {kNx, kNx, kNy};
  const double spacing[3] = {kSpacing[0], kSpacing[0], kSpacing[1]};
  for (std::size_t i = 0; i < 3; ++i) {
    const Rect& r = panels[i];
    const double pixelsPerVoxel = double(r.width()) / across[i];
    const double expected = 10.0 / spacing[i] * pixelsPerVoxel;
    const int measured = longestBlackRun(p, r.x0, r.x1, r.y1, r.y1 + 3 * (o.fontPx + 6));
    std::cout << "panel " << i << ": " << r.width() << " x " << r.height() << " px, scale bar " << measured
              << " px, expected " << expected << " px\n";
    EXPECT_NEAR(measured, expected, 1.0) << "panel " << i;
  }
  // No bar when asked for none.
  o.scaleBarMm = 0.0;
  writeCementSlices(volume(VTK_FLOAT, 300.0), volume(VTK_UNSIGNED_CHAR, 0), {16, 12, 18}, dir / "none.png", o);
  const Picture none = readPicture(dir / "none.png");
  const auto nonePanels = findPanels(none, kLevelGrey);
  ASSERT_EQ(nonePanels.size(), 3u);
  EXPECT_LT(longestBlackRun(none, nonePanels[0].x0, nonePanels[0].x1, nonePanels[0].y1, nonePanels[0].y1 + 40), 20);
  o.scaleBarMm = -1.0;
  EXPECT_THROW(writeCementSlices(volume(VTK_FLOAT, 300.0), volume(VTK_UNSIGNED_CHAR, 0), {16, 12, 18}, dir / "x.png", o),
               std::invalid_argument);
}

TEST(LabelledCementSlices, TipRingAndShaftSitWhereTheyProject) {
  const auto dir = scratchFolder();
  CementSlicesOptions o;
  const std::array<double, 3> tip{13.3, 9.7, 14.2};
  // From the entry towards the tip: down (-z) and forwards (-y), a little to the left (+x): the shaft lies behind
  // the tip, above it and posterior.
  const double n = std::sqrt(0.2 * 0.2 + 0.5 * 0.5 + 0.8 * 0.8);
  const std::array<double, 3> d{0.2 / n, -0.5 / n, -0.8 / n};
  o.tipMm = tip;
  o.directionUnit = d;
  writeCementSlices(volume(VTK_FLOAT, 300.0), volume(VTK_UNSIGNED_CHAR, 0), {16, 12, 18}, dir / "tip.png", o);
  const Picture p = readPicture(dir / "tip.png");
  const auto panels = findPanels(p, kLevelGrey);
  ASSERT_EQ(panels.size(), 3u);
  const Rgb ring{255, 255, 0}, shaft{0, 220, 255};
  const double ti = toIndex(tip[0], 0), tj = toIndex(tip[1], 1), tk = toIndex(tip[2], 2);
  const std::array<double, 2> expected[3] = {onPanel(panels[0], ti, kNx, tj, kNy, false),
                                             onPanel(panels[1], ti, kNx, tk, kNz, true),
                                             onPanel(panels[2], tj, kNy, tk, kNz, true)};
  // 8 mm back along the shaft.
  const double bi = toIndex(tip[0] - 8 * d[0], 0), bj = toIndex(tip[1] - 8 * d[1], 1), bk = toIndex(tip[2] - 8 * d[2], 2);
  const std::array<double, 2> behind[3] = {onPanel(panels[0], bi, kNx, bj, kNy, false),
                                           onPanel(panels[1], bi, kNx, bk, kNz, true),
                                           onPanel(panels[2], bj, kNy, bk, kNz, true)};
  for (std::size_t i = 0; i < 3; ++i) {
    const Centroid c = centroidOf(p, panels[i], ring);
    ASSERT_GT(c.count, 20) << "no tip ring on panel " << i;
    std::cout << "panel " << i << ": tip ring at (" << c.x << ", " << c.y << "), projected (" << expected[i][0] << ", "
              << expected[i][1] << ")\n";
    EXPECT_NEAR(c.x, expected[i][0], 1.0) << "panel " << i;
    EXPECT_NEAR(c.y, expected[i][1], 1.0) << "panel " << i;
    // The shaft passes 8 mm behind the tip (within 2 px of its projection) and not 8 mm ahead of it.
    const int bx = int(behind[i][0]), by = int(behind[i][1]);
    EXPECT_TRUE(contains(p, {bx - 2, by - 2, bx + 3, by + 3}, shaft)) << "no shaft 8 mm behind the tip, panel " << i;
    const int ax = int(2 * expected[i][0] - behind[i][0]), ay = int(2 * expected[i][1] - behind[i][1]);
    EXPECT_FALSE(contains(p, {ax - 2, ay - 2, ax + 3, ay + 3}, shaft)) << "shaft drawn ahead of the tip, panel " << i;
  }
  // The same cannula in the same patient stored mirrored or permuted: the same picture, pixel for pixel.
  for (const auto& [stored, name] : {std::make_pair(Stored::MirroredX, "mirrored.png"), std::make_pair(Stored::Permuted, "permuted.png")}) {
    writeCementSlices(volume(VTK_FLOAT, 300.0, stored), volume(VTK_UNSIGNED_CHAR, 0, stored), {16, 12, 18}, dir / name, o);
    const Picture other = readPicture(dir / name);
    ASSERT_EQ(other.pixels.size(), p.pixels.size()) << name;
    EXPECT_EQ(differingPixels(other, p), 0u) << name << " differs from the LPS CT's picture";
  }
}

TEST(LabelledCementSlices, LeaksTakeTheirClassColourAndTheLegendShowsIt) {
  const auto dir = scratchFolder();
  // Two leaks on the axial slice k = 12: a disc leak at i 30..33, j 5..8 and a venous leak at i 5..8, j 20..23;
  // cement in bone between.
  auto labels = volume(VTK_UNSIGNED_CHAR, 0), classes = volume(VTK_UNSIGNED_CHAR, 1); // 1: target vertebra
  for (int k = 10; k < 15; ++k)
    for (int j = 0; j < kNy; ++j)
      for (int i = 0; i < kNx; ++i) {
        const bool disc = i >= 30 && i < 34 && j >= 5 && j < 9, vein = i >= 5 && i < 9 && j >= 20 && j < 24;
        const bool cement = i >= 15 && i < 25 && j >= 10 && j < 20;
        labels->SetScalarComponentFromDouble(i, j, k, 0, disc || vein ? 2 : cement ? 1 : 0);
        classes->SetScalarComponentFromDouble(i, j, k, 0, disc ? 2 : vein ? 4 : 1); // TissueClass Disc 2, Vessel 4
      }
  const Rgb discColour{220, 0, 220}, venousColour{140, 70, 255}, unknownLeak{230, 20, 20};
  const std::array<double, 3> centre{20 * 0.8, 15 * 0.8, 12 * 1.5};
  auto check = [&](const std::filesystem::path& png, Rgb first, Rgb second) {
    const Picture p = readPicture(png);
    const auto panels = findPanels(p, kLevelGrey);
    ASSERT_EQ(panels.size(), 3u);
    const Rect& axial = panels[0];
    // The leaked voxels' pixels (axial: x right, y down), at the blocks' centres.
    const auto a = onPanel(axial, 31.5, kNx, 6.5, kNy, false), b = onPanel(axial, 6.5, kNx, 21.5, kNy, false);
    EXPECT_EQ(p.at(int(a[0]), int(a[1])), first);
    EXPECT_EQ(p.at(int(b[0]), int(b[1])), second);
    // The legend, below the panels' labels, holds the same colours.
    int below = 0;
    for (const Rect& r : panels) below = std::max(below, r.y1);
    const Rect legend{0, below + 2 * (14 + 6), p.width, p.height};
    EXPECT_TRUE(contains(p, legend, first)) << "legend without the first leak's colour";
    EXPECT_TRUE(contains(p, legend, second)) << "legend without the second leak's colour";
  };
  CementSlicesOptions o;
  o.tissueClasses = classes; // exact: each voxel's own class
  writeCementSlices(volume(VTK_FLOAT, 300.0), labels, centre, dir / "classes.png", o);
  check(dir / "classes.png", discColour, venousColour);
  // From the sites metrics.json lists (each voxel: the nearest site's kind).
  CementSlicesOptions bySites;
  bySites.leakSites = {{{31.5 * 0.8, 6.5 * 0.8, 12 * 1.5}, "disc"}, {{6.5 * 0.8, 21.5 * 0.8, 12 * 1.5}, "venous"}};
  writeCementSlices(volume(VTK_FLOAT, 300.0), labels, centre, dir / "sites.png", bySites);
  check(dir / "sites.png", discColour, venousColour);
  // Neither: both red, and red in the legend.
  writeCementSlices(volume(VTK_FLOAT, 300.0), labels, centre, dir / "plain.png");
  check(dir / "plain.png", unknownLeak, unknownLeak);
  // A class map on another grid is refused.
  auto small = vtkSmartPointer<vtkImageData>::New();
  small->SetDimensions(4, 4, 4);
  small->AllocateScalars(VTK_UNSIGNED_CHAR, 1);
  o.tissueClasses = small;
  EXPECT_THROW(writeCementSlices(volume(VTK_FLOAT, 300.0), labels, centre, dir / "x.png", o), std::invalid_argument);
}

TEST(LabelledCementSlices, VertebraOutlineFollowsTheMask) {
  const auto dir = scratchFolder();
  // The vertebra: label 26 (TotalSegmentator's numbering) in i 10..29, j 8..21, all k; another label (27) beside
  // it. The tip in the first: its label is the one outlined.
  auto mask = volume(VTK_SHORT, 0);
  for (int k = 0; k < kNz; ++k)
    for (int j = 0; j < kNy; ++j)
      for (int i = 0; i < kNx; ++i)
        mask->SetScalarComponentFromDouble(i, j, k, 0, (i >= 10 && i < 30 && j >= 8 && j < 22) ? 26 : (i >= 32 ? 27 : 0));
  CementSlicesOptions o;
  o.vertebraMask = mask;
  o.tipMm = std::array<double, 3>{20 * 0.8, 15 * 0.8, 12 * 1.5};
  writeCementSlices(volume(VTK_FLOAT, 300.0), volume(VTK_UNSIGNED_CHAR, 0), {16, 12, 18}, dir / "outline.png", o);
  const Picture p = readPicture(dir / "outline.png");
  const auto panels = findPanels(p, kLevelGrey);
  ASSERT_FALSE(panels.empty());
  const Rect& axial = panels[0];
  const Rgb green{0, 200, 80};
  const double px = double(axial.width()) / kNx, py = double(axial.height()) / kNy;
  // The mask's boundary on the axial panel: x from 10 to 30 voxels, y from 8 to 22 voxels.
  const int left = axial.x0 + int(std::lround(10 * px)), right = axial.x0 + int(std::lround(30 * px));
  const int top = axial.y0 + int(std::lround(8 * py)), bottom = axial.y0 + int(std::lround(22 * py));
  const int midY = (top + bottom) / 2, midX = (left + right) / 2;
  EXPECT_TRUE(contains(p, {left, midY - 2, left + 2, midY + 2}, green)) << "no outline on the left boundary";
  EXPECT_TRUE(contains(p, {right - 2, midY - 2, right, midY + 2}, green)) << "no outline on the right boundary";
  EXPECT_TRUE(contains(p, {midX - 2, top, midX + 2, top + 2}, green)) << "no outline on the top boundary";
  EXPECT_TRUE(contains(p, {midX - 2, bottom - 2, midX + 2, bottom}, green)) << "no outline on the bottom boundary";
  EXPECT_FALSE(contains(p, {left + 4, top + 4, right - 4, bottom - 4}, green)) << "outline inside the vertebra";
  // The other label (i >= 32) is not outlined.
  EXPECT_FALSE(contains(p, {axial.x0 + int(31 * px), axial.y0, axial.x1, axial.y1}, green)) << "the neighbour is outlined";
}

TEST(LabelledSliceComparison, AxialPanelsCarryLettersAndScaleBar) {
  const auto dir = scratchFolder();
  // 40 x 30 x 24 voxels of 0.8 x 0.8 x 1.5 mm, 300 HU with a cement slab (2000 HU) in k 10..13. HU window
  // -200..2000: 300 HU is grey round(255 * 500 / 2200) = 58.
  auto post = volume(VTK_FLOAT, 300.0);
  for (int k = 10; k < 14; ++k)
    for (int j = 10; j < 20; ++j)
      for (int i = 15; i < 25; ++i) post->SetScalarComponentFromDouble(i, j, k, 0, 2000.0);
  SliceComparisonOptions o;
  renderSliceComparison(post, nullptr, dir / "slices.png", 5.0, o);
  const Picture p = readPicture(dir / "slices.png");
  const Rgb grey{58, 58, 58};
  const auto panels = findPanels(p, grey);
  ASSERT_FALSE(panels.empty());
  for (std::size_t i = 0; i < panels.size(); ++i) {
    // Axial, LPS: right on the left, anterior up.
    expectEdgeLetters(p, panels, i, "RLAP", o.fontPx);
    const double pixelsPerVoxel = double(panels[i].width()) / kNx;
    const double expected = 10.0 / kSpacing[0] * pixelsPerVoxel;
    const int measured = longestBlackRun(p, panels[i].x0, panels[i].x1, panels[i].y1, panels[i].y1 + 3 * (o.fontPx + 6));
    std::cout << "slice " << i << ": scale bar " << measured << " px, expected " << expected << " px\n";
    EXPECT_NEAR(measured, expected, 1.0);
  }
  // The same patient stored mirrored in x or with permuted axes (the same physical grid): the same picture, pixel
  // for pixel (slices, letters, bars).
  for (const auto& [stored, name] : {std::make_pair(Stored::MirroredX, "mirrored.png"), std::make_pair(Stored::Permuted, "permuted.png")}) {
    auto other = volume(VTK_FLOAT, 300.0, stored);
    paintBox(other, {15 * 0.8 - 0.4, 10 * 0.8 - 0.4, 10 * 1.5 - 0.75}, {24 * 0.8 + 0.4, 19 * 0.8 + 0.4, 13 * 1.5 + 0.75}, 2000.0);
    renderSliceComparison(other, nullptr, dir / name, 5.0, o);
    const Picture picture = readPicture(dir / name);
    ASSERT_EQ(picture.pixels.size(), p.pixels.size()) << name;
    EXPECT_EQ(differingPixels(picture, p), 0u) << name << " differs from the LPS CT's picture";
  }
}

// A title wider than its panel (a long row name over a 40-voxel volume) is drawn whole: the ink in the title row
// is as wide as FreeType's own rendering of the whole title. Arial's digits share one advance width, so the
// slice's z (unknown to the test) is stood in for by "00.0"; the tight ink box then differs by at most a pixel.
// Before the margin grew with the title, the title was cut at the panel and its side margins (about 200 px here).
TEST(LabelledSliceComparison, ATitleWiderThanItsPanelIsDrawnWhole) {
  const auto dir = scratchFolder();
  auto post = volume(VTK_FLOAT, 300.0);
  for (int j = 10; j < 20; ++j)
    for (int i = 15; i < 25; ++i) post->SetScalarComponentFromDouble(i, j, 12, 0, 2000.0);
  SliceComparisonOptions o;
  o.postRowName = "post (phantom, simulated)";
  renderSliceComparison(post, nullptr, dir / "slices.png", 5.0, o);
  const Picture p = readPicture(dir / "slices.png");
  const auto panels = findPanels(p, Rgb{58, 58, 58});
  ASSERT_EQ(panels.size(), 1u) << "one slice through a one-plane slab";
  const int row = o.fontPx + 6; // the title row sits two text rows above the panel
  const Glyph title = inkIn(p, {0, panels[0].y0 - 2 * row, p.width, panels[0].y0 - row});
  const Glyph expected = renderText("post (phantom, simulated), axial z = 00.0 mm", o.fontPx, false);
  std::cout << "title ink " << title.width << " px wide, FreeType's whole title " << expected.width << " px, panel "
            << panels[0].width() << " px\n";
  ASSERT_GT(expected.width, panels[0].width() + 40) << "the case must have a title wider than its panel";
  EXPECT_NEAR(title.width, expected.width, 2);
}
