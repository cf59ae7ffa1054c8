// Fig. 7 style surface pictures. Three viewports in one render window (rather than three PNGs glued
// together) so the panels share a single vtkCamera object: the comparison is only fair if the view is
// identical, and sharing the camera makes that true by construction.
#include "cementsph/rendering/SurfaceComparison.h"

#include "cementsph/rendering/OffScreenWindow.h"

#include <vtkActor.h>
#include <vtkCamera.h>
#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkLookupTable.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkProperty.h>
#include <vtkRenderer.h>
#include <vtkScalarBarActor.h>
#include <vtkSmartPointer.h>
#include <vtkTextActor.h>
#include <vtkTextProperty.h>
#include <vtkUnsignedCharArray.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace cementsph::rendering {

namespace {

void requireSurface(vtkPolyData* surface, const char* which) {
  if (surface == nullptr || surface->GetNumberOfPoints() == 0 || surface->GetNumberOfCells() == 0)
    throw std::invalid_argument(std::string("renderSurfaceComparison: the ") + which + " surface is empty");
}

vtkSmartPointer<vtkRenderer> panel(double x0, double x1) {
  auto renderer = vtkSmartPointer<vtkRenderer>::New();
  renderer->SetViewport(x0, 0.0, x1, 1.0);
  renderer->SetBackground(1.0, 1.0, 1.0);
  return renderer;
}

void addTitle(vtkRenderer* renderer, const std::string& text) {
  auto title = vtkSmartPointer<vtkTextActor>::New();
  title->SetInput(text.c_str());
  title->GetTextProperty()->SetFontSize(20);
  title->GetTextProperty()->SetColor(0.1, 0.1, 0.1);
  title->GetTextProperty()->SetJustificationToCentered();
  title->GetPositionCoordinate()->SetCoordinateSystemToNormalizedViewport();
  title->SetPosition(0.5, 0.93);
  renderer->AddViewProp(title);
}

vtkSmartPointer<vtkActor> plainActor(vtkPolyData* surface, double r, double g, double b) {
  auto mapper = vtkSmartPointer<vtkPolyDataMapper>::New();
  mapper->SetInputData(surface);
  mapper->ScalarVisibilityOff();
  auto actor = vtkSmartPointer<vtkActor>::New();
  actor->SetMapper(mapper);
  actor->GetProperty()->SetColor(r, g, b);
  return actor;
}

// The label (1 in bone, 2 leaked) of the cement voxel nearest to p among the 3 x 3 x 3 around it (index
// distance); 1 where none is labelled.
int labelNear(vtkImageData* labels, const double p[3]) {
  double ijk[3];
  labels->TransformPhysicalPointToContinuousIndex(p, ijk);
  int extent[6];
  labels->GetExtent(extent);
  int best = 1;
  double bestDistance = 1e300;
  for (int dk = -1; dk <= 1; ++dk)
    for (int dj = -1; dj <= 1; ++dj)
      for (int di = -1; di <= 1; ++di) {
        const int i = int(std::lround(ijk[0])) + di, j = int(std::lround(ijk[1])) + dj, k = int(std::lround(ijk[2])) + dk;
        if (i < extent[0] || i > extent[1] || j < extent[2] || j > extent[3] || k < extent[4] || k > extent[5]) continue;
        const int label = int(std::lround(labels->GetScalarComponentAsDouble(i, j, k, 0)));
        if (label != 1 && label != 2) continue;
        const double d = (i - ijk[0]) * (i - ijk[0]) + (j - ijk[1]) * (j - ijk[1]) + (k - ijk[2]) * (k - ijk[2]);
        if (d < bestDistance) {
          bestDistance = d;
          best = label;
        }
      }
  return best;
}

// The simulated surface coloured per vertex by the label map: blue in bone, red leaked.
vtkSmartPointer<vtkActor> labelledActor(vtkPolyData* surface, vtkImageData* labels) {
  auto colours = vtkSmartPointer<vtkUnsignedCharArray>::New();
  colours->SetName("cement_label_colour");
  colours->SetNumberOfComponents(3);
  colours->SetNumberOfTuples(surface->GetNumberOfPoints());
  for (vtkIdType v = 0; v < surface->GetNumberOfPoints(); ++v) {
    double p[3];
    surface->GetPoint(v, p);
    const bool leaked = labelNear(labels, p) == 2;
    const unsigned char rgb[3] = {static_cast<unsigned char>(leaked ? 230 : 140), static_cast<unsigned char>(leaked ? 20 : 179),
                                  static_cast<unsigned char>(leaked ? 20 : 230)};
    colours->SetTypedTuple(v, rgb);
  }
  auto coloured = vtkSmartPointer<vtkPolyData>::New();
  coloured->ShallowCopy(surface); // the caller's surface keeps its arrays
  coloured->GetPointData()->SetScalars(colours);
  auto mapper = vtkSmartPointer<vtkPolyDataMapper>::New();
  mapper->SetInputData(coloured);
  mapper->SetScalarModeToUsePointData();
  mapper->SetColorModeToDirectScalars();
  mapper->ScalarVisibilityOn();
  auto actor = vtkSmartPointer<vtkActor>::New();
  actor->SetMapper(mapper);
  return actor;
}

} // namespace

