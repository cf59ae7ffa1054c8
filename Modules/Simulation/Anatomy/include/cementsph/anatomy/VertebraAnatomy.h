// Which tissue each voxel of a CT region is (issue 20, item 1), so that leakage is cement outside the target
// vertebra, reported by where it went, and a tip outside bone is refused.
//
// Input: the CT region as plain arrays (HU per voxel, x fastest, then y, then z), its grid (size, spacing,
// origin = the first voxel's centre, direction = the index axes in the patient frame), the tip (LPS mm), and
// the continuum model's thresholds (BoneCalibration.h: soft_tissue_max_hu 40, cortical_hu 350), passed in.
// Optionally a label map on the same grid with a label -> class table (TotalSegmentator, Slicer, ...).
//
// The CT-only bone rule (classifyAnatomyFromCT; each step's reason at its code):
//  1. Cortex: HU > cortical_hu. The bone band: soft_tissue_max_hu <= HU <= cortical_hu.
//  2. The shell (HU > wall_hu, 250: a 1 mm end plate averaged over a 2 mm slice shows 250-350 HU, trabecular
//     bone 80-200) is thickened by wall_close_mm (a box of ceil(wall_close_mm / spacing) voxels per axis) into a
//     wall: gaps in the shell up to 2 x wall_close_mm wide (the basivertebral foramen, a vein's channel, a thin
//     or partial-volumed end plate) are closed, so the region grown from the tip cannot run out through them.
//  3. The target's core: the 6-connected band voxels outside the wall around the tip, with its 3-D holes filled
//     (marrow fat and any low-HU voxel fully enclosed by it are bone). It must be enclosed on all six sides: in
//     each of +-x, +-y, +-z at least min_enclosure of the core's boundary faces that way meet the wall (a disc is
//     open at its sides, a vessel or muscle everywhere). If the tip's own region fails, the nearest other region
//     within seed_search_mm that passes is the target (a tip in a disc: the vertebra next to it).
//  4. The body: the core grown back by the wall's width + 1 voxel into band and cortex (the strip the wall took,
//     up to and including the cortex), holes filled again in 3-D and then in every sagittal and coronal slice
//     (marrow fat that reaches a gap of the cortex is open in 3-D but enclosed in those slices; axial slices are
//     not used: there the canal is enclosed by the vertebral ring). The target vertebra: the body, the cortex 26-connected
//     to it within the body's axial extent +- 2 mm (pedicles, lamina), and the band voxels touching that cortex
//     (its partial-volume rim).
//  5. Disc: along the spine axis (the index axis nearest patient z), above and below the body in each of its
//     columns, the run of voxels from the body's end plate to the next shell voxel (the neighbour's end plate), if
//     (HU > wall_hu) is found within max_disc_height_mm and the run holds no air.
//  6. Canal: in each axial slice, the non-target regions of at least min_canal_area_mm2 enclosed by the target
//     vertebra (the vertebral foramen: body, pedicles and lamina ring it). Not detected at disc level.
//  7. Other bone: cortex not in the target, its partial-volume rim, and anything enclosed by bone that is not the
//     target (the marrow of a neighbour wholly inside the region).
//  8. Vessel: 6-connected components of band voxels left over, of at least min_vessel_ml, that either touch the
//     target and are thin (no voxel deeper than max_vein_radius_mm inside: a vein draining the body, not a
//     muscle), or are contrast-filled (mean HU >= contrast_hu: an enhanced aorta, vena cava, plexus); then a
//     soft-tissue voxel with 4 or more of its 6 neighbours vessel is vessel (noise holes).
//  9. Air: HU < air_max_hu; everything else: other soft tissue.
// Assumptions: the region holds the target vertebra with soft tissue around; the spine runs along patient z
// within 45 degrees; the basivertebral vein inside the body is bone-band HU and belongs to the target.
// Cost: linear in the voxels of the box that holds everything not air (below air_max_hu; the rest is classed air
// without a pass of its own, the same classes as the rule on the whole grid), the hole fillings in the box of
// what they fill; about 2 s for 6.4 million voxels before those cuts (0.5 mm voxels over 100 x 100 x 80 mm, one
// core); since then (2026-12-03) VertebraAnatomyTest takes 0.65 s instead of 1.35 s and PlanObliqueTest's 19-injection
// plan on a 200 x 70 x 200 mm field 1.23 s CPU instead of 2.26 s. Pass a region around the tip (a vertebra and its
// discs fit in 100 mm), not a whole scan.
#pragma once

#include <nlohmann/json.hpp>

#include <array>
#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace cementsph::anatomy {

// Class codes, stored one byte per voxel (Anatomy::classes).
enum class TissueClass : std::uint8_t {
  OtherSoftTissue = 0,
  TargetVertebra = 1,
  Disc = 2,
  Canal = 3,
  Vessel = 4,
  OtherBone = 5,
  Air = 6,
};
const char* className(TissueClass c);   // "other_soft_tissue", "target_vertebra", "disc", "canal", ...
const char* tissueWords(TissueClass c); // for messages: "the intervertebral disc", "the spinal canal", ...
TissueClass classFromName(const std::string& name); // std::invalid_argument naming the word

