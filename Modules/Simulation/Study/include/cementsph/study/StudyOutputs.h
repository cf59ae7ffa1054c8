// What `cementsph study` prepares before its runs and writes after each: the reference the size study is
// scored against (a post-operative CT's cement, or the finest run), the notes on runs whose estimated work
// is large, and the tables (study.csv, spreading_vs_viscosity.csv, study.md, study.json). Here, beside the
// runner and the CSV/Markdown formats (StudyReport.h), so that the command holds no schema or writer.
#pragma once

#include "cementsph/imaging/ImageTypes.h"
#include "cementsph/study/StudyPlan.h"
#include "cementsph/study/StudyRow.h"
#include "cementsph/study/StudyRunner.h"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace cementsph::study {

// One line for each planned run whose estimated work scene::checkRunSize notes ("run NAME: NOTE"); throws
// as checkRunSize does for a run too large without allowLarge. voxelVolumeMm3: the CT's voxel volume.
std::vector<std::string> runSizeNotes(const StudyPlan& plan, double voxelVolumeMm3, bool allowLarge);

// Reads the post-operative CT referenceCtPath, puts it on ct's grid (registered as `compare` does, or only
// resampled), analyses its cement with the runner's segmentation and sets it as the runner's reference.
// Returns study.md's description of it. Throws std::runtime_error naming the file when it has no cement.
std::string setReferenceCt(StudyRunner& runner, const imaging::ImageType* ct, const std::string& referenceCtPath,
                           bool registration, const std::string& thresholdRule);

// The description of the size study's finest run, the reference when no CT is given ("" without a size study).
std::string finestRunReference(const StudyPlan& plan);

// Everything the tables say: the inputs, the plan as run and the rows so far.
struct StudyRecord {
  std::string ct, sceneFile, referenceCt; // referenceCt empty: scored against the finest run
  const StudyPlan* plan = nullptr;
  std::string reference;     // its description (setReferenceCt / finestRunReference)
  std::string thresholdRule; // imaging::describeThresholdRule of the runs' segmentation
  int threads = 1;           // OpenMP threads of each rank
  int ranks = 1;             // MPI ranks
  std::vector<StudyRow> sizeRows, viscosityRows;
  double studyWallTimeS = 0.0; // since the study started
};

// The injections' and analyses' wall time of the rows so far, s.
double runsWallTimeS(const StudyRecord& record);

// study.json (provenance included).
nlohmann::json studyJson(const StudyRecord& record);

// Writes the tables into out (created): study.csv (with size rows), spreading_vs_viscosity.csv (with
// viscosity rows), study.md and study.json, each atomically. Returns the names written: study.md, study.json, then the CSVs.
std::vector<std::string> writeStudyTables(const StudyRecord& record, const std::filesystem::path& out);

} // namespace cementsph::study
