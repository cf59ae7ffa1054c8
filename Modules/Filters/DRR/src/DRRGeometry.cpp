#include "cementsph/drr/DRRGeometry.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace cementsph::drr {

namespace {

constexpr double kPi = 3.14159265358979323846;

Vec3 add(const Vec3& a, const Vec3& b, double s) { return {a[0] + s * b[0], a[1] + s * b[1], a[2] + s * b[2]}; }
double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

} // namespace

std::string DRRGeometry::validate() const {
  std::ostringstream why;
  auto finite = [](double v) { return std::isfinite(v); };
  if (rows < 1 || cols < 1)
    why << "the detector needs at least 1x1 pixels (got " << rows << "x" << cols << ")";
  else if (!(heightMm > 0) || !(widthMm > 0) || !finite(heightMm) || !finite(widthMm))
    why << "the detector size must be positive (got " << heightMm << " x " << widthMm << " mm)";
  else if (!finite(gantryAngleDeg) || !finite(isocenterMm[0]) || !finite(isocenterMm[1]) ||
           !finite(isocenterMm[2]))
    why << "the gantry angle and isocentre must be finite numbers";
  else if (!parallel && (!(sadMm > 0) || !finite(sadMm)))
    why << "the source-axis distance must be positive (got " << sadMm << " mm)";
  else if (!parallel && (!(sidMm > sadMm) || !finite(sidMm)))
    // The detector must lie beyond the isocentre, else the object is not between source and detector.
    why << "the source-image distance (" << sidMm << " mm) must exceed the source-axis distance ("
        << sadMm << " mm)";
  return why.str();
}

Vec3 DRRGeometry::beamDirection() const {
  // plastimatch's sense of rotation: the source sits at isocentre + sad * (cos a, -sin a, 0).
  const double a = gantryAngleDeg * kPi / 180.0;
  return {-std::cos(a), std::sin(a), 0.0};
}

Vec3 DRRGeometry::horizontalAxis() const {
  // u = beam x z = (b_y, -b_x, 0); already unit because the beam lies in the xy plane.
  const Vec3 b = beamDirection();
  return {b[1], -b[0], 0.0};
}

Vec3 DRRGeometry::verticalAxis() const {
  // up = u x beam, which is +z for a beam in the xy plane.
  return {0.0, 0.0, 1.0};
}

Vec3 DRRGeometry::source() const { return add(isocenterMm, beamDirection(), -sadMm); }

Vec3 DRRGeometry::pixelCentre(double i, double j) const {
  // Detector centre between pixels (cols-1)/2 and (rows-1)/2, as plastimatch's default image centre.
  const Vec3 centre = parallel ? isocenterMm : add(source(), beamDirection(), sidMm);
  const Vec3 p = add(centre, horizontalAxis(), (i - 0.5 * (cols - 1)) * pixelWidthMm());
  return add(p, verticalAxis(), (j - 0.5 * (rows - 1)) * pixelHeightMm());
}

DetectorFrame DRRGeometry::frame() const {
  DetectorFrame f;
  f.source = source();
  f.beam = beamDirection();
  f.pixel00 = pixelCentre(0.0, 0.0);
  const Vec3 u = horizontalAxis(), up = verticalAxis();
  for (int a = 0; a < 3; ++a) {
    f.stepI[a] = u[a] * pixelWidthMm();
    f.stepJ[a] = up[a] * pixelHeightMm();
  }
  f.parallel = parallel;
  return f;
}

std::array<double, 2> DRRGeometry::project(const Vec3& pointMm) const {
  const Vec3 b = beamDirection();
  const Vec3 u = horizontalAxis();
  const Vec3 up = verticalAxis();
  // Offset from the isocentre in detector axes, scaled by the magnification at the point's depth.
  const Vec3 rel{pointMm[0] - isocenterMm[0], pointMm[1] - isocenterMm[1], pointMm[2] - isocenterMm[2]};
  const double magnification = parallel ? 1.0 : sidMm / (sadMm + dot(rel, b));
  return {0.5 * (cols - 1) + dot(rel, u) * magnification / pixelWidthMm(),
          0.5 * (rows - 1) + dot(rel, up) * magnification / pixelHeightMm()};
}

void DRRGeometry::fitDetectorTo(const std::array<double, 6>& b, double margin) {
  if (!(margin >= 1.0) || !std::isfinite(margin)) throw std::invalid_argument("fitDetectorTo: margin must be >= 1");
  for (int a = 0; a < 3; ++a)
    if (!(b[2 * a + 1] >= b[2 * a]) || !std::isfinite(b[2 * a]) || !std::isfinite(b[2 * a + 1]))
      throw std::invalid_argument("fitDetectorTo: the bounding box is empty or not finite");
  const Vec3 beam = beamDirection(), u = horizontalAxis(), up = verticalAxis();
  // A perspective projection maps the box onto the convex hull of its projected corners, so the
  // corners give the half-extents the detector needs on each side of its centre.
  double halfU = 0.0, halfV = 0.0;
  for (int c = 0; c < 8; ++c) {
    const Vec3 corner{b[(c & 1) ? 1 : 0], b[(c & 2) ? 3 : 2], b[(c & 4) ? 5 : 4]};
    const Vec3 rel{corner[0] - isocenterMm[0], corner[1] - isocenterMm[1], corner[2] - isocenterMm[2]};
    double m = 1.0;
    if (!parallel) {
      const double distance = sadMm + dot(rel, beam); // from the source along the beam
      if (!(distance > 0.0)) throw std::invalid_argument("fitDetectorTo: the box reaches behind the source");
      m = sidMm / distance;
    }
    halfU = std::max(halfU, std::abs(dot(rel, u)) * m);
    halfV = std::max(halfV, std::abs(dot(rel, up)) * m);
  }
  const double pixel = std::max(2.0 * halfU * margin / cols, 2.0 * halfV * margin / rows);
  if (!(pixel > 0.0)) throw std::invalid_argument("fitDetectorTo: the box projects to a point");
  widthMm = pixel * cols;
  heightMm = pixel * rows;
}

} // namespace cementsph::drr
