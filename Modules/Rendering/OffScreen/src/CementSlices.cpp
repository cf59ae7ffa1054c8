#include "cementsph/rendering/CementSlices.h"

#include "PixelCanvas.h"
#include "cementsph/anatomy/LeakSites.h"
#include "cementsph/rendering/OffScreenWindow.h"

#include <vtkMatrix3x3.h>
#include <vtkSmartPointer.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

namespace cementsph::rendering {

namespace {

using detail::PixelCanvas;
using detail::Rgb;

const Rgb kBlack{0, 0, 0}, kWhite{255, 255, 255};
const Rgb kTip{255, 255, 0}, kTrajectory{0, 220, 255}, kVertebra{0, 200, 80};
const Rgb kLeakUnknown{230, 20, 20};

// Leak kinds in legend order, their colours and words (CementSlices.h lists the colours).
struct LeakStyle {
  const char* kind;
  Rgb colour;
  const char* words;
};
const LeakStyle kLeakStyles[] = {
    {"disc", {220, 0, 220}, "leak into the disc"},
    {"canal", {255, 140, 0}, "leak into the canal"},
    {"venous", {140, 70, 255}, "venous leak"},
    {"other_bone", {150, 90, 30}, "leak into other bone"},
    {"cortex_breach", {230, 20, 20}, "cortex breach"},
    {"soft-tissue", {230, 20, 20}, "leak (below the bone band)"},
};

bool styled(const std::string& kind) {
  for (const LeakStyle& s : kLeakStyles)
    if (kind == s.kind) return true;
  return false;
}

Rgb leakColour(const std::string& kind) {
  for (const LeakStyle& s : kLeakStyles)
    if (kind == s.kind) return s.colour;
  return kLeakUnknown;
}

void requireSameGrid(vtkImageData* image, const int dims[3], const char* what) {
  if (!image) return;
  int d[3];
  image->GetDimensions(d);
  if (d[0] != dims[0] || d[1] != dims[1] || d[2] != dims[2])
    throw std::invalid_argument(std::string("cement slices: the ") + what + " is not on the CT's grid");
}

double voxel(vtkImageData* image, const int ijk[3]) { return image->GetScalarComponentAsDouble(ijk[0], ijk[1], ijk[2], 0); }

// The legend: one entry per colour the picture uses, left to right, wrapped to the picture's width.
class Legend {
public:
  enum class Mark { Swatch, Ring, Line, Outline };
  void add(Mark mark, Rgb colour, std::string words) { entries_.push_back({mark, colour, std::move(words), 0, 0}); }
  bool empty() const { return entries_.empty(); }
  // Places the entries from (x0, y0) within [x0, x1); returns the rows' height (px).
  int layout(int x0, int x1, int y0, int fontPx) {
    fontPx_ = fontPx;
    const int row = fontPx + 8;
    int x = x0, y = y0;
    for (Entry& e : entries_) {
      const int w = fontPx + 6 + PixelCanvas::textSize(e.words, fontPx)[0] + 16;
      if (x > x0 && x + w > x1) x = x0, y += row;
      e.x = x, e.y = y;
      x += w;
    }
    return entries_.empty() ? 0 : y + row - y0;
  }
  void draw(PixelCanvas& canvas) const {
    const int swatch = fontPx_;
    for (const Entry& e : entries_) {
      const int x = e.x, y = e.y + 2;
      switch (e.mark) {
      case Mark::Swatch: canvas.fillRect(x, y, swatch, swatch, e.colour); break;
      case Mark::Ring: canvas.ring(x + 0.5 * swatch, y + 0.5 * swatch, 0.5 * swatch - 2, 2.0, e.colour); break;
      case Mark::Line:
        canvas.line(x, y + 0.5 * swatch, x + swatch, y + 0.5 * swatch, 2.0, e.colour, {0, canvas.width(), 0, canvas.height()});
        break;
      case Mark::Outline:
        canvas.fillRect(x, y, swatch, swatch, e.colour);
        canvas.fillRect(x + 2, y + 2, swatch - 4, swatch - 4, kWhite);
        break;
      }
      canvas.text(e.words, x + swatch + 6, y, fontPx_, kBlack);
    }
  }

private:
  struct Entry {
    Mark mark;
    Rgb colour;
    std::string words;
    int x, y;
  };
  std::vector<Entry> entries_;
  int fontPx_ = 14;
};

// Outlines a region of a panel: its pixels within 2 px of a pixel outside it (the panel's edge is no boundary).
// inside: w x h flags, row by row; (x0, y0): the panel's top-left pixel on the canvas.
void drawOutline(PixelCanvas& canvas, const std::vector<char>& inside, int w, int h, int x0, int y0, Rgb colour) {
  auto in = [&](int x, int y) { return inside[std::size_t(y) * std::size_t(w) + std::size_t(x)] != 0; };
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      if (!in(x, y)) continue;
      bool edge = false;
      for (int s = 1; s <= 2 && !edge; ++s)
        for (const auto& d : {std::array<int, 2>{s, 0}, {-s, 0}, {0, s}, {0, -s}}) {
          const int xx = x + d[0], yy = y + d[1];
          if (xx >= 0 && yy >= 0 && xx < w && yy < h && !in(xx, yy)) edge = true;
        }
      if (edge) canvas.set(x0 + x, y0 + y, colour);
    }
}

} // namespace