// A CT region's grid. Voxel (i, j, k) is at originMm + direction * (i sx, j sy, k sz); index n = i + nx (j + ny k).
struct Grid {
  std::array<int, 3> size{0, 0, 0};
  std::array<double, 3> spacingMm{1, 1, 1};
  std::array<double, 3> originMm{0, 0, 0};
  std::array<double, 9> direction{1, 0, 0, 0, 1, 0, 0, 0, 1}; // row-major; column a = index axis a in LPS
  std::size_t count() const { return std::size_t(size[0]) * std::size_t(size[1]) * std::size_t(size[2]); }
  std::array<double, 3> centreMm(int i, int j, int k) const;
  std::array<double, 3> continuousIndex(const std::array<double, 3>& pointMm) const; // inverse of centreMm
  double voxelVolumeMm3() const { return spacingMm[0] * spacingMm[1] * spacingMm[2]; }
  void validate() const; // std::invalid_argument naming the field
};

struct AnatomyOptions {
  double softTissueMaxHu = 40.0; // BoneCalibration::softTissueMaxHu: below it, not bone
  double corticalHu = 350.0;     // BoneCalibration::corticalHu: above it, cortex
  double airMaxHu = -500.0;      // below it, air (fat is -150 .. -50, lung -900)
  double wallHu = 250.0;         // above it, the shell that bounds the target (partial-volumed cortex included)
  double wallCloseMm = 2.5;      // gaps of the shell up to twice this are closed
  double minEnclosure = 0.5;     // per direction, the share of the core's boundary on the wall
  double seedSearchMm = 20.0;    // where to look for the vertebra when the tip is not in one
  double minBodyMl = 1.0;        // a vertebral core is at least this big (a lumbar body is 20-40 ml)
  double maxDiscHeightMm = 15.0; // lumbar discs are 8-14 mm
  double minCanalAreaMm2 = 30.0; // the spinal canal is 150-300 mm^2; smaller holes are cortical pores
  double maxVeinRadiusMm = 3.0;  // basivertebral and segmental veins are 1-4 mm across
  double minVesselMl = 0.02;     // smaller band specks outside bone are noise
  double contrastHu = 150.0;     // contrast-filled vessels (200-400 HU) above it
  void validate() const;         // std::invalid_argument naming the option (snake_case, as a scene key)
};

// Which labels of a label map are which class. Labels not listed are classed by HU (air or soft tissue).
// JSON: {"vertebrae": [..], "target_vertebra": n (optional), "bone": [..], "disc": [..], "canal": [..],
//        "vessel": [..], "air": [..], "soft_tissue": [..]}. The target vertebra is target_vertebra if given,
// else the vertebra label at the tip, else the one nearest the tip within seed_search_mm; other vertebrae
// are other bone.
struct LabelTable {
  std::vector<int> vertebrae;
  int targetVertebra = -1; // -1: the one at (or nearest) the tip
  std::map<int, TissueClass> classes; // the other labels
  // The default: TotalSegmentator's "total" task, v2 numbering (map_to_binary.py, class_map["total"]):
  // vertebrae 26 (S1) .. 50 (C1); bone: sacrum 25, humeri, scapulae, claviculae, femora, hips 69-78, ribs
  // 92-115, sternum 116; vessel: aorta 52, pulmonary vein 53, the great vessels 54-60, venae cavae 62-63,
  // portal/splenic vein 64, iliac arteries and veins 65-68; canal: spinal cord 79. It has no discs (its
  // "vertebrae_body" task does): pass a table (JSON) for that or any other segmentation.
  static LabelTable totalSegmentator();
  static LabelTable fromJson(const nlohmann::json& j); // std::invalid_argument naming the key
  nlohmann::json toJson() const;
};

struct Anatomy {
  Grid grid;
  std::vector<std::uint8_t> classes; // TissueClass per voxel
  std::string rule;                  // "labels" or "ct-bone-rule"
  std::string description;           // one line: which rule, what the target is
  bool targetFound = false;
  std::array<double, 3> targetCentroidMm{0, 0, 0};
  TissueClass at(std::size_t n) const { return TissueClass(classes[n]); }
  TissueClass atPoint(const std::array<double, 3>& pointMm) const; // the nearest voxel; outside: OtherSoftTissue
  double volumeMl(TissueClass c) const;
  nlohmann::json toJson() const; // rule, description, target centroid, volume per class
};

// The CT-only bone rule. hu: grid.count() values. std::invalid_argument for an empty grid or a tip outside it.
Anatomy classifyAnatomyFromCT(const float* hu, const Grid& grid, const std::array<double, 3>& tipMm,
                              const AnatomyOptions& options);
// From a label map on the same grid (the CT gives air and soft tissue where no label is).
Anatomy classifyAnatomyFromLabels(const float* hu, const std::int32_t* labels, const Grid& grid,
                                  const std::array<double, 3>& tipMm, const LabelTable& table,
                                  const AnatomyOptions& options);

// The class at the tip (its nearest voxel).
TissueClass tissueAtTip(const Anatomy& anatomy, const std::array<double, 3>& tipMm);
// Throws std::invalid_argument, one line naming the tissue and the tip's HU, when the tip is not in the target
// vertebra and allowOutsideBone is false: "the tip at (x, y, z) mm is in the intervertebral disc (HU 82);
// place it in the vertebral body or set allow_tip_outside_bone". Returns the class at the tip.
TissueClass requireTipInVertebra(const Anatomy& anatomy, const float* hu, const std::array<double, 3>& tipMm,
                                 bool allowOutsideBone);

} // namespace cementsph::anatomy
