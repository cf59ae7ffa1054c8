// The cement surface picture (CementSurface.h): one renderer for the surfaces, one for the title band, in
// one off-screen window.
#include "cementsph/rendering/CementSurface.h"

#include "cementsph/rendering/OffScreenWindow.h"
#include "cementsph/surfacemetrics/Isosurface.h"

#include <vtkActor.h>
#include <vtkCamera.h>
#include <vtkDataArray.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkProperty.h>
#include <vtkRenderer.h>
#include <vtkSmartPointer.h>
#include <vtkTextActor.h>
#include <vtkTextProperty.h>
#include <vtkUnsignedCharArray.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <tuple>

namespace cementsph::rendering {

namespace {

// The 0/1 mask of one label, on the labels' grid (origin, spacing, direction).
vtkSmartPointer<vtkImageData> maskOf(vtkImageData* labels, int label, vtkIdType& count) {
  auto mask = vtkSmartPointer<vtkImageData>::New();
  mask->CopyStructure(labels);
  mask->SetDirectionMatrix(labels->GetDirectionMatrix());
  mask->AllocateScalars(VTK_UNSIGNED_CHAR, 1);
  vtkDataArray* in = labels->GetPointData()->GetScalars();
  auto* out = vtkUnsignedCharArray::SafeDownCast(mask->GetPointData()->GetScalars());
  count = 0;
  for (vtkIdType i = 0; i < in->GetNumberOfTuples(); ++i) {
    const bool on = std::lround(in->GetTuple1(i)) == label;
    out->SetValue(i, on ? 1 : 0);
    count += on ? 1 : 0;
  }
  return mask;
}

void addText(vtkRenderer* renderer, const std::string& text, double x, double y, int size, const double rgb[3]) {
  auto actor = vtkSmartPointer<vtkTextActor>::New();
  actor->SetInput(text.c_str());
  actor->GetTextProperty()->SetFontSize(size);
  actor->GetTextProperty()->SetColor(rgb[0], rgb[1], rgb[2]);
  actor->GetPositionCoordinate()->SetCoordinateSystemToNormalizedViewport();
  actor->SetPosition(x, y);
  renderer->AddViewProp(actor);
}

// Adds `surface` to `scene` in one colour (opacity 1: opaque) and grows `box` (xmin, xmax, ymin, ...) to hold it.
void addSurface(vtkRenderer* scene, vtkPolyData* surface, const double rgb[3], double opacity, double box[6]) {
  double b[6];
  surface->GetBounds(b);
  for (int i = 0; i < 3; ++i) {
    box[2 * i] = std::min(box[2 * i], b[2 * i]);
    box[2 * i + 1] = std::max(box[2 * i + 1], b[2 * i + 1]);
  }
  auto mapper = vtkSmartPointer<vtkPolyDataMapper>::New();
  mapper->SetInputData(surface);
  mapper->ScalarVisibilityOff();
  auto actor = vtkSmartPointer<vtkActor>::New();
  actor->SetMapper(mapper);
  actor->GetProperty()->SetColor(rgb[0], rgb[1], rgb[2]);
  if (opacity < 1) actor->GetProperty()->SetOpacity(opacity);
  actor->GetProperty()->SetAmbient(0.35); // keeps the colours readable on faces turned from the light
  actor->GetProperty()->SetDiffuse(0.65);
  scene->AddActor(actor);
}

} // namespace

void writeCementSurface(vtkImageData* labels, const std::filesystem::path& png, const CementSurfaceOptions& options) {
  if (labels == nullptr || labels->GetPointData()->GetScalars() == nullptr ||
      labels->GetNumberOfScalarComponents() != 1)
    throw std::invalid_argument("writeCementSurface: the label map must be a one-component image");
  const double inBone[3] = {0.30, 0.50, 0.95}, leaked[3] = {0.90, 0.08, 0.08}, grey[3] = {0.15, 0.15, 0.15},
               bone[3] = {0.80, 0.72, 0.55};
  vtkIdType inBoneVoxels = 0, leakedVoxels = 0;
  const auto boneMask = maskOf(labels, 1, inBoneVoxels);
  const auto leakMask = maskOf(labels, 2, leakedVoxels);
  if (inBoneVoxels + leakedVoxels == 0)
    throw std::invalid_argument("writeCementSurface: the label map holds no cement (no voxel labelled 1 or 2)");

  surfacemetrics::IsosurfaceOptions iso;
  iso.smoothingSigmaVoxels = 0.0; // faithful to the voxels: a one-voxel leak must still show
  auto scene = vtkSmartPointer<vtkRenderer>::New();
  scene->SetViewport(0.0, 0.0, 1.0, 1.0 - options.titleBandFraction);
  scene->SetBackground(1.0, 1.0, 1.0);
  double box[6] = {1e300, -1e300, 1e300, -1e300, 1e300, -1e300};
  for (const auto& [mask, voxels, rgb] : {std::make_tuple(boneMask, inBoneVoxels, inBone), std::make_tuple(leakMask, leakedVoxels, leaked)}) {
    if (voxels == 0) continue;
    const auto surface = surfacemetrics::isosurface(mask, iso);
    if (surface->GetNumberOfPoints() == 0) continue;
    addSurface(scene, surface, rgb, 1.0, box);
  }
  if (!(box[0] <= box[1]))
    throw std::invalid_argument("writeCementSurface: the cement has no surface inside the image");
  // The vertebra, translucent, drawn after the cement so the cement shows through it.
  bool vertebraShown = false;
  if (options.vertebraMask) {
    if (!options.vertebraMask->GetPointData()->GetScalars())
      throw std::invalid_argument("writeCementSurface: the vertebra label map has no scalars");
    vtkIdType vertebraVoxels = 0;
    const auto vertebra = maskOf(options.vertebraMask, options.vertebraLabel, vertebraVoxels);
    const auto surface = vertebraVoxels > 0 ? surfacemetrics::isosurface(vertebra, iso) : nullptr;
    if (surface && surface->GetNumberOfPoints() > 0) {
      addSurface(scene, surface, bone, options.vertebraOpacity, box);
      vertebraShown = true;
    }
  }

  auto camera = scene->GetActiveCamera();
  const double centre[3] = {(box[0] + box[1]) / 2, (box[2] + box[3]) / 2, (box[4] + box[5]) / 2};
  const double diagonal = std::sqrt((box[1] - box[0]) * (box[1] - box[0]) + (box[3] - box[2]) * (box[3] - box[2]) +
                                    (box[5] - box[4]) * (box[5] - box[4]));
  const double* d = options.viewDirection;
  const double norm = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  if (!(norm > 0)) throw std::invalid_argument("writeCementSurface: the view direction is zero");
  camera->ParallelProjectionOn();
  camera->SetFocalPoint(centre);
  camera->SetPosition(centre[0] + 4 * diagonal * d[0] / norm, centre[1] + 4 * diagonal * d[1] / norm,
                      centre[2] + 4 * diagonal * d[2] / norm);
  camera->SetViewUp(options.viewUp);
  camera->OrthogonalizeViewUp();
  camera->SetParallelScale(0.55 * std::max(diagonal, 1e-6));
  scene->ResetCameraClippingRange(box);

  auto title = vtkSmartPointer<vtkRenderer>::New();
  title->SetViewport(0.0, 1.0 - options.titleBandFraction, 1.0, 1.0);
  title->SetBackground(1.0, 1.0, 1.0);
  addText(title, "Cement surface", 0.02, 0.55, 22, grey);
  addText(title, "blue: cement in bone", 0.02, 0.12, 18, inBone);
  if (leakedVoxels > 0) addText(title, "red: leaked (outside bone)", 0.36, 0.12, 18, leaked);
  else addText(title, "no leakage", 0.36, 0.12, 18, grey);
  if (!options.note.empty()) addText(title, options.note, 0.40, 0.55, 16, grey);
  if (vertebraShown) addText(title, "beige: the vertebra", 0.70, 0.12, 18, bone);

  auto window = makeOffScreenRenderWindow(options.widthPx, options.heightPx);
  window->AddRenderer(scene);
  window->AddRenderer(title);
  writeWindowPng(window, png);
}

} // namespace cementsph::rendering
