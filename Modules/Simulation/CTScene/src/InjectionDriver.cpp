// The one driver of every injection engine (InjectionModel.h): what the engines share lives here once.
#include "cementsph/scene/InjectionRunner.h"

#include "InjectionOutputs.h"

#include "cementsph/provenance/Provenance.h"
#include "cementsph/imaging/VolumeIO.h"
#include "cementsph/scene/AxisAlignedCT.h"
#include "cementsph/scene/InputGridPaste.h"
#include "cementsph/scene/ModelSelection.h"
#include "cementsph/scene/PorousSolid.h"
#include "cementsph/scene/SimulatedCT.h"
#include "cementsph/scene/SlicerFiles.h"
#include "cementsph/sph/Presets.h"
#include "cementsph/sph/Simulation.h"

#include <itkImageRegionIteratorWithIndex.h>

#include <algorithm>
#include <filesystem>
#include <chrono>
#include <cmath>
#include <iostream>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace cementsph::scene {

namespace {

// The preset's model with the scene's overrides; h from the particle spacing.
sph::ModelParameters modelParameters(const sph::ModelPreset& preset, const SceneConfig& scene) {
  sph::ModelParameters m = preset.model;
  if (scene.integrator) m.integrator = sph::parseIntegrator(*scene.integrator);
  if (scene.dragCoefficient) m.dragCoefficient = *scene.dragCoefficient;
  if (scene.soundSpeedMPerS) m.soundSpeed = *scene.soundSpeedMPerS;
  m.fixedSums = scene.fixedSumMethod();
  if (scene.fixedFieldSpacingOverH) m.fixedFieldSpacing = *scene.fixedFieldSpacingOverH;
  // The overdamped step moves the fastest particle at most this fraction of h. The engine's 0.05 suits
  // the Darcy box; in an injection the fastest particles are the few at the tip, and 0.05 to 0.5 gave
  // the same cement to 0.01 mm of spreading on the phantom (VALIDATION.md), so 0.25: 4x fewer steps.
  m.maxDisplacement = scene.maxDisplacementOverH.value_or(0.25);
  if (scene.neighbourSkinOverH) m.neighbourSkin = *scene.neighbourSkinOverH;
  m.smoothingLength = preset.hOverD * scene.spacingM();
  return m;
}

struct BoneChoice {
  std::string model, reason;
};

// The bone: pore-resolved (the paper's solid voxels) or a continuum from HU (BoneCalibration.h). Auto: a
// continuum when the tip's voxel is above threshold_hu but not cortex, i.e. no pore is resolved there.
BoneChoice chooseBone(const imaging::ImageType* ct, const SceneConfig& scene) {
  BoneChoice b{scene.boneModel, "forced by the scene key bone_model"};
  if (b.model != "auto") return b;
  const Eigen::Vector3d tipMm = *scene.tipMm;
  imaging::ImageType::PointType point;
  for (unsigned a = 0; a < 3; ++a) point[a] = tipMm[int(a)];
  imaging::ImageType::IndexType index;
  b.model = "pore-resolved";
  b.reason = "the tip's voxel is at or below threshold_hu: the CT resolves the pores (the paper's model)";
  if (ct->TransformPhysicalPointToIndex(point, index)) {
    const double hu = ct->GetPixel(index);
    if (hu > scene.thresholdHu && hu <= scene.bone.corticalHu) {
      b.model = "continuum";
      std::ostringstream r;
      r << "the tip's voxel is " << hu << " HU, above threshold_hu " << scene.thresholdHu << " HU and below cortical_hu "
        << scene.bone.corticalHu << " HU: the CT does not resolve the pores there, so the bone is a continuum from HU";
      b.reason = r.str();
    }
  }
  return b;
}

// Outlet pressures from the series: final, largest, and the injection (syringe) pressure's largest.
void summarisePressures(const std::vector<TipRecord>& series, InjectionSummary& s) {
  if (series.empty()) return;
  double maxTip = -std::numeric_limits<double>::infinity(), maxInjection = 0.0;
  for (const TipRecord& r : series) {
    maxTip = std::max(maxTip, r.tipPa);
    maxInjection = std::max(maxInjection, r.tipPa + r.cannulaPa);
  }
  const double finalTip = std::isfinite(series.back().tipPa) ? series.back().tipPa : 0.0;
  s.finalTipPressurePa = finalTip;
  s.maxTipPressurePa = std::isfinite(maxTip) ? maxTip : 0.0;
  s.cannulaPressureDropPa = series.back().cannulaPa;
  s.injectionPressurePa = finalTip + series.back().cannulaPa;
  s.maxInjectionPressurePa = maxInjection;
}

// A label map on `grid`'s geometry from per-voxel labels in its buffer order.
imaging::MaskType::Pointer labelMapOn(const imaging::ImageType* grid, const std::vector<std::uint8_t>& labels) {
  auto map = imaging::MaskType::New();
  map->CopyInformation(grid);
  map->SetRegions(grid->GetLargestPossibleRegion());
  map->Allocate();
  std::copy(labels.begin(), labels.end(), map->GetBufferPointer());
  return map;
}

// The anatomy's classes as a label map on the grid they were made on.
imaging::MaskType::Pointer anatomyMap(const anatomy::Anatomy& a) {
  auto map = imaging::MaskType::New();
  imaging::MaskType::RegionType region;
  imaging::MaskType::SpacingType spacing;
  imaging::MaskType::PointType origin;
  imaging::MaskType::DirectionType direction;
  for (unsigned r = 0; r < 3; ++r) {
    region.SetSize(r, itk::SizeValueType(a.grid.size[r]));
    spacing[r] = a.grid.spacingMm[r];
    origin[r] = a.grid.originMm[r];
    for (unsigned c = 0; c < 3; ++c) direction(r, c) = a.grid.direction[3 * r + c];
  }
  map->SetRegions(region);
  map->SetSpacing(spacing);
  map->SetOrigin(origin);
  map->SetDirection(direction);
  map->Allocate();
  std::copy(a.classes.begin(), a.classes.end(), map->GetBufferPointer());
  return map;
}

// The label map on the input CT's grid: each input voxel whose centre lies in the region's box takes the label
// of the region voxel nearest that centre (labels are not interpolated); 0 elsewhere. Every index is checked.
imaging::MaskType::Pointer labelsOnInputGrid(const imaging::ImageType* input, const imaging::MaskType* region) {
  auto map = imaging::MaskType::New();
  map->CopyInformation(input);
  map->SetRegions(input->GetLargestPossibleRegion());
  map->Allocate();
  map->FillBuffer(0);
  const auto inRegion = input->GetLargestPossibleRegion();
  const auto roi = region->GetLargestPossibleRegion();
  // Only the input voxels near the region's box: its corners' input indices bound them.
  itk::ImageRegionIteratorWithIndex<imaging::MaskType> it(map, inRegion);
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
  for (int corner = 0; corner < 8; ++corner) {
    itk::ContinuousIndex<double, 3> ci;
    for (unsigned a = 0; a < 3; ++a)
      ci[a] = double(roi.GetIndex()[a]) - 0.5 + ((corner >> a) & 1 ? double(roi.GetSize()[a]) : 0.0);
    imaging::MaskType::PointType p;
    region->TransformContinuousIndexToPhysicalPoint(ci, p);
    itk::ContinuousIndex<double, 3> ii;
    input->TransformPhysicalPointToContinuousIndex(p, ii);
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], ii[unsigned(a)]);
      hi[a] = std::max(hi[a], ii[unsigned(a)]);
    }
  }
  imaging::MaskType::IndexType start;
  imaging::MaskType::SizeType size;
  for (unsigned a = 0; a < 3; ++a) {
    const long first = std::max<long>(inRegion.GetIndex()[a], long(std::floor(lo[int(a)])));
    const long last = std::min<long>(inRegion.GetIndex()[a] + long(inRegion.GetSize()[a]) - 1, long(std::ceil(hi[int(a)])));
    if (last < first) return map; // the region lies outside the input
    start[a] = first;
    size[a] = itk::SizeValueType(last - first + 1);
  }
  itk::ImageRegionIteratorWithIndex<imaging::MaskType> near(map, imaging::MaskType::RegionType(start, size));
  for (; !near.IsAtEnd(); ++near) {
    imaging::MaskType::PointType p;
    map->TransformIndexToPhysicalPoint(near.GetIndex(), p);
    imaging::MaskType::IndexType r;
    if (region->TransformPhysicalPointToIndex(p, r)) near.Set(region->GetPixel(r)); // nearest, inside only
  }
  return map;
}