CementSlicesOptions InjectionMarks::options(CementSlicesOptions base) const {
  base.tipMm = tipMm;
  const double norm = std::sqrt(direction[0] * direction[0] + direction[1] * direction[1] + direction[2] * direction[2]);
  base.directionUnit = std::array<double, 3>{direction[0] / norm, direction[1] / norm, direction[2] / norm};
  for (const Leak& leak : leaks) base.leakSites.push_back(leak.site);
  base.vertebraMask = vertebraMask;
  base.vertebraLabel = vertebraLabel;
  return base;
}

std::array<double, 3> InjectionMarks::centreMm() const {
  std::array<double, 3> at = tipMm;
  double largest = 0;
  for (const Leak& leak : leaks)
    if (leak.volumeMl > largest) {
      largest = leak.volumeMl;
      at = leak.site.positionMm;
    }
  return at;
}

void writeCementSlices(vtkImageData* ct, vtkImageData* labels, const std::array<double, 3>& centreMm,
                       const std::filesystem::path& png, const CementSlicesOptions& o) {
  if (!ct || !labels) throw std::invalid_argument("cement slices: no image");
  int dims[3], ldims[3];
  ct->GetDimensions(dims);
  labels->GetDimensions(ldims);
  if (dims[0] != ldims[0] || dims[1] != ldims[1] || dims[2] != ldims[2])
    throw std::invalid_argument("cement slices: the CT and the labels have different grids");
  requireSameGrid(o.tissueClasses, dims, "tissue class map");
  requireSameGrid(o.vertebraMask, dims, "vertebra mask");
  if (!(o.scaleBarMm >= 0.0) || !std::isfinite(o.scaleBarMm))
    throw std::invalid_argument("cement slices: the scale bar's length must be a finite number of mm >= 0");
  double spacing[3], direction[9];
  ct->GetSpacing(spacing);
  std::copy_n(ct->GetDirectionMatrix()->GetData(), 9, direction);
  // Through the direction matrix, so a mirrored or permuted CT is sliced where the point really is.
  double centreIndex[3];
  ct->TransformPhysicalPointToContinuousIndex(centreMm.data(), centreIndex);
  int centre[3];
  for (int a = 0; a < 3; ++a) {
    centre[a] = int(std::lround(centreIndex[a]));
    if (!std::isfinite(centreIndex[a]) || centre[a] < 0 || centre[a] >= dims[a])
      throw std::invalid_argument("cement slices: the centre is outside the CT");
  }

  // The cannula in continuous voxel indices: the tip and a point far behind it on the shaft (the shaft's
  // projection is a straight line, so its two ends are enough).
  std::optional<std::array<double, 3>> tipIndex, shaftEndIndex;
  if (o.tipMm) {
    std::array<double, 3> t{};
    ct->TransformPhysicalPointToContinuousIndex(o.tipMm->data(), t.data());
    if (!std::isfinite(t[0]) || !std::isfinite(t[1]) || !std::isfinite(t[2]))
      throw std::invalid_argument("cement slices: the cannula tip is not a finite point");
    tipIndex = t;
    if (o.directionUnit) {
      const auto& d = *o.directionUnit;
      const double norm = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
      if (!(norm > 0.0) || !std::isfinite(norm))
        throw std::invalid_argument("cement slices: the cannula direction is zero or not finite");
      double diagonal = 0.0;
      for (int a = 0; a < 3; ++a) diagonal += std::pow(dims[a] * spacing[a], 2);
      const double behind = 2.0 * std::sqrt(diagonal) + 1.0; // beyond every panel's edge
      std::array<double, 3> end{}, p{};
      for (int a = 0; a < 3; ++a) p[std::size_t(a)] = (*o.tipMm)[std::size_t(a)] - behind * d[std::size_t(a)] / norm;
      ct->TransformPhysicalPointToContinuousIndex(p.data(), end.data());
      shaftEndIndex = end;
    }
  }

  // Which label is the vertebra: the given one, the one under the tip, else any non-zero voxel.
  int vertebraLabel = o.vertebraLabel;
  if (o.vertebraMask && vertebraLabel < 0 && tipIndex) {
    int t[3];
    bool inside = true;
    for (int a = 0; a < 3; ++a) {
      t[a] = int(std::lround((*tipIndex)[std::size_t(a)]));
      inside = inside && t[a] >= 0 && t[a] < dims[a];
    }
    if (inside) vertebraLabel = int(std::lround(voxel(o.vertebraMask, t)));
    if (vertebraLabel == 0) vertebraLabel = -1;
  }
  auto inVertebra = [&](const int ijk[3]) {
    const double value = voxel(o.vertebraMask, ijk);
    return vertebraLabel >= 0 ? std::lround(value) == vertebraLabel : value != 0.0;
  };
  // The kind of a leaked voxel: its tissue class's, the nearest site's, or "" (not known).
  auto leakKindAt = [&](const int ijk[3]) -> std::string {
    if (o.tissueClasses) {
      const long code = std::lround(voxel(o.tissueClasses, ijk));
      if (code < 0 || code > long(anatomy::TissueClass::Air)) return "";
      return anatomy::leakKind(anatomy::TissueClass(code));
    }
    if (o.leakSites.empty()) return "";
    double p[3];
    ct->TransformIndexToPhysicalPoint(ijk[0], ijk[1], ijk[2], p);
    double best = std::numeric_limits<double>::infinity();
    std::string kind;
    for (const LeakSiteMark& s : o.leakSites) {
      const double d2 = std::pow(p[0] - s.positionMm[0], 2) + std::pow(p[1] - s.positionMm[1], 2) +
                        std::pow(p[2] - s.positionMm[2], 2);
      if (d2 < best) best = d2, kind = s.kind;
    }
    return kind;
  };

  const std::array<detail::PanelAxes, 3> panels = detail::conventionalViews(direction);
  // Panel sizes: square pixels in mm, each voxel an integer number of pixels wide.
  int scale[3], widths[3], heights[3];
  for (int p = 0; p < 3; ++p) {
    const detail::PanelAxes& q = panels[std::size_t(p)];
    const double mmPerPixel = std::max(dims[q.u] * spacing[q.u], 1e-9) / o.pixelsPerPanel;
    scale[p] = std::max(1, int(std::lround(spacing[q.u] / mmPerPixel)));
    widths[p] = dims[q.u] * scale[p];
    heights[p] = std::max(1, int(std::lround(dims[q.v] * spacing[q.v] / spacing[q.u]))) * scale[p];
  }
  // The voxel a panel pixel shows.
  auto voxelAt = [&](int p, int x, int y, int ijk[3]) {
    const detail::PanelAxes& q = panels[std::size_t(p)];
    ijk[q.fixed] = centre[q.fixed];
    const int right = std::min(dims[q.u] - 1, x / scale[p]);
    ijk[q.u] = q.uSign > 0 ? right : dims[q.u] - 1 - right;
    const int down = std::min(dims[q.v] - 1, int(double(y) * dims[q.v] / heights[p]));
    ijk[q.v] = q.vSign > 0 ? down : dims[q.v] - 1 - down;
  };

  // What the legend needs: the labels and leak kinds on the three slices.
  std::set<int> labelsShown;
  std::set<std::string> kindsShown;
  bool vertebraShown = false;
  for (const detail::PanelAxes& q : panels) {
    int ijk[3];
    ijk[q.fixed] = centre[q.fixed];
    for (ijk[q.v] = 0; ijk[q.v] < dims[q.v]; ++ijk[q.v])
      for (ijk[q.u] = 0; ijk[q.u] < dims[q.u]; ++ijk[q.u]) {
        const int label = int(voxel(labels, ijk));
        labelsShown.insert(label);
        if (label == 2) kindsShown.insert(leakKindAt(ijk));
        if (o.vertebraMask && !vertebraShown) vertebraShown = inVertebra(ijk);
      }
  }
  Legend legend;
  auto halfOverGrey = [](Rgb c) { // how a half-transparent overlay looks on the bone window's mid grey
    return Rgb{static_cast<unsigned char>(std::lround(0.5 * 127.5 + 0.5 * c[0])),
               static_cast<unsigned char>(std::lround(0.5 * 127.5 + 0.5 * c[1])),
               static_cast<unsigned char>(std::lround(0.5 * 127.5 + 0.5 * c[2]))};
  };
  if (labelsShown.count(1)) legend.add(Legend::Mark::Swatch, halfOverGrey({40, 110, 255}), "cement in bone");
  if (labelsShown.count(3)) legend.add(Legend::Mark::Swatch, halfOverGrey({255, 220, 0}), "target without cement");
  for (const LeakStyle& s : kLeakStyles)
    if (kindsShown.count(s.kind)) legend.add(Legend::Mark::Swatch, s.colour, s.words);
  for (const std::string& kind : kindsShown)
    if (!styled(kind)) legend.add(Legend::Mark::Swatch, kLeakUnknown, kind.empty() ? "leaked cement" : "leak: " + kind);
  if (tipIndex) legend.add(Legend::Mark::Ring, kTip, "cannula tip (projected)");
  if (shaftEndIndex) legend.add(Legend::Mark::Line, kTrajectory, "trajectory (projected)");
  if (vertebraShown) legend.add(Legend::Mark::Outline, kVertebra, "vertebra");

  // Layout: the panels side by side, each in its margins for the labels; the legend below.
  const detail::PanelMargins margins = o.annotate ? detail::annotationMargins(o.fontPx) : detail::PanelMargins{};
  const int gap = 8, border = o.annotate ? 6 : 0;
  int panelX[3], total = border, tallest = 0;
  for (int p = 0; p < 3; ++p) {
    panelX[p] = total + margins.left;
    total = panelX[p] + widths[p] + margins.right + (p < 2 ? gap : border);
    tallest = std::max(tallest, heights[p]);
  }
  const int panelY = border + margins.top;
  const int legendTop = panelY + tallest + margins.bottom + 4;
  const int legendHeight = o.annotate && !legend.empty() ? legend.layout(border, total - border, legendTop, o.fontPx) + 4 : 0;
  PixelCanvas canvas(total, panelY + tallest + margins.bottom + legendHeight + border, kWhite);

  for (int p = 0; p < 3; ++p) {
    const detail::PanelAxes& q = panels[std::size_t(p)];
    const int w = widths[p], h = heights[p];
    std::vector<char> vertebra(o.vertebraMask ? std::size_t(w) * std::size_t(h) : 0);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        int ijk[3];
        voxelAt(p, x, y, ijk);
        const double hu = voxel(ct, ijk);
        const int label = int(voxel(labels, ijk));
        const double g = std::clamp((hu - (o.levelHu - 0.5 * o.windowHu)) / o.windowHu, 0.0, 1.0) * 255.0;
        double rgb[3] = {g, g, g};
        if (label == 1) { // cement in bone: blue, half over the CT
          rgb[0] = 0.5 * g + 0.5 * 40;
          rgb[1] = 0.5 * g + 0.5 * 110;
          rgb[2] = 0.5 * g + 0.5 * 255;
        } else if (label == 3) { // a target without cement: yellow, half over the CT
          rgb[0] = 0.5 * g + 0.5 * 255;
          rgb[1] = 0.5 * g + 0.5 * 220;
          rgb[2] = 0.5 * g + 0.5 * 0;
        } else if (label == 2) { // leaked: opaque, in its kind's colour
          const Rgb c = leakColour(leakKindAt(ijk));
          for (int k = 0; k < 3; ++k) rgb[k] = c[std::size_t(k)];
        }
        canvas.set(panelX[p] + x, panelY + y,
                   {static_cast<unsigned char>(std::lround(rgb[0])), static_cast<unsigned char>(std::lround(rgb[1])),
                    static_cast<unsigned char>(std::lround(rgb[2]))});
        if (o.vertebraMask) vertebra[std::size_t(y) * std::size_t(w) + std::size_t(x)] = inVertebra(ijk);
      }
    if (o.vertebraMask) drawOutline(canvas, vertebra, w, h, panelX[p], panelY, kVertebra);
    // The cannula, projected onto the panel's plane.
    auto toPixel = [&](const std::array<double, 3>& c) {
      const double cu = c[std::size_t(q.u)], cv = c[std::size_t(q.v)];
      const double right = q.uSign > 0 ? cu : dims[q.u] - 1 - cu, down = q.vSign > 0 ? cv : dims[q.v] - 1 - cv;
      return std::array<double, 2>{panelX[p] + (right + 0.5) * scale[p], panelY + (down + 0.5) * h / dims[q.v]};
    };
    const std::array<int, 4> clip{panelX[p], panelX[p] + w, panelY, panelY + h};
    if (tipIndex && shaftEndIndex) {
      const auto a = toPixel(*tipIndex), b = toPixel(*shaftEndIndex);
      if (std::hypot(b[0] - a[0], b[1] - a[1]) > 1.0) canvas.line(a[0], a[1], b[0], b[1], 2.0, kTrajectory, clip);
    }
    if (tipIndex) {
      const auto a = toPixel(*tipIndex);
      if (a[0] >= clip[0] && a[0] <= clip[1] && a[1] >= clip[2] && a[1] <= clip[3]) canvas.ring(a[0], a[1], 6.0, 2.0, kTip);
    }
    if (o.annotate) {
      detail::PanelAnnotation a;
      double centrePoint[3];
      ct->TransformIndexToPhysicalPoint(centre[0], centre[1], centre[2], centrePoint);
      const int along = detail::patientAxis(direction, q.fixed);
      std::ostringstream title;
      title << detail::planeName(direction, q.fixed) << "  " << "xyz"[along] << " = " << std::fixed
            << std::setprecision(1) << centrePoint[along] << " mm";
      a.title = title.str();
      a.left = detail::patientLetter(direction, q.u, -q.uSign);
      a.right = detail::patientLetter(direction, q.u, q.uSign);
      a.top = detail::patientLetter(direction, q.v, -q.vSign);
      a.bottom = detail::patientLetter(direction, q.v, q.vSign);
      a.mmPerPixel = spacing[q.u] / scale[p];
      a.scaleBarMm = o.scaleBarMm;
      detail::annotatePanel(canvas, panelX[p], panelY, w, h, a, o.fontPx);
    }
  }
  if (o.annotate) legend.draw(canvas);
  writeImagePng(canvas.toImage(), png);
}

} // namespace cementsph::rendering