void renderSurfaceComparison(vtkPolyData* experiment, vtkPolyData* simulation, const std::filesystem::path& png,
                             const SurfaceComparisonOptions& options) {
  requireSurface(experiment, "experimental");
  requireSurface(simulation, "simulated");
  vtkDataArray* distances = simulation->GetPointData()->GetArray(options.distanceArray.c_str());
  if (distances == nullptr || distances->GetNumberOfComponents() != 1)
    throw std::invalid_argument("renderSurfaceComparison: the simulated surface has no one-component point array '" +
                                options.distanceArray + "'");
  double range[2];
  distances->GetRange(range, 0);
  double top = options.maxDistanceMm.value_or(range[1]);
  if (!(top > 0.0) || !std::isfinite(top)) top = 1.0; // identical surfaces: keep a usable scale

  // Shallow copy: colouring selects the active scalars, which must not change the caller's surface.
  auto coloured = vtkSmartPointer<vtkPolyData>::New();
  coloured->ShallowCopy(simulation);

  auto window = makeOffScreenRenderWindow(options.widthPx, options.heightPx);

  auto left = panel(0.0, 1.0 / 3.0);
  auto middle = panel(1.0 / 3.0, 2.0 / 3.0);
  auto right = panel(2.0 / 3.0, 1.0);
  left->AddActor(plainActor(experiment, 0.85, 0.75, 0.45)); // bone-cement beige
  if (options.simulationLabels != nullptr) {
    middle->AddActor(labelledActor(simulation, options.simulationLabels));
    addTitle(middle, "simulation: blue in bone, red leaked");
  } else {
    middle->AddActor(plainActor(simulation, 0.55, 0.70, 0.90));
    addTitle(middle, "simulation");
  }
  addTitle(left, options.postTitle);
  addTitle(right, "simulation: distance to CT surface");

  // Sequential table (white-yellow-red, like the paper's 0 -> large error colouring): distance is >= 0,
  // so a diverging table would waste half its colours.
  auto lut = vtkSmartPointer<vtkLookupTable>::New();
  lut->SetNumberOfTableValues(256);
  lut->SetHueRange(0.17, 0.0);
  lut->SetSaturationRange(0.15, 1.0);
  lut->SetValueRange(1.0, 0.75);
  lut->SetTableRange(0.0, top);
  lut->SetAboveRangeColor(0.45, 0.0, 0.0, 1.0);
  lut->UseAboveRangeColorOn();
  lut->Build();
  auto mapper = vtkSmartPointer<vtkPolyDataMapper>::New();
  mapper->SetInputData(coloured);
  mapper->SetScalarModeToUsePointFieldData();
  mapper->SelectColorArray(options.distanceArray.c_str());
  mapper->SetLookupTable(lut);
  mapper->SetScalarRange(0.0, top);
  mapper->ScalarVisibilityOn();
  mapper->SetColorModeToMapScalars();
  auto colouredActor = vtkSmartPointer<vtkActor>::New();
  colouredActor->SetMapper(mapper);
  right->AddActor(colouredActor);

  auto bar = vtkSmartPointer<vtkScalarBarActor>::New();
  bar->SetLookupTable(lut);
  // Horizontal, under the surface: a vertical bar beside it would overlap the surface in a third-width panel.
  bar->SetTitle("mm"); // the panel title says what is measured
  bar->SetNumberOfLabels(4); // even count: no label under the centred title
  bar->SetLabelFormat("%.1f");
  bar->SetOrientationToHorizontal();
  bar->GetPositionCoordinate()->SetCoordinateSystemToNormalizedViewport();
  bar->SetPosition(0.12, 0.02);
  bar->SetWidth(0.76);
  bar->SetHeight(0.2);
  bar->SetBarRatio(0.3);
  bar->UnconstrainedFontSizeOn();
  bar->GetTitleTextProperty()->SetFontSize(16);
  bar->GetTitleTextProperty()->SetColor(0.1, 0.1, 0.1);
  bar->GetTitleTextProperty()->ItalicOff();
  bar->GetTitleTextProperty()->ShadowOff();
  bar->GetLabelTextProperty()->SetFontSize(14);
  bar->GetLabelTextProperty()->SetColor(0.1, 0.1, 0.1);
  bar->GetLabelTextProperty()->ItalicOff();
  bar->GetLabelTextProperty()->ShadowOff();
  right->AddViewProp(bar);

  // One camera for all three panels, fitted to the union of the two surfaces' bounds.
  double a[6], b[6], both[6];
  experiment->GetBounds(a);
  simulation->GetBounds(b);
  for (int i = 0; i < 3; ++i) {
    both[2 * i] = std::min(a[2 * i], b[2 * i]);
    both[2 * i + 1] = std::max(a[2 * i + 1], b[2 * i + 1]);
  }
  auto camera = vtkSmartPointer<vtkCamera>::New();
  const double centre[3] = {(both[0] + both[1]) / 2, (both[2] + both[3]) / 2, (both[4] + both[5]) / 2};
  camera->SetFocalPoint(centre);
  camera->SetPosition(centre[0] + options.viewDirection[0], centre[1] + options.viewDirection[1],
                      centre[2] + options.viewDirection[2]);
  camera->SetViewUp(options.viewUp);
  for (vtkRenderer* r : {left.Get(), middle.Get(), right.Get()}) {
    r->SetActiveCamera(camera);
    window->AddRenderer(r);
  }
  left->ResetCamera(both); // the shared camera now sees the union's bounding sphere
  camera->Zoom(0.95); // leave room for the titles above and the scalar bar below
  for (vtkRenderer* r : {left.Get(), middle.Get(), right.Get()}) r->ResetCameraClippingRange(both);

  writeWindowPng(window, png);
}

} // namespace cementsph::rendering