// Cement in the outermost voxels of the region: where that face is the scan's edge the cement may go on beyond
// what the CT shows; elsewhere the region (roi_size_mm) cut it. Either is a warning (and a plan limit).
void edgeWarnings(const imaging::ImageType& ct, const PorousSolid& solid, const SparseDensity& density,
                  InjectionSummary& s) {
  const auto size = ct.GetLargestPossibleRegion().GetSize();
  const std::array<int, 3> n = solid.grid.size;
  // Which of the region's six faces hold cement (a voxel in the face's layer with density > 0): a pass over the
  // cement, not over the faces' voxels.
  bool onFace[3][2] = {{false, false}, {false, false}, {false, false}};
  for (const auto& [c, rho] : density) {
    if (!(rho > 0)) continue;
    const std::size_t row = c / std::size_t(n[0]);
    const std::array<int, 3> ijk{int(c % std::size_t(n[0])), int(row % std::size_t(n[1])), int(row / std::size_t(n[1]))};
    for (int a = 0; a < 3; ++a) {
      if (ijk[std::size_t(a)] == 0) onFace[a][0] = true;
      if (ijk[std::size_t(a)] == n[std::size_t(a)] - 1) onFace[a][1] = true;
    }
  }
  bool scanEdge = false, regionEdge = false;
  for (int a = 0; a < 3; ++a)
    for (int side = 0; side < 2; ++side) {
      const bool atScan = side == 0 ? solid.roiStart[std::size_t(a)] == 0
                                    : solid.roiStart[std::size_t(a)] + solid.roiSize[std::size_t(a)] == long(size[unsigned(a)]);
      if (onFace[a][side]) (atScan ? scanEdge : regionEdge) = true;
    }
  if (scanEdge)
    s.warnings.push_back("the cement reached the edge of the scan: it may go on where the CT does not show "
                         "(a larger field of view, or less cement)");
  if (regionEdge)
    s.warnings.push_back("the cement reached the edge of the region of interest: the result is cut there "
                         "(a larger roi_size_mm)");
}

