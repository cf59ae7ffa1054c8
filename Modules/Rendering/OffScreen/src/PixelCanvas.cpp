#include "PixelCanvas.h"

#include <vtkFreeTypeTools.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkStdString.h>
#include <vtkTextProperty.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace cementsph::rendering::detail {

namespace {

// 72 dpi makes VTK's font size a size in pixels.
constexpr int kDpi = 72;

vtkSmartPointer<vtkTextProperty> textProperty(int fontPx, bool bold) {
  auto p = vtkSmartPointer<vtkTextProperty>::New();
  p->SetFontFamilyToArial(); // compiled into VTK: no font files or fontconfig needed
  p->SetFontSize(fontPx);
  p->SetBold(bold);
  p->SetColor(0, 0, 0);
  p->SetJustificationToLeft();
  p->SetVerticalJustificationToBottom();
  return p;
}

} // namespace

PixelCanvas::PixelCanvas(int width, int height, Rgb background)
    : width_(width), height_(height), rgb_(std::size_t(std::max(width, 0)) * std::size_t(std::max(height, 0)) * 3) {
  if (width <= 0 || height <= 0) throw std::invalid_argument("picture of " + std::to_string(width) + " x " +
                                                              std::to_string(height) + " px has no pixels");
  for (std::size_t p = 0; p < rgb_.size(); p += 3) std::copy(background.begin(), background.end(), rgb_.begin() + long(p));
}

void PixelCanvas::set(int x, int y, Rgb colour) {
  if (!inside(x, y)) return;
  std::copy(colour.begin(), colour.end(), rgb_.begin() + long((std::size_t(y) * std::size_t(width_) + std::size_t(x)) * 3));
}

void PixelCanvas::blend(int x, int y, Rgb colour, double alpha) {
  if (!inside(x, y) || !(alpha > 0.0)) return;
  alpha = std::min(alpha, 1.0);
  unsigned char* p = rgb_.data() + (std::size_t(y) * std::size_t(width_) + std::size_t(x)) * 3;
  for (int c = 0; c < 3; ++c) p[c] = static_cast<unsigned char>(std::lround((1.0 - alpha) * p[c] + alpha * colour[std::size_t(c)]));
}

void PixelCanvas::fillRect(int x, int y, int w, int h, Rgb colour) {
  for (int yy = std::max(0, y); yy < std::min(height_, y + h); ++yy)
    for (int xx = std::max(0, x); xx < std::min(width_, x + w); ++xx) set(xx, yy, colour);
}

void PixelCanvas::line(double x0, double y0, double x1, double y1, double widthPx, Rgb colour,
                       const std::array<int, 4>& clip) {
  const double half = 0.5 * widthPx, dx = x1 - x0, dy = y1 - y0, length2 = dx * dx + dy * dy;
  const int xa = std::max(clip[0], int(std::floor(std::min(x0, x1) - half)));
  const int xb = std::min(clip[1], int(std::ceil(std::max(x0, x1) + half)) + 1);
  const int ya = std::max(clip[2], int(std::floor(std::min(y0, y1) - half)));
  const int yb = std::min(clip[3], int(std::ceil(std::max(y0, y1) + half)) + 1);
  for (int y = ya; y < yb; ++y)
    for (int x = xa; x < xb; ++x) {
      const double px = x + 0.5, py = y + 0.5;
      const double t = length2 > 0 ? std::clamp(((px - x0) * dx + (py - y0) * dy) / length2, 0.0, 1.0) : 0.0;
      const double ex = px - (x0 + t * dx), ey = py - (y0 + t * dy);
      if (ex * ex + ey * ey <= half * half) set(x, y, colour);
    }
}

void PixelCanvas::ring(double cx, double cy, double radiusPx, double thicknessPx, Rgb colour) {
  const double outer = radiusPx + 0.5 * thicknessPx, inner = std::max(0.0, radiusPx - 0.5 * thicknessPx);
  for (int y = int(std::floor(cy - outer)); y <= int(std::ceil(cy + outer)); ++y)
    for (int x = int(std::floor(cx - outer)); x <= int(std::ceil(cx + outer)); ++x) {
      const double r = std::hypot(x + 0.5 - cx, y + 0.5 - cy);
      if (r >= inner && r <= outer) set(x, y, colour);
    }
}

int PixelCanvas::text(const std::string& s, int x, int y, int fontPx, Rgb colour, bool bold, int maxWidth) {
  if (s.empty()) return 0;
  vtkNew<vtkImageData> glyphs;
  int size[2] = {0, 0};
  if (!vtkFreeTypeTools::GetInstance()->RenderString(textProperty(fontPx, bold), vtkStdString(s), kDpi, glyphs, size))
    throw std::runtime_error("cannot render the text '" + s + "' (FreeType)");
  int extent[6];
  glyphs->GetExtent(extent);
  const int w = maxWidth > 0 ? std::min(size[0], maxWidth) : size[0];
  // The text occupies the image's first size[0] x size[1] pixels, its row 0 at the bottom (VTK's order).
  for (int ty = 0; ty < size[1]; ++ty)
    for (int tx = 0; tx < w; ++tx) {
      const double alpha = glyphs->GetScalarComponentAsDouble(extent[0] + tx, extent[2] + ty, 0, 3) / 255.0;
      blend(x + tx, y + (size[1] - 1 - ty), colour, alpha);
    }
  return w;
}

