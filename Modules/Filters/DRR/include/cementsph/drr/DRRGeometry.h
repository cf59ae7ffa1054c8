// The projection geometry of a DRR, with plastimatch's (`plastimatch drr`) conventions so that a user
// can compare images pixel for pixel:
//  - the source sits at isocentre + sad * (cos a, -sin a, 0), a being the gantry angle about z
//    (a = 0: source on +x; a = 90 deg: source on -y), as plastimatch 1.9 places it. (Debian 12's
//    plastimatch 1.9.4 reads its --gantry-angle in radians although its help says degrees; ours is
//    in degrees, so compare with `plastimatch drr -y <a * pi / 180>`.)
//  - the detector is perpendicular to the beam axis, sid from the source, centred on that axis;
//  - its horizontal axis u = beam x z, its vertical axis (up) = u x beam; for a = 0 the source is on
//    +x, u is +y and up is +z.
// Output pixel (i, j): i counts along u (columns), j counts *up* (rows, bottom row j = 0), which is
// VTK's image convention; plastimatch's PFM files store the top row first (row r = rows - 1 - j).
// Parallel beam: every ray runs along the beam axis; the detector's pixel size is then the size at
// the isocentre (no magnification).
#pragma once

#include "cementsph/drr/DetectorFrame.h"

#include <array>
#include <string>

namespace cementsph::drr {

struct DRRGeometry {
  double sadMm = 1000.0;                 // source to isocentre
  double sidMm = 1500.0;                 // source to detector
  int rows = 512;                        // detector pixels, vertical
  int cols = 512;                        // detector pixels, horizontal
  double heightMm = 400.0;               // detector physical size, vertical
  double widthMm = 400.0;                // detector physical size, horizontal
  Vec3 isocenterMm{0.0, 0.0, 0.0};       // patient (volume physical) coordinates
  double gantryAngleDeg = 0.0;           // about z
  bool parallel = false;

  // Empty when usable, else one sentence saying what is wrong (shared by the filter and the CLI so
  // both refuse the same inputs with the same words).
  std::string validate() const;

  double pixelWidthMm() const { return widthMm / cols; }
  double pixelHeightMm() const { return heightMm / rows; }

  // Source position; for a parallel beam the point the rays would converge to at infinity is
  // meaningless, so this is the isocentre moved sad back along the beam (where rays start).
  Vec3 source() const;
  Vec3 beamDirection() const;  // unit, source -> detector
  Vec3 horizontalAxis() const; // unit u: i increases along it
  Vec3 verticalAxis() const;   // unit up: j increases along it

  // Position of the centre of output pixel (i, j) on the detector (parallel beam: in the plane of
  // the isocentre).
  Vec3 pixelCentre(double i, double j) const;

  DetectorFrame frame() const;
  Ray ray(int i, int j) const { return frame().ray(i, j); } // see DetectorFrame::ray

  // Continuous output pixel coordinates (i, j) where a physical point projects.
  std::array<double, 2> project(const Vec3& pointMm) const;

  // Magnification of the isocentre plane onto the detector: sid / sad (1 for a parallel beam). An area at
  // the detector times (1 / magnification)^2 is the area in the plane through the isocentre.
  double isocentreMagnification() const { return parallel ? 1.0 : sidMm / sadMm; }

  // Sets widthMm and heightMm (rows and cols unchanged, square pixels) so that the projection of the
  // axis-aligned box boundsMm = {xmin, xmax, ymin, ymax, zmin, zmax} fits on the detector, centred, with
  // `margin` (>= 1) times the room it needs. Throws std::invalid_argument if a corner of the box is not in
  // front of the source, the box is empty or margin < 1.
  void fitDetectorTo(const std::array<double, 6>& boundsMm, double margin = 1.1);
};

} // namespace cementsph::drr
