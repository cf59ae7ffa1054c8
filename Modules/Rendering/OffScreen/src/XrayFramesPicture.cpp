// Fig. 12 style X-ray frames: composed pixel by pixel (as the Fig. 11 slice picture), labels rendered by
// vtkFreeTypeTools into RGBA images and blended in, so no GL context or display is involved.
#include "cementsph/rendering/XrayFramesPicture.h"

#include "cementsph/rendering/OffScreenWindow.h"

#include <vtkDataArray.h>
#include <vtkFreeTypeTools.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkSmartPointer.h>
#include <vtkStdString.h>
#include <vtkTextProperty.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace cementsph::rendering {

namespace {

// A panel with no frame at its instant (a DRR pixel is grey and an outline is saturated, so this tint
// is never either).
constexpr std::array<unsigned char, 3> kNoFrameRgb{235, 235, 242};

[[noreturn]] void reject(const std::string& why) { throw std::invalid_argument("renderXrayFrames: " + why); }

// An RGB canvas addressed top-down (VTK's image row 0 is the PNG's bottom row).
class Canvas {
public:
  Canvas(int width, int height) : width_(width), height_(height) {
    image_->SetDimensions(width, height, 1);
    image_->AllocateScalars(VTK_UNSIGNED_CHAR, 3);
    pixels_ = static_cast<unsigned char*>(image_->GetScalarPointer());
    std::fill(pixels_, pixels_ + static_cast<std::size_t>(width) * height * 3, 255);
  }
  void put(int x, int yTopDown, const std::array<unsigned char, 3>& rgb) {
    if (x < 0 || x >= width_ || yTopDown < 0 || yTopDown >= height_) return;
    unsigned char* p = pixels_ + (static_cast<std::size_t>(height_ - 1 - yTopDown) * width_ + x) * 3;
    p[0] = rgb[0];
    p[1] = rgb[1];
    p[2] = rgb[2];
  }
  // Black text whose top-left corner is at (x, y); returns its width and height in pixels.
  static std::array<int, 2> textSize(const std::string& text, int fontPx) {
    int box[4] = {0, -1, 0, -1};
    vtkFreeTypeTools::GetInstance()->GetBoundingBox(property(fontPx), vtkStdString(text), 72, box);
    return {box[1] - box[0] + 1, box[3] - box[2] + 1};
  }
  void text(const std::string& text, int fontPx, int x, int yTop) {
    if (text.empty() || fontPx <= 0) return;
    vtkNew<vtkImageData> glyphs;
    int size[2] = {0, 0};
    if (!vtkFreeTypeTools::GetInstance()->RenderString(property(fontPx), vtkStdString(text), 72, glyphs, size))
      throw std::runtime_error("renderXrayFrames: could not render the label '" + text + "'");
    int dims[3];
    glyphs->GetDimensions(dims);
    const auto* rgba = static_cast<const unsigned char*>(glyphs->GetScalarPointer());
    for (int j = 0; j < std::min(size[1], dims[1]); ++j)
      for (int i = 0; i < std::min(size[0], dims[0]); ++i) {
        // Glyph row 0 is the bottom of the text.
        const unsigned char alpha = rgba[(static_cast<std::size_t>(j) * dims[0] + i) * 4 + 3];
        const int xx = x + i, yy = yTop + (size[1] - 1 - j);
        if (alpha == 0 || xx < 0 || xx >= width_ || yy < 0 || yy >= height_) continue;
        unsigned char* p = pixels_ + (static_cast<std::size_t>(height_ - 1 - yy) * width_ + xx) * 3;
        for (int c = 0; c < 3; ++c) p[c] = static_cast<unsigned char>(std::lround(p[c] * (1.0 - alpha / 255.0)));
      }
  }
  vtkImageData* image() { return image_; }

private:
  static vtkTextProperty* property(int fontPx) {
    static vtkNew<vtkTextProperty> p;
    p->SetFontFamilyToArial();
    p->SetFontSize(fontPx);
    p->SetColor(0.0, 0.0, 0.0);
    return p;
  }
  int width_, height_;
  vtkNew<vtkImageData> image_;
  unsigned char* pixels_ = nullptr;
};

bool sameGrid(vtkImageData* a, vtkImageData* b) {
  int da[3], db[3];
  a->GetDimensions(da);
  b->GetDimensions(db);
  for (int i = 0; i < 3; ++i)
    if (da[i] != db[i] || std::abs(a->GetSpacing()[i] - b->GetSpacing()[i]) > 1e-9) return false;
  return true;
}

} // namespace