// True when `region` lies on exactly the input's grid: an axial input (nothing resampled or reoriented, so the
// region's HU are the input's own), the same voxels, origin, spacing and direction.
bool isInputGrid(const imaging::ImageType* input, const imaging::ImageType* region) {
  if (!isAxisAligned(input) || input->GetLargestPossibleRegion() != region->GetLargestPossibleRegion() ||
      input->GetDirection() != region->GetDirection())
    return false;
  for (unsigned a = 0; a < 3; ++a) {
    const double h = input->GetSpacing()[a];
    if (region->GetSpacing()[a] != h || std::abs(region->GetOrigin()[a] - input->GetOrigin()[a]) > 1e-6 * h) return false;
  }
  return true;
}

// The path of the first number in j that is NaN or infinite ("" if none).
std::string firstNonFinite(const nlohmann::json& j, const std::string& path = "") {
  if (j.is_number_float()) return std::isfinite(j.get<double>()) ? "" : path;
  if (j.is_object())
    for (const auto& [key, value] : j.items())
      if (std::string bad = firstNonFinite(value, path.empty() ? key : path + "." + key); !bad.empty()) return bad;
  if (j.is_array())
    for (std::size_t i = 0; i < j.size(); ++i)
      if (std::string bad = firstNonFinite(j[i], path + "[" + std::to_string(i) + "]"); !bad.empty()) return bad;
  return "";
}

} // namespace

