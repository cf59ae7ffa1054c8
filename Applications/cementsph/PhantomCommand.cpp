// cementsph phantom: a synthetic open-cell foam CT and its post-injection CT (issue 4; Basafa et al. 2013,
// "Foam Block Tests"). Writes DIR/pre.nrrd, DIR/post.nrrd (unless --no-post; --post-dicom adds DIR/post_dicom/)
// and DIR/truth.json (every key names its unit). Modules/Simulation/Phantom; docs/phantom-figures.md.
// A thin layer: the phantoms and truth.json's schema are CementSPH::Phantom's (PhantomFiles.h); this file turns
// the options into the phantoms' options, writes the command that makes the files again, and prints a summary.
#include "CommandRegistry.h"
#include "SceneOverrides.h"

#include "cementsph/phantom/FoamPhantom.h"
#include "cementsph/phantom/PhantomFiles.h"
#include "cementsph/phantom/VertebraPhantom.h"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>
#include <stdexcept>

namespace {

namespace fs = std::filesystem;
using namespace cementsph::phantom;

struct PhantomArgs {
  std::string out;
  std::vector<double> sizeMm;
  double cellSizeMm = 4.0, strutThicknessMm = 0, porosity = 0.8, shellMm = 5.0, airMarginMm = 2.0, noiseHu = 20.0;
  std::uint64_t seed = 1;
  double volumeMl = 1.0, viscosityPaS = 100.0;
  bool noPost = false, postDicom = false, quiet = false;
  int threads = 0;
  std::string kind = "foam";
  double foramenDiameterMm = 3.0;
  // The vertebra's anatomy variant (issue 20): 0 = off, as the module's defaults.
  double marrowFatRadiusMm = 0.0, discHeightMm = 0.0, veinRadiusMm = 0.0;
};

double secondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Runs validate(); its message names a key ("disc_height_mm must be ..."): the user typed the option.
template <typename Validate> void validateNamingTheOption(const Validate& validate) {
  try {
    validate();
  } catch (const std::invalid_argument& e) {
    std::string m = e.what();
    for (auto& c : m)
      if (c == '_') c = '-';
    throw std::invalid_argument("--" + m);
  }
}

void checkOutputPath(const std::string& out) {
  if (fs::exists(out) && !fs::is_directory(out)) throw std::runtime_error(out + ": exists and is not a directory");
}

const char* const kVariantOptions[] = {"--marrow-fat-radius-mm", "--disc-height-mm", "--vein-radius-mm"};

VertebraOptions vertebraOptions(const PhantomArgs& a, const CLI::App& sub) {
  VertebraOptions vo;
  if (sub.count("--noise-hu")) vo.noiseHu = a.noiseHu; // else the vertebra's own default (the foam's is higher)
  vo.seed = a.seed;
  vo.foramenDiameterMm = a.foramenDiameterMm;
  vo.marrowFatRadiusMm = a.marrowFatRadiusMm;
  vo.discHeightMm = a.discHeightMm;
  vo.veinRadiusMm = a.veinRadiusMm;
  try {
    validateNamingTheOption([&] { vo.validate(); });
  } catch (const std::invalid_argument& e) {
    // The field is not an option: a disc that does not fit it is the disc height's fault.
    const std::string m = e.what();
    if (m.rfind("--field-mm", 0) != 0 || m.find("must hold") == std::string::npos) throw;
    throw std::invalid_argument("--disc-height-mm: " + cementsph::app::exactNumber(a.discHeightMm) +
                                " mm does not fit: the vertebra phantom's field (" +
                                cementsph::app::exactNumber(vo.fieldMm[2]) + " mm high) " +
                                m.substr(m.find("must hold")) + "; give a smaller height");
  }
  return vo;
}

// The command that makes these files again (generation times aside), with every option spelled out.
std::string vertebraCommandLine(const PhantomArgs& a, const VertebraOptions& vo) {
  std::ostringstream command;
  command << "cementsph phantom --kind vertebra --out " << a.out << " --noise-hu " << vo.noiseHu << " --seed " << vo.seed
          << " --foramen-diameter-mm " << vo.foramenDiameterMm;
  if (vo.marrowFatRadiusMm > 0) command << " --marrow-fat-radius-mm " << vo.marrowFatRadiusMm;
  if (vo.discHeightMm > 0) command << " --disc-height-mm " << vo.discHeightMm;
  if (vo.veinRadiusMm > 0) command << " --vein-radius-mm " << vo.veinRadiusMm;
  return command.str();
}

// The vertebra: pre.nrrd, the same as a DICOM series in pre_dicom/, and truth.json (geometry, plan, command).
int runVertebra(const PhantomArgs& a, const CLI::App& sub) {
  const VertebraOptions vo = vertebraOptions(a, sub);
  checkOutputPath(a.out);
  const auto t0 = std::chrono::steady_clock::now();
  const VertebraResult v = makeVertebra(vo);
  PhantomFiles files;
  files.truth = vertebraTruthJson(vo, v, secondsSince(t0));
  files.truth["command"] = vertebraCommandLine(a, vo);
  files.volumes = {{"pre.nrrd", v.ct}};
  files.dicomSeries = {{"pre_dicom", v.ct}};
  writePhantomFiles(a.out, files);
  const auto size = v.ct->GetLargestPossibleRegion().GetSize();
  std::cout << "vertebra " << size[0] << " x " << size[1] << " x " << size[2] << " voxels of " << vo.spacingMm[0] << " x "
            << vo.spacingMm[1] << " x " << vo.spacingMm[2] << " mm; suggested tip " << v.suggestedTipMm[0] << ","
            << v.suggestedTipMm[1] << "," << v.suggestedTipMm[2] << " mm; results in " << a.out << "\n";
  return 0;
}

// --cell-size-mm against the grid and the block, before any work: a cell under a voxel cannot show in the CT
// (and 0.001 mm asked for 1.7e12 Voronoi seeds: "out of memory"), and one over the block's smallest edge
// leaves it no pores ("size_mm: the block has no sub-samples", naming another option).
void checkCellSize(const FoamOptions& fo) {
  const double voxelMm = *std::max_element(fo.spacingMm.begin(), fo.spacingMm.end());
  const double edgeMm = *std::min_element(fo.sizeMm.begin(), fo.sizeMm.end());
  if (!(fo.cellSizeMm >= voxelMm))
    throw std::invalid_argument("--cell-size-mm " + cementsph::scene::exactNumber(fo.cellSizeMm) +
                                ": a cell smaller than a CT voxel (" + cementsph::scene::exactNumber(voxelMm) +
                                " mm) cannot show in the CT: give " + cementsph::scene::exactNumber(voxelMm) + " mm or more");
  if (fo.cellSizeMm > edgeMm)
    throw std::invalid_argument("--cell-size-mm " + cementsph::scene::exactNumber(fo.cellSizeMm) +
                                ": a cell larger than the block's smallest edge (--size-mm, " +
                                cementsph::scene::exactNumber(edgeMm) + " mm) leaves it no pores: give at most " +
                                cementsph::scene::exactNumber(edgeMm) + " mm");
}

FoamOptions foamOptions(const PhantomArgs& a, const CLI::App& sub) {
  FoamOptions fo;
  if (a.sizeMm.size() == 1) fo.sizeMm = {a.sizeMm[0], a.sizeMm[0], a.sizeMm[0]};
  else if (a.sizeMm.size() == 3) fo.sizeMm = {a.sizeMm[0], a.sizeMm[1], a.sizeMm[2]};
  else if (!a.sizeMm.empty()) throw std::invalid_argument("--size-mm takes one value or three (x,y,z)");
  fo.cellSizeMm = a.cellSizeMm;
  checkCellSize(fo);
  if (sub.count("--strut-thickness-mm")) {
    if (sub.count("--porosity")) throw std::invalid_argument("give --porosity or --strut-thickness-mm, not both");
    fo.porosity.reset();
    fo.strutThicknessMm = a.strutThicknessMm;
  } else {
    fo.porosity = a.porosity;
  }
  fo.shellMm = a.shellMm;
  fo.airMarginMm = a.airMarginMm;
  fo.noiseHu = a.noiseHu;
  fo.seed = a.seed;
  return fo;
}

std::string foamCommandLine(const PhantomArgs& a, const FoamOptions& fo, const PostOptions& po) {
  std::ostringstream command;
  command << "cementsph phantom --out " << a.out << " --size-mm " << fo.sizeMm[0] << "," << fo.sizeMm[1] << ","
          << fo.sizeMm[2] << " --cell-size-mm " << fo.cellSizeMm;
  if (fo.porosity) command << " --porosity " << *fo.porosity;
  else command << " --strut-thickness-mm " << *fo.strutThicknessMm;
  command << " --shell-mm " << fo.shellMm << " --air-margin-mm " << fo.airMarginMm << " --noise-hu " << fo.noiseHu
          << " --seed " << fo.seed;
  if (a.noPost) command << " --no-post";
  else command << " --volume-ml " << po.volumeMl << " --viscosity-pa-s " << po.viscosityPaS;
  if (a.postDicom) command << " --post-dicom";
  return command.str();
}

void printFoamSummary(const PhantomArgs& a, const FoamOptions& fo, const FoamResult& foam, const PostResult& post) {
  const auto size = foam.ct->GetLargestPossibleRegion().GetSize();
  std::cout << "foam " << size[0] << " x " << size[1] << " x " << size[2] << " voxels, realised porosity "
            << foam.realisedPorosity << " (target " << (fo.porosity ? std::to_string(*fo.porosity) : "none")
            << ", band " << foam.bandMm << " mm)";
  if (!a.noPost)
    std::cout << "; tip " << post.tipMm[0] << "," << post.tipMm[1] << "," << post.tipMm[2] << " mm, cement "
              << post.cementVolumeMl << " ml in " << post.cementVoxels << " voxels";
  std::cout << "; results in " << a.out << "\n";
}

int runFoam(const PhantomArgs& a, const CLI::App& sub) {
  for (const char* option : kVariantOptions)
    if (sub.count(option)) throw std::invalid_argument(std::string(option) + " applies to --kind vertebra only");
  const FoamOptions fo = foamOptions(a, sub);
  PostOptions po;
  po.volumeMl = a.volumeMl;
  po.viscosityPaS = a.viscosityPaS;
  po.progress = !a.quiet;
  validateNamingTheOption([&] {
    fo.validate();
    po.validate();
  });
  if (a.threads < 0) throw std::invalid_argument("--threads must be >= 0");
  checkOutputPath(a.out);
  if (a.threads > 0) omp_set_num_threads(a.threads);

  const auto t0 = std::chrono::steady_clock::now();
  const FoamResult foam = makeFoam(fo);
  const double foamS = secondsSince(t0);
  if (!a.quiet)
    std::cerr << "foam: realised porosity " << foam.realisedPorosity << " (band " << foam.bandMm << " mm), " << foamS
              << " s\n";
  PhantomFiles files;
  files.truth["foam"] = foamTruthJson(fo, foam, foamS);
  files.truth["command"] = foamCommandLine(a, fo, po);
  files.volumes = {{"pre.nrrd", foam.ct}};
  PostResult post;
  if (!a.noPost) {
    const auto t1 = std::chrono::steady_clock::now();
    post = makePost(foam, fo, po);
    files.truth["misalignment"] = misalignmentTruthJson(post);
    files.truth["injection"] = injectionTruthJson(po, post, secondsSince(t1));
    files.volumes.push_back({"post.nrrd", post.ct});
    if (a.postDicom) files.dicomSeries = {{"post_dicom", post.ct}};
  }
  // Files: created only now; on failure the files this run wrote are removed.
  writePhantomFiles(a.out, files);
  printFoamSummary(a, fo, foam, post);
  return 0;
}

cementsph::app::CommandRunner setupPhantom(CLI::App& sub) {
  auto a = std::make_shared<PhantomArgs>();
  sub.add_option("--out", a->out, "Output directory (created; pre.nrrd, post.nrrd, truth.json replaced)")->required();
  sub.add_option("--size-mm", a->sizeMm, "Foam block edge(s) in mm: one value (cube) or x,y,z (default 30)")
      ->delimiter(',');
  sub.add_option("--cell-size-mm", a->cellSizeMm, "Voronoi cell size in mm (default 4)");
  sub.add_option("--porosity", a->porosity, "Target porosity of the block (default 0.8; the strut band is solved)");
  sub.add_option("--strut-thickness-mm", a->strutThicknessMm,
                 "Fixed strut band in mm instead of a target porosity (not with --porosity)");
  sub.add_option("--shell-mm", a->shellMm, "Plexiglass shell around the block in mm (default 5; 0: none)");
  sub.add_option("--air-margin-mm", a->airMarginMm, "Air around the shell in mm (default 2)");
  sub.add_option("--noise-hu", a->noiseHu, "Gaussian CT noise sigma in HU (default 20)");
  sub.add_option("--seed", a->seed, "Random seed (foam; noise; post noise uses seed + 1) (default 1)");
  sub.add_option("--volume-ml", a->volumeMl, "Injected volume in ml (default 1)");
  sub.add_option("--viscosity-pa-s", a->viscosityPaS, "Cement viscosity in Pa.s (default 100)");
  sub.add_flag("--no-post", a->noPost, "Only the pre-injection CT and truth.json");
  sub.add_flag("--post-dicom", a->postDicom, "Also write the post CT as a DICOM series in DIR/post_dicom");
  sub.add_option("--threads", a->threads, "OpenMP threads (0: the cores the load average leaves free)");
  sub.add_flag("--quiet", a->quiet, "No progress line");
  sub.add_option("--kind", a->kind, "foam (the paper's foam block, default) or vertebra (a clinical-resolution vertebra "
                                    "with cortex, canal and a basivertebral foramen: pre.nrrd, pre_dicom/, truth.json)");
  sub.add_option("--foramen-diameter-mm", a->foramenDiameterMm, "vertebra: the posterior-wall opening (default 3; 0: intact)");
  sub.add_option("--marrow-fat-radius-mm", a->marrowFatRadiusMm,
                 "vertebra: a sphere of marrow fat inside the body, radius 1 .. 6 mm (default 0: none)");
  sub.add_option("--disc-height-mm", a->discHeightMm,
                 "vertebra: disc spaces above and below the body, each this high, 4 mm up to what the 45 mm field "
                 "holds with the neighbours' end plates (8 mm) (default 0: none)");
  sub.add_option("--vein-radius-mm", a->veinRadiusMm,
                 "vertebra: a basivertebral vein out through the body's posterolateral wall, radius 1 .. 3 mm "
                 "(default 0: none)");
  return [a, &sub]() {
    if (a->kind == "vertebra") return runVertebra(*a, sub);
    if (a->kind != "foam") throw std::invalid_argument("--kind must be foam or vertebra (got " + a->kind + ")");
    return runFoam(*a, sub);
  };
}

} // namespace

CEMENTSPH_REGISTER_COMMAND(phantom_command, "phantom",
                           "Make a synthetic open-cell foam CT (fat-filled pores, optional shell, noise) and its "
                           "post-injection CT with a known misalignment; truth.json",
                           setupPhantom)