void renderXrayFrames(const std::vector<XrayFramesRow>& rows, const std::vector<std::string>& columnLabels,
                      const std::filesystem::path& png, const XrayFramesOptions& options) {
  if (rows.empty()) reject("no rows");
  const std::size_t columns = rows[0].panels.size();
  if (columns == 0) reject("no columns");
  if (!columnLabels.empty() && columnLabels.size() != columns)
    reject(std::to_string(columnLabels.size()) + " column labels for " + std::to_string(columns) + " columns");
  if (options.panelWidthPx < 8 || options.panelWidthPx > 2048) reject("panel width must be 8..2048 px");
  vtkImageData* first = nullptr;
  for (const XrayFramesRow& row : rows) {
    if (row.panels.size() != columns) reject("rows have different numbers of panels");
    for (const XrayPanel& p : row.panels) {
      if (p.drr == nullptr) continue;
      if (p.drr->GetPointData()->GetScalars() == nullptr) reject("a DRR has no pixel values");
      if (first == nullptr) first = p.drr;
      if (!sameGrid(first, p.drr)) reject("the DRRs are not all on one detector grid");
      if (p.mask != nullptr && (!sameGrid(p.drr, p.mask) || p.mask->GetPointData()->GetScalars() == nullptr))
        reject("a cement mask is not on its DRR's grid");
    }
  }
  if (first == nullptr) reject("no frame to draw");

  int dims[3];
  first->GetDimensions(dims);
  const int cols = dims[0], detRows = dims[1];
  const double aspect = (detRows * first->GetSpacing()[1]) / (cols * first->GetSpacing()[0]);
  const int panelW = options.panelWidthPx;
  const int panelH = std::max(1, static_cast<int>(std::lround(panelW * aspect)));
  const int gap = std::max(0, options.gapPx);
  const int font = std::max(0, options.fontSizePx);
  int labelW = 0;
  for (const XrayFramesRow& row : rows)
    if (font > 0 && !row.label.empty()) labelW = std::max(labelW, Canvas::textSize(row.label, font)[0] + gap);
  const int labelH = font > 0 && !columnLabels.empty() ? font + gap : 0;
  const int width = gap + labelW + static_cast<int>(columns) * (panelW + gap);
  const int height = gap + labelH + static_cast<int>(rows.size()) * (panelH + gap);
  if (width > 16384 || height > 16384) reject("the picture would be larger than 16384 px");

  Canvas canvas(width, height);
  // Source pixel (DRR index, j = 0 at the bottom) of panel pixel (x, y top-down).
  auto source = [&](int x, int y) {
    const int i = std::min(cols - 1, static_cast<int>((x + 0.5) * cols / panelW));
    const int jDown = std::min(detRows - 1, static_cast<int>((y + 0.5) * detRows / panelH));
    return static_cast<vtkIdType>(detRows - 1 - jDown) * cols + i;
  };
  for (std::size_t r = 0; r < rows.size(); ++r) {
    const XrayFramesRow& row = rows[r];
    double window = row.windowMax;
    if (!(window > 0.0)) {
      for (const XrayPanel& p : row.panels) {
        if (p.drr == nullptr) continue;
        double range[2];
        p.drr->GetPointData()->GetScalars()->GetRange(range, 0);
        window = std::max(window, range[1]);
      }
    }
    if (!(window > 0.0) || !std::isfinite(window)) window = 1.0; // all air: a white panel
    const int top = gap + labelH + static_cast<int>(r) * (panelH + gap);
    if (labelW > 0) canvas.text(row.label, font, gap, top + (panelH - font) / 2);
    for (std::size_t c = 0; c < columns; ++c) {
      const int left = gap + labelW + static_cast<int>(c) * (panelW + gap);
      if (r == 0 && labelH > 0) {
        const int w = Canvas::textSize(columnLabels[c], font)[0];
        canvas.text(columnLabels[c], font, left + (panelW - w) / 2, gap);
      }
      const XrayPanel& p = row.panels[c];
      if (p.drr == nullptr) { // no frame at this instant: a light blue-grey panel (no DRR pixel is tinted)
        for (int y = 0; y < panelH; ++y)
          for (int x = 0; x < panelW; ++x) canvas.put(left + x, top + y, kNoFrameRgb);
        continue;
      }
      vtkDataArray* values = p.drr->GetPointData()->GetScalars();
      vtkDataArray* mask = p.mask ? p.mask->GetPointData()->GetScalars() : nullptr;
      auto cement = [&](int x, int y) {
        return x >= 0 && x < panelW && y >= 0 && y < panelH && mask->GetComponent(source(x, y), 0) != 0.0;
      };
      for (int y = 0; y < panelH; ++y)
        for (int x = 0; x < panelW; ++x) {
          if (mask != nullptr && cement(x, y)) {
            bool edge = false;
            for (int dy = -1; dy <= 1 && !edge; ++dy)
              for (int dx = -1; dx <= 1 && !edge; ++dx) edge = !cement(x + dx, y + dy);
            if (edge) {
              canvas.put(left + x, top + y, row.outlineRgb);
              continue;
            }
          }
          const double v = values->GetComponent(source(x, y), 0);
          const double t = std::isfinite(v) ? std::clamp(v / window, 0.0, 1.0) : 0.0;
          const auto grey = static_cast<unsigned char>(std::lround(255.0 * (1.0 - t)));
          canvas.put(left + x, top + y, {grey, grey, grey});
        }
    }
  }
  writeImagePng(canvas.image(), png); // atomic: temporary sibling, then rename
}

} // namespace cementsph::rendering