InjectionRunResult runInjection(const imaging::ImageType* input, const SceneConfig& scene, const InjectionRunOptions& o) {
  scene.validate();
  // Any orientation: an oblique CT is resampled onto an axis-aligned grid in its own patient frame.
  const imaging::ImageType::ConstPointer aligned = axisAligned(input);
  const imaging::ImageType* ct = aligned.GetPointer();
  const auto wallStart = std::chrono::steady_clock::now();
  const sph::ModelPreset preset = sph::modelPreset(scene.modelPreset);
  InjectionSetup setup;
  setup.ct = ct;
  setup.scene = &scene;
  setup.preset = &preset;
  setup.model = modelParameters(preset, scene);
  const BoneChoice bone = chooseBone(ct, scene);
  setup.continuum = bone.model == "continuum";
  // A label map (labels_path): on the CT's own grid, oriented as the CT is (an exact reorientation moves no
  // label; an oblique resampling would blend them, so it is refused).
  imaging::ImageType::ConstPointer labels;
  if (!scene.labelsPath.empty()) {
    const auto raw = imaging::readVolume(scene.labelsPath);
    if (!imaging::geometryOf(raw).sameGrid(imaging::geometryOf(input)))
      throw std::invalid_argument("scene: labels_path " + scene.labelsPath +
                                  ": the label map is not on the CT's grid (size, origin, spacing, direction); export "
                                  "it on the CT's grid (TotalSegmentator and 3D Slicer do)");
    if (!isAxisAligned(input) && !axisPermutation(input))
      throw std::invalid_argument("scene: labels_path with an oblique CT: labels cannot be resampled without blending "
                                  "them; resample the CT and its labels onto an axial grid first (nearest neighbour)");
    labels = axisAligned(raw);
    setup.labels = labels.GetPointer();
  }

  PorousSolidOptions po;
  po.thresholdHu = setup.continuum ? scene.bone.corticalHu : scene.thresholdHu; // continuum: only cortex is solid
  po.roiSizeMm = scene.roiSizeMm;
  po.reachMm = 2.0 * setup.model.smoothingLength * 1e3;
  po.restDensity = setup.model.restDensity;
  po.massFactor = scene.solidMassFactor;
  po.requiredPoreVolumeMm3 = scene.volumeMl * 1e3;
  po.keptPositions = false; // below, for the engines that place fixed particles
  PorousSolid solid = buildPorousSolid(ct, *scene.tipMm, po);
  setup.solid = &solid;
  const double roiVoxels = double(solid.roiSize[0]) * double(solid.roiSize[1]) * double(solid.roiSize[2]);
  const double roiPorosity = roiVoxels > 0 ? 1.0 - double(solid.solidVoxels) / roiVoxels : 1.0;
  // The pore scale for the choice between particles and voxels (ModelSelection.h): pore-resolved bone only.
  const PoreScale pores = poreScaleOf(solid.solid, solid.grid.size,
                                      {solid.grid.spacing[0], solid.grid.spacing[1], solid.grid.spacing[2]},
                                      !setup.continuum);
  ModelChoice choice = chooseModel(scene, setup.model.restDensity, setup.model.soundSpeed, roiPorosity, pores);
  const InjectionModelRegistry::Entry& entry = InjectionModelRegistry::instance().at(choice.pressureModel);
  choice.model = entry.description;
  setup.choice = &choice;
  setup.model.pressureModel = choice.pressureModel;
  if (o.progress) std::cerr << "inject: model " << choice.model << ": " << choice.reason << "\n";
  if (o.progress) std::cerr << "inject: bone " << bone.model << ": " << bone.reason << "\n";
  // Keys the user set that this engine does not read: never ignored silently. Printed with the progress lines
  // (a quiet run, or a plan's evaluations, has them in metrics.json only).
  const std::vector<std::string> unreadKeys = sceneKeysNotRead(scene, choice.pressureModel, choice);
  if (o.progress)
    for (const std::string& w : unreadKeys) std::cerr << "inject: warning: " << w << "\n";

  std::unique_ptr<InjectionModel> model = entry.make();
  // The kept solid voxels' centres (24 bytes each, over a million on a whole-scan region) and their region-sized
  // pass only for an engine that reads them (issue 23): the voxel engine reads the solid mask only.
  if (model->readsKeptSolidCentres()) keepSolidNearPores(solid, po.reachMm);
  model->start(setup);
  if (o.checkOnly) return InjectionResult{};

  const double rho0 = setup.model.restDensity;
  const double hu = o.huPerRelativeDensity;
  InjectionResult result;
  InjectionSummary& s = result.summary;
  s.warnings = unreadKeys;
  auto volumeRecord = [&]() {
    return nlohmann::json{{"time_s", model->time()}, {"volume_injected_ml", model->injectedVolumeM3() * 1e6},
                          {"cement_volume_ml", model->cementVolumeM3() * 1e6}};
  };
  detail::InjectionWriter writer(o.outDir, scene, hu,
                                 [&] {
                                   // The engine is freed before finish() (its CT comes with it then): a frame made
                                   // after that is a programming error, said, not a null dereference.
                                   if (!model) throw std::logic_error("inject: a simulated CT frame asked for after the engine ended");
                                   return simulatedCtOnRoi(ct, solid, model->cementDensity(), hu, rho0);
                                 },
                                 o.onCtFrame);

  // The loop: steps of at most the time to the next snapshot or the end.
  const double T = scene.injectionDurationS();
  const double endTime = T * (1 - model->endSlack());
  detail::InjectionProgress progress(o, wallStart, T);
  double nextSnapshot = scene.snapshotIntervalS;
  while (model->time() < endTime) {
    double dtMax = T - model->time();
    if (nextSnapshot - model->time() > 1e-9 * T) dtMax = std::min(dtMax, nextSnapshot - model->time());
    model->advance(dtMax);
    result.tipSeries.push_back(model->outlet());
    // A surgeon stops at the first leak (1 mm^3 of cement outside bone).
    if (scene.stopAtFirstLeak && model->leakedVolumeM3() > 1e-9) {
      s.stoppedAtFirstLeak = s.stoppedEarly = true;
      break;
    }
    if (model->time() >= nextSnapshot * (1 - 1e-12) && model->time() < endTime) {
      // The cement first: an engine may give the volume record its snapshot's sum (the voxel engine's "flow"
      // snapshots do; a growth piece holds no volumes, so the record then takes the engine's own pass).
      // As growth where the engine's cement stays where it arrived (the voxel engine), else whole.
      vtkSmartPointer<vtkPolyData> arrived =
          writer.writing() && scene.snapshotArrays == "growth" ? model->cementArrivedSinceLastCall() : nullptr;
      vtkSmartPointer<vtkPolyData> cement = writer.writing() && !arrived ? model->cement() : nullptr;
      s.volumeHistory.push_back(volumeRecord());
      if (arrived) writer.snapshotPiece(model->time(), std::move(arrived));
      if (cement) writer.snapshot(model->time(), std::move(cement));
      while (nextSnapshot <= model->time() * (1 + 1e-12)) nextSnapshot += scene.snapshotIntervalS;
    }
    if (!progress.step(model->time(), [&] { return model->state(); })) {
      s.stoppedEarly = true;
      break;
    }
  }
  model->finish(s.stoppedEarly);
  progress.done();

  // The summary: what the driver knows, then what the engine knows.
  s.wallTimeS = progress.wallSeconds();
  s.engine = choice.pressureModel;
  s.model = choice.model;
  s.modelReason = choice.reason;
  s.recommendedPressureModel = choice.recommended;
  s.dimensionlessNumbers = choice.numbersJson();
  s.modelPreset = preset.name;
  s.boneModel = bone.model;
  s.boneModelReason = bone.reason;
  s.ctOrientation = isAxisAligned(input) ? "axial" : axisPermutation(input) ? "reoriented" : "resampled";
  s.ctResampled = s.ctOrientation == "resampled"; // a reorientation moves no value: nothing was interpolated
  s.volumeRequestedMl = scene.volumeMl;
  s.volumeInjectedMl = model->injectedVolumeM3() * 1e6;
  s.cementVolumeMl = model->cementVolumeM3() * 1e6;
  s.simulatedTimeS = model->time();
  s.huPerRelativeDensity = hu;
  for (int a = 0; a < 3; ++a) {
    s.roiStart[std::size_t(a)] = solid.roiStart[std::size_t(a)];
    s.roiSize[std::size_t(a)] = solid.roiSize[std::size_t(a)];
  }
  s.solidVoxelsTotal = solid.solidVoxels;
  s.connectedPoreVoxels = solid.connectedPoreVoxels;
  summarisePressures(result.tipSeries, s);
  s.volumeHistory.push_back(volumeRecord()); // the final state
  model->report(s, result.engineFigures);
  // What the files need from the engine, taken before the engine goes: its state (the voxel model's medium,
  // 4 bytes a region voxel) is then freed before the region-sized images are made, which were the run's peak
  // memory on a whole-scan region (issue 23).
  // kg/m^3 where the cement is at the end, sized to the cement (the voxel engine's; a particle engine's is made
  // from its dense array), freed once the simulated CT is made from it.
  SparseDensity finalDensity = model->cementDensityWhereNonZero();
  edgeWarnings(*ct, solid, finalDensity, s);
  for (std::size_t w = unreadKeys.size(); w < s.warnings.size(); ++w) std::cerr << "inject: warning: " << s.warnings[w] << "\n";
  result.particles = model->cement();
  s.cementPoints = std::size_t(result.particles->GetNumberOfPoints());
  std::vector<std::uint8_t> cementLabels = model->cementLabels();
  imaging::MaskType::Pointer anatomyOnRegion; // the anatomy the leakage was judged by
  if (const anatomy::Anatomy* used = model->anatomyUsed(); used && writer.writing()) anatomyOnRegion = anatomyMap(*used);
  const double finalTime = model->time();
  const std::optional<double> baselinePa = model->pressureBaselinePa();
  model.reset();
  result.simulatedCt = simulatedCtOnRoi(ct, solid, finalDensity, hu, rho0);
  SparseDensity().swap(finalDensity);
  if (!cementLabels.empty()) result.cementLabels = labelMapOn(result.simulatedCt, cementLabels);
  std::vector<std::uint8_t>().swap(cementLabels);
  // The files on the input's own grid unless a crop was asked for (only when files are written: a copy of the
  // whole scan is what a study or a plan does not need).
  if (writer.writing()) {
    result.simulatedCtFile = result.simulatedCt;
    result.cementLabelsFile = result.cementLabels;
    // A region that is the input's whole grid (a whole-scan region on an axial CT) is the file as it is: the
    // paste would copy it voxel for voxel (issue 23: a third copy of the scan at the run's peak).
    if (!o.cropToRegion && !isInputGrid(input, result.simulatedCt)) {
      // The region of the CT the engine ran on, before cement: what the paste takes the difference from (made
      // here only: on a whole-scan region it would be another copy of the scan).
      const imaging::ImageType::Pointer regionCt = simulatedCtOnRoi(ct, solid, std::vector<double>{}, hu, rho0);
      result.simulatedCtFile = pasteOntoInputGrid(input, result.simulatedCt, regionCt);
      if (result.cementLabels) result.cementLabelsFile = labelsOnInputGrid(input, result.cementLabels);
    } else if (!o.cropToRegion) {
      // The input's origin to the bit (the region's went mm -> m -> mm, within 1e-6 of a voxel: isInputGrid), as
      // the paste's copy of the input's geometry gave it: the files' headers say what the input's say.
      result.simulatedCt->SetOrigin(input->GetOrigin());
      if (result.cementLabels) result.cementLabels->SetOrigin(input->GetOrigin());
    }
    // The anatomy on the same grid as the simulated CT's file.
    if (anatomyOnRegion) result.anatomyLabelsFile = labelsOnInputGrid(result.simulatedCtFile, anatomyOnRegion);
  }
  result.metrics = s.toJson();
  result.metrics["provenance"] = provenance::toJson();
  for (const auto& [key, value] : result.engineFigures.items()) {
    if (result.metrics.contains(key))
      throw std::logic_error("injection model \"" + s.engine + "\" reports \"" + key + "\", a key the driver owns");
    result.metrics[key] = value;
  }
  // Not one non-finite figure goes out silently (JSON would write it as null): a run that made one failed.
  if (const std::string bad = firstNonFinite(result.metrics); !bad.empty())
    throw sph::SimulationError("inject: the run's figure " + bad + " is not a finite number (the run went wrong; "
                               "try a smaller flow rate or particle radius, or report the scene)");
  result.metrics["simulated_ct_grid"] = o.cropToRegion ? "region" : "input";
  // The label maps are this run's files too: a later write that fails takes them with it.
  if (result.cementLabelsFile) imaging::writeMask(result.cementLabelsFile, writer.fileOfThisRun("cement_labels.nrrd"));
  if (result.anatomyLabelsFile)
    imaging::writeMask(result.anatomyLabelsFile, writer.fileOfThisRun("anatomy_labels.nrrd"));
  // For 3D Slicer (SlicerFiles.h): the tip and trajectory, the leak sites, the label maps' colours.
  std::vector<std::pair<std::string, std::string>> slicerFiles{
      {"injection.mrk.json", injectionMarkups(*scene.tipMm, scene.direction, scene.cannulaLengthMm).dump(2) + "\n"},
      {"leak_sites.mrk.json", leakSiteMarkups(s.leakageSites).dump(2) + "\n"},
      {"cement_labels.ctbl", cementLabelColourTable()}};
  if (result.anatomyLabelsFile) slicerFiles.emplace_back("anatomy_labels.ctbl", anatomyLabelColourTable());
  writer.finish(finalTime, result.particles, result.simulatedCt, result.simulatedCtFile, result.tipSeries, baselinePa,
                result.metrics, slicerFiles);
  return result;
}

} // namespace cementsph::scene
