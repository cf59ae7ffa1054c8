// cementsph phantom: a synthetic open-cell foam CT and its post-injection CT (issue 4; Basafa et al. 2013,
// "Foam Block Tests"). Writes DIR/pre.nrrd, DIR/post.nrrd (unless --no-post; --post-dicom adds DIR/post_dicom/)
// and DIR/truth.json (every key names its unit). Modules/Simulation/Phantom; docs/phantom-figures.md.
#include "CommandRegistry.h"
#include "OutputFiles.h"

#include "cementsph/imaging/VolumeIO.h"
#include "cementsph/phantom/FoamPhantom.h"
#include "cementsph/phantom/VertebraPhantom.h"

#include <nlohmann/json.hpp>

#include <omp.h>

#include <chrono>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>
#include <stdexcept>

namespace {

namespace fs = std::filesystem;

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
};

double secondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// The vertebra: pre.nrrd, the same as a DICOM series in pre_dicom/, and truth.json (geometry, plan, command).
int runVertebra(const PhantomArgs& a, bool noiseGiven) {
  using namespace cementsph::phantom;
  VertebraOptions vo;
  if (noiseGiven) vo.noiseHu = a.noiseHu; // else the vertebra's own default (the foam's is higher)
  vo.seed = a.seed;
  vo.foramenDiameterMm = a.foramenDiameterMm;
  try {
    vo.validate();
  } catch (const std::invalid_argument& e) {
    std::string m = e.what();
    for (auto& c : m)
      if (c == '_') c = '-';
    throw std::invalid_argument("--" + m);
  }
  const fs::path out(a.out);
  if (fs::exists(out) && !fs::is_directory(out)) throw std::runtime_error(a.out + ": exists and is not a directory");
  const auto t0 = std::chrono::steady_clock::now();
  const VertebraResult v = makeVertebra(vo);
  nlohmann::json truth;
  truth["kind"] = "vertebra";
  truth["vertebra"] = v.toJson();
  truth["vertebra"]["spacing_mm"] = vo.spacingMm;
  truth["vertebra"]["field_mm"] = vo.fieldMm;
  truth["vertebra"]["cortical_hu"] = vo.corticalHu;
  truth["vertebra"]["trabecular_centre_hu"] = vo.trabecularCentreHu;
  truth["vertebra"]["trabecular_rim_hu"] = vo.trabecularRimHu;
  truth["vertebra"]["canal_hu"] = vo.canalHu;
  truth["vertebra"]["soft_tissue_hu"] = vo.softTissueHu;
  truth["vertebra"]["foramen_diameter_mm"] = vo.foramenDiameterMm;
  truth["vertebra"]["noise_hu"] = vo.noiseHu;
  truth["vertebra"]["seed"] = vo.seed;
  truth["vertebra"]["generation_time_s"] = secondsSince(t0);
  truth["injection"] = {{"tip_mm", v.suggestedTipMm},     {"direction", v.suggestedDirection},
                        {"volume_ml", 4.0},               {"flow_rate_ml_per_s", 0.05},
                        {"viscosity_pa_s", 100.0},        {"note", "a transpedicular plan for the demo"}};
  std::ostringstream command;
  command << "cementsph phantom --kind vertebra --out " << a.out << " --noise-hu " << vo.noiseHu << " --seed " << vo.seed
          << " --foramen-diameter-mm " << vo.foramenDiameterMm;
  truth["command"] = command.str();
  const bool created = !fs::exists(out);
  fs::create_directories(out);
  std::vector<fs::path> written;
  try {
    cementsph::imaging::writeVolume(v.ct, (out / "pre.nrrd").string());
    written.push_back(out / "pre.nrrd");
    fs::remove_all(out / "pre_dicom");
    written.push_back(out / "pre_dicom");
    cementsph::imaging::writeDicomSeries(v.ct, (out / "pre_dicom").string(), -1024.0);
    cementsph::app::writeFileAtomically(out / "truth.json", truth.dump(2) + "\n");
  } catch (...) {
    std::error_code ec;
    for (const auto& p : written) fs::remove_all(p, ec);
    if (created) fs::remove(out, ec);
    throw;
  }
  const auto size = v.ct->GetLargestPossibleRegion().GetSize();
  std::cout << "vertebra " << size[0] << " x " << size[1] << " x " << size[2] << " voxels of " << vo.spacingMm[0] << " x "
            << vo.spacingMm[1] << " x " << vo.spacingMm[2] << " mm; suggested tip " << v.suggestedTipMm[0] << ","
            << v.suggestedTipMm[1] << "," << v.suggestedTipMm[2] << " mm; results in " << a.out << "\n";
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
  return [a, &sub]() {
    using namespace cementsph::phantom;
    if (a->kind == "vertebra") return runVertebra(*a, sub.count("--noise-hu") > 0);
    if (a->kind != "foam") throw std::invalid_argument("--kind must be foam or vertebra (got " + a->kind + ")");
    FoamOptions fo;
    if (a->sizeMm.size() == 1) fo.sizeMm = {a->sizeMm[0], a->sizeMm[0], a->sizeMm[0]};
    else if (a->sizeMm.size() == 3) fo.sizeMm = {a->sizeMm[0], a->sizeMm[1], a->sizeMm[2]};
    else if (!a->sizeMm.empty()) throw std::invalid_argument("--size-mm takes one value or three (x,y,z)");
    fo.cellSizeMm = a->cellSizeMm;
    if (sub.count("--strut-thickness-mm")) {
      if (sub.count("--porosity")) throw std::invalid_argument("give --porosity or --strut-thickness-mm, not both");
      fo.porosity.reset();
      fo.strutThicknessMm = a->strutThicknessMm;
    } else {
      fo.porosity = a->porosity;
    }
    fo.shellMm = a->shellMm;
    fo.airMarginMm = a->airMarginMm;
    fo.noiseHu = a->noiseHu;
    fo.seed = a->seed;
    PostOptions po;
    po.volumeMl = a->volumeMl;
    po.viscosityPaS = a->viscosityPaS;
    po.progress = !a->quiet;
    try {
      fo.validate();
      po.validate();
    } catch (const std::invalid_argument& e) {
      // Name the command-line option, not the key.
      std::string m = e.what();
      for (auto& c : m)
        if (c == '_') c = '-';
      throw std::invalid_argument("--" + m);
    }
    if (a->threads < 0) throw std::invalid_argument("--threads must be >= 0");
    const fs::path out(a->out);
    if (fs::exists(out) && !fs::is_directory(out)) throw std::runtime_error(a->out + ": exists and is not a directory");
    if (a->threads > 0) omp_set_num_threads(a->threads);

    const auto t0 = std::chrono::steady_clock::now();
    const FoamResult foam = makeFoam(fo);
    const double foamS = secondsSince(t0);
    if (!a->quiet)
      std::cerr << "foam: realised porosity " << foam.realisedPorosity << " (band " << foam.bandMm << " mm), "
                << foamS << " s\n";
    nlohmann::json truth;
    truth["foam"] = foam.toJson();
    truth["foam"]["size_mm"] = fo.sizeMm;
    truth["foam"]["spacing_mm"] = fo.spacingMm;
    truth["foam"]["cell_size_mm"] = fo.cellSizeMm;
    truth["foam"]["target_porosity"] = fo.porosity ? nlohmann::json(*fo.porosity) : nlohmann::json(nullptr);
    truth["foam"]["shell_mm"] = fo.shellMm;
    truth["foam"]["air_margin_mm"] = fo.airMarginMm;
    truth["foam"]["air_hu"] = fo.airHu;
    truth["foam"]["noise_hu"] = fo.noiseHu;
    truth["foam"]["seed"] = fo.seed;
    truth["foam"]["post_noise_seed"] = fo.seed + 1;
    truth["foam"]["supersample"] = fo.supersample;
    truth["foam"]["strut_hu"] = fo.strutHu;
    truth["foam"]["fat_hu"] = fo.fatHu;
    truth["foam"]["shell_hu"] = fo.shellHu;
    const auto size = foam.ct->GetLargestPossibleRegion().GetSize();
    truth["foam"]["voxels"] = {size[0], size[1], size[2]};
    truth["foam"]["generation_time_s"] = foamS;
    // The command that makes these files again (generation times aside), with every option spelled out.
    std::ostringstream command;
    command << "cementsph phantom --out " << a->out << " --size-mm " << fo.sizeMm[0] << "," << fo.sizeMm[1] << ","
            << fo.sizeMm[2] << " --cell-size-mm " << fo.cellSizeMm;
    if (fo.porosity) command << " --porosity " << *fo.porosity;
    else command << " --strut-thickness-mm " << *fo.strutThicknessMm;
    command << " --shell-mm " << fo.shellMm << " --air-margin-mm " << fo.airMarginMm << " --noise-hu " << fo.noiseHu
            << " --seed " << fo.seed;
    if (a->noPost) command << " --no-post";
    else command << " --volume-ml " << po.volumeMl << " --viscosity-pa-s " << po.viscosityPaS;
    if (a->postDicom) command << " --post-dicom";
    truth["command"] = command.str();

    PostResult post;
    if (!a->noPost) {
      const auto t1 = std::chrono::steady_clock::now();
      post = makePost(foam, fo, po);
      const double postS = secondsSince(t1);
      const auto& p = post.misalignment;
      truth["misalignment"] = {
          {"convention", "post(y) = pre_cemented(A^-1 y); y = M (x - centre_mm) + centre_mm + translation_mm, "
                         "M = Rz Ry Rx S; a point x of pre.nrrd appears at y in post.nrrd"},
          {"rotation_deg", p.rotationDeg},
          {"scale", p.scale},
          {"translation_mm", p.translationMm},
          {"centre_mm", p.centreMm},
          {"matrix", p.matrix()}};
      truth["injection"] = {{"requested_tip_mm", post.requestedTipMm},
                            {"tip_mm", post.tipMm},
                            {"volume_ml", po.volumeMl},
                            {"viscosity_pa_s", po.viscosityPaS},
                            {"flow_rate_ml_per_s", po.flowRateMlPerS},
                            {"direction", {0, 0, 1}},
                            {"cement_hu", po.cementHu},
                            {"cement_threshold_rho_over_rho0", po.cementThreshold},
                            {"cement_voxels", post.cementVoxels},
                            {"cement_volume_ml", post.cementVolumeMl},
                            {"volume_injected_ml", post.injectionMetrics.value("volume_injected_ml", 0.0)},
                            {"cement_points", post.injectionMetrics.at("cement_points")},
                            {"steps", post.injectionMetrics.at("steps")},
                            {"numerics", toJson(po.numerics)},
                            {"scene", post.scene},
                            {"generation_time_s", postS}};
    }

    // Files: created only now; on failure the files this run wrote are removed.
    const bool created = !fs::exists(out);
    fs::create_directories(out);
    std::vector<fs::path> written;
    try {
      cementsph::imaging::writeVolume(foam.ct, (out / "pre.nrrd").string());
      written.push_back(out / "pre.nrrd");
      if (!a->noPost) {
        cementsph::imaging::writeVolume(post.ct, (out / "post.nrrd").string());
        written.push_back(out / "post.nrrd");
        if (a->postDicom) {
          fs::remove_all(out / "post_dicom");
          written.push_back(out / "post_dicom");
          cementsph::imaging::writeDicomSeries(post.ct, (out / "post_dicom").string(), -1024.0);
        }
      }
      cementsph::app::writeFileAtomically(out / "truth.json", truth.dump(2) + "\n");
    } catch (...) {
      std::error_code ec;
      for (const auto& p : written) fs::remove_all(p, ec);
      if (created) fs::remove(out, ec);
      throw;
    }
    std::cout << "foam " << size[0] << " x " << size[1] << " x " << size[2] << " voxels, realised porosity "
              << foam.realisedPorosity << " (target " << (fo.porosity ? std::to_string(*fo.porosity) : "none")
              << ", band " << foam.bandMm << " mm)";
    if (!a->noPost)
      std::cout << "; tip " << post.tipMm[0] << "," << post.tipMm[1] << "," << post.tipMm[2] << " mm, cement "
                << post.cementVolumeMl << " ml in " << post.cementVoxels << " voxels";
    std::cout << "; results in " << a->out << "\n";
    return 0;
  };
}

} // namespace

CEMENTSPH_REGISTER_COMMAND(phantom_command, "phantom",
                           "Make a synthetic open-cell foam CT (fat-filled pores, optional shell, noise) and its "
                           "post-injection CT with a known misalignment; truth.json",
                           setupPhantom)
