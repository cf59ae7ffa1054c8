// An RGB picture composed on the CPU, rows top-down (as a PNG is read), with the few drawing operations the
// slice pictures need: rectangles, lines, rings and text. Text is rasterised by VTK's FreeType tools into an
// image and blended by its coverage, so no render window or GL context is ever made: the pictures come out the
// same on any machine with the same FreeType, and nothing can come back black.
// Private to the module (not installed); CementSlices and SliceComparison use it.
#pragma once

#include <vtkSmartPointer.h>

#include <array>
#include <string>
#include <vector>

class vtkImageData;

namespace cementsph::rendering::detail {

using Rgb = std::array<unsigned char, 3>;

// Pixel (x, y) covers [x, x + 1) x [y, y + 1); continuous coordinates put its centre at (x + 0.5, y + 0.5).
class PixelCanvas {
public:
  PixelCanvas(int width, int height, Rgb background);
  int width() const { return width_; }
  int height() const { return height_; }
  bool inside(int x, int y) const { return x >= 0 && y >= 0 && x < width_ && y < height_; }
  void set(int x, int y, Rgb colour);                       // outside: ignored
  void blend(int x, int y, Rgb colour, double alpha);       // alpha in [0, 1]
  void fillRect(int x, int y, int w, int h, Rgb colour);
  // A line of the given width (px) between continuous points, clipped to the clip rectangle [cx0, cx1) x [cy0, cy1).
  void line(double x0, double y0, double x1, double y1, double widthPx, Rgb colour, const std::array<int, 4>& clip);
  // The pixels whose centres lie within half a thickness of the circle of radius r about (cx, cy).
  void ring(double cx, double cy, double radiusPx, double thicknessPx, Rgb colour);
  // Text with its box's top-left corner at (x, y); returns its width (px). Clipped to maxWidth px when > 0.
  int text(const std::string& s, int x, int y, int fontPx, Rgb colour, bool bold = false, int maxWidth = 0);
  // The rendered text's width and height (px) without drawing it.
  static std::array<int, 2> textSize(const std::string& s, int fontPx, bool bold = false);
  // Rows flipped to VTK's bottom-up order, ready for vtkPNGWriter.
  vtkSmartPointer<vtkImageData> toImage() const;

private:
  int width_, height_;
  std::vector<unsigned char> rgb_;
};

// Orientation of a voxel axis in the patient frame (LPS): the letter of the patient direction the axis runs
// towards, from its dominant component in the image's direction matrix: +x 'L', -x 'R', +y 'P', -y 'A',
// +z 'S', -z 'I'. direction: the 3 x 3 direction matrix (row major), axis 0..2, sign +1 or -1.
char patientLetter(const double direction[9], int axis, int sign);
// The patient axis (0 x, 1 y, 2 z) a voxel axis runs along (its dominant component).
int patientAxis(const double direction[9], int axis);
// "sagittal", "coronal" or "axial": the plane normal to the given voxel axis.
const char* planeName(const double direction[9], int normalAxis);

// A view of a volume: which voxel axis runs to the right (u) and which downwards (v), and which way; which is fixed.
struct PanelAxes {
  int u, v, fixed;
  int uSign, vSign; // +1: the index grows to the right (u) or downwards (v); -1: the other way
};
// The conventional views whatever order the voxels are stored in: [0] axial with the patient's right on the
// left and anterior up (radiological convention), [1] coronal with the right on the left and superior up, [2]
// sagittal with anterior on the left and superior up. Each patient axis is the voxel axis whose direction is mostly
// along it; where two voxel axes are mostly along the same patient axis (an oblique grid near 45 degrees) the views
// keep the stored order: index x right, y down (axial), z up (coronal, sagittal), and the letters say where they run.
std::array<PanelAxes, 3> conventionalViews(const double direction[9]);

// The labels around one image panel: a title row and the top edge's letter above it, the left and right edges'
// letters beside it, the bottom edge's letter and a scale bar below it. All bold letters are centred on their edge.
struct PanelAnnotation {
  std::string title;                 // e.g. "axial  z = 12.0 mm"
  char left = '?', right = '?', top = '?', bottom = '?';
  double mmPerPixel = 1.0;           // along the panel's horizontal axis
  double scaleBarMm = 10.0;          // halved until bar and label fit the panel's width; 0: no bar
  int titleWidthPx = 0;              // the title's room (px) from the left margin; 0: the panel and its side margins
};
struct PanelMargins {
  int left = 0, right = 0, top = 0, bottom = 0;
};
PanelMargins annotationMargins(int fontPx);
// Draws the labels around the panel whose top-left pixel is (x, y). Returns the scale bar's length (px; 0: none).
int annotatePanel(PixelCanvas& canvas, int x, int y, int w, int h, const PanelAnnotation& a, int fontPx);

} // namespace cementsph::rendering::detail