std::array<int, 2> PixelCanvas::textSize(const std::string& s, int fontPx, bool bold) {
  if (s.empty()) return {0, 0};
  int bbox[4] = {0, 0, 0, 0};
  if (!vtkFreeTypeTools::GetInstance()->GetBoundingBox(textProperty(fontPx, bold), vtkStdString(s), kDpi, bbox))
    throw std::runtime_error("cannot measure the text '" + s + "' (FreeType)");
  return {bbox[1] - bbox[0] + 1, bbox[3] - bbox[2] + 1};
}

vtkSmartPointer<vtkImageData> PixelCanvas::toImage() const {
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->SetDimensions(width_, height_, 1);
  image->AllocateScalars(VTK_UNSIGNED_CHAR, 3);
  auto* out = static_cast<unsigned char*>(image->GetScalarPointer());
  const std::size_t row = std::size_t(width_) * 3;
  for (int y = 0; y < height_; ++y)
    std::copy_n(rgb_.data() + std::size_t(y) * row, row, out + std::size_t(height_ - 1 - y) * row);
  return image;
}

int patientAxis(const double direction[9], int axis) {
  int best = 0;
  for (int r = 1; r < 3; ++r)
    if (std::abs(direction[r * 3 + axis]) > std::abs(direction[best * 3 + axis])) best = r;
  return best;
}

char patientLetter(const double direction[9], int axis, int sign) {
  const int r = patientAxis(direction, axis);
  const bool positive = direction[r * 3 + axis] * sign > 0;
  static const char kPositive[3] = {'L', 'P', 'S'}, kNegative[3] = {'R', 'A', 'I'};
  return positive ? kPositive[r] : kNegative[r];
}

const char* planeName(const double direction[9], int normalAxis) {
  static const char* const kNames[3] = {"sagittal", "coronal", "axial"};
  return kNames[patientAxis(direction, normalAxis)];
}

std::array<PanelAxes, 3> conventionalViews(const double direction[9]) {
  int along[3] = {-1, -1, -1}; // the voxel axis along patient x, y, z
  for (int a = 0; a < 3; ++a) {
    const int r = patientAxis(direction, a);
    if (along[r] >= 0) return {PanelAxes{0, 1, 2, +1, +1}, PanelAxes{0, 2, 1, +1, -1}, PanelAxes{1, 2, 0, +1, -1}};
    along[r] = a;
  }
  auto sign = [&](int r) { return direction[r * 3 + along[r]] > 0 ? +1 : -1; };
  // Right: +x (the patient's left) on the axial and coronal views, +y (posterior) on the sagittal one. Down: +y
  // (posterior) on the axial view, -z (inferior) on the others.
  return {PanelAxes{along[0], along[1], along[2], sign(0), sign(1)},
          PanelAxes{along[0], along[2], along[1], sign(0), -sign(2)},
          PanelAxes{along[1], along[2], along[0], sign(1), -sign(2)}};
}

PanelMargins annotationMargins(int fontPx) {
  const int row = fontPx + 6; // a text row with 3 px above and below
  const int letter = PixelCanvas::textSize("W", fontPx, true)[0] + 8;
  return {letter, letter, 2 * row, 2 * row};
}

int annotatePanel(PixelCanvas& canvas, int x, int y, int w, int h, const PanelAnnotation& a, int fontPx) {
  const Rgb black{0, 0, 0};
  const PanelMargins m = annotationMargins(fontPx);
  const int row = m.top / 2;
  canvas.text(a.title, x - m.left, y - 2 * row + 3, fontPx, black, false, a.titleWidthPx > 0 ? a.titleWidthPx : w + m.left + m.right);
  auto letter = [&](char c, int cx, int cy) { // centred on (cx, cy)
    const std::string s(1, c);
    const auto size = PixelCanvas::textSize(s, fontPx, true);
    canvas.text(s, cx - size[0] / 2, cy - size[1] / 2, fontPx, black, true);
  };
  letter(a.top, x + w / 2, y - row / 2);
  letter(a.bottom, x + w / 2, y + h + row / 2);
  letter(a.left, x - m.left / 2, y + h / 2);
  letter(a.right, x + w + m.right / 2, y + h / 2);
  if (!(a.scaleBarMm > 0.0) || !(a.mmPerPixel > 0.0)) return 0;
  // The bar, then its length in words; halved (10, 5, 2.5 mm ...) until both fit under the panel.
  double mm = a.scaleBarMm;
  auto words = [](double v) {
    std::ostringstream s;
    s << v << " mm";
    return s.str();
  };
  int length = int(std::lround(mm / a.mmPerPixel));
  while (length + 6 + PixelCanvas::textSize(words(mm), fontPx)[0] > w && length > 4) {
    mm *= 0.5;
    length = int(std::lround(mm / a.mmPerPixel));
  }
  const int barY = y + h + row + row / 2 - 2;
  canvas.fillRect(x, barY, length, 4, black);
  canvas.text(words(mm), x + length + 6, y + h + row + 3, fontPx, black);
  return length;
}

} // namespace cementsph::rendering::detail
