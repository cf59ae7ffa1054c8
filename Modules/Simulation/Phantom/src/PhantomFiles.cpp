#include "cementsph/phantom/PhantomFiles.h"

#include "cementsph/imaging/AtomicFile.h"
#include "cementsph/imaging/VolumeIO.h"
#include "cementsph/phantom/PhantomNumerics.h"

#include <fstream>
#include <stdexcept>

namespace cementsph::phantom {

namespace fs = std::filesystem;
using nlohmann::json;

json foamTruthJson(const FoamOptions& fo, const FoamResult& foam, double generationS) {
  json j = foam.toJson();
  j["size_mm"] = fo.sizeMm;
  j["spacing_mm"] = fo.spacingMm;
  j["cell_size_mm"] = fo.cellSizeMm;
  j["target_porosity"] = fo.porosity ? json(*fo.porosity) : json(nullptr);
  j["shell_mm"] = fo.shellMm;
  j["air_margin_mm"] = fo.airMarginMm;
  j["air_hu"] = fo.airHu;
  j["noise_hu"] = fo.noiseHu;
  j["seed"] = fo.seed;
  j["post_noise_seed"] = fo.seed + 1;
  j["supersample"] = fo.supersample;
  j["strut_hu"] = fo.strutHu;
  j["fat_hu"] = fo.fatHu;
  j["shell_hu"] = fo.shellHu;
  const auto size = foam.ct->GetLargestPossibleRegion().GetSize();
  j["voxels"] = {size[0], size[1], size[2]};
  j["generation_time_s"] = generationS;
  return j;
}

json misalignmentTruthJson(const PostResult& post) {
  const auto& p = post.misalignment;
  return {{"convention", "post(y) = pre_cemented(A^-1 y); y = M (x - centre_mm) + centre_mm + translation_mm, "
                         "M = Rz Ry Rx S; a point x of pre.nrrd appears at y in post.nrrd"},
          {"rotation_deg", p.rotationDeg},
          {"scale", p.scale},
          {"translation_mm", p.translationMm},
          {"centre_mm", p.centreMm},
          {"matrix", p.matrix()}};
}

json injectionTruthJson(const PostOptions& po, const PostResult& post, double generationS) {
  return {{"requested_tip_mm", post.requestedTipMm},
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
          {"generation_time_s", generationS}};
}

json vertebraTruthJson(const VertebraOptions& vo, const VertebraResult& v, double generationS) {
  json truth;
  truth["kind"] = "vertebra";
  json& j = truth["vertebra"];
  j = v.toJson();
  j["spacing_mm"] = vo.spacingMm;
  j["field_mm"] = vo.fieldMm;
  j["cortical_hu"] = vo.corticalHu;
  j["trabecular_centre_hu"] = vo.trabecularCentreHu;
  j["trabecular_rim_hu"] = vo.trabecularRimHu;
  j["canal_hu"] = vo.canalHu;
  j["soft_tissue_hu"] = vo.softTissueHu;
  j["foramen_diameter_mm"] = vo.foramenDiameterMm;
  j["noise_hu"] = vo.noiseHu;
  j["seed"] = vo.seed;
  j["generation_time_s"] = generationS;
  truth["injection"] = {{"tip_mm", v.suggestedTipMm},     {"direction", v.suggestedDirection},
                        {"volume_ml", 4.0},               {"flow_rate_ml_per_s", 0.05},
                        {"viscosity_pa_s", 100.0},        {"note", "a transpedicular plan for the demo"}};
  return truth;
}

PhantomInjectionPlan readInjectionPlan(const fs::path& phantomFolder) {
  const fs::path path = phantomFolder / "truth.json";
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path.string() + ": cannot read the phantom's truth.json (is --data-dir right?)");
  const json truth = json::parse(in, nullptr, /*allow_exceptions=*/false);
  if (truth.is_discarded())
    throw std::runtime_error(path.string() + ": not JSON; make the phantom again (cementsph phantom)");
  if (!truth.contains("injection") || !truth["injection"].is_object())
    throw std::runtime_error(path.string() + ": no \"injection\" object (a phantom with no planned injection)");
  const json& j = truth["injection"];
  auto number = [&](const char* key) {
    if (!j.contains(key) || !j[key].is_number())
      throw std::runtime_error(path.string() + ": injection." + key + " is missing or not a number");
    return j[key].get<double>();
  };
  auto vector3 = [&](const char* key) {
    const json& v = j[key];
    if (!v.is_array() || v.size() != 3 || !v[0].is_number() || !v[1].is_number() || !v[2].is_number())
      throw std::runtime_error(path.string() + ": injection." + key + " must be [x, y, z]");
    return std::array<double, 3>{v[0].get<double>(), v[1].get<double>(), v[2].get<double>()};
  };
  PhantomInjectionPlan plan;
  if (!j.contains("tip_mm")) throw std::runtime_error(path.string() + ": injection.tip_mm is missing");
  plan.tipMm = vector3("tip_mm");
  if (j.contains("direction")) plan.direction = vector3("direction");
  plan.volumeMl = number("volume_ml");
  plan.flowRateMlPerS = number("flow_rate_ml_per_s");
  plan.viscosityPaS = number("viscosity_pa_s");
  return plan;
}

void writePhantomFiles(const fs::path& out, const PhantomFiles& files) {
  const bool created = !fs::exists(out);
  fs::create_directories(out);
  std::vector<fs::path> written;
  try {
    for (const auto& v : files.volumes) {
      imaging::writeVolume(v.ct, (out / v.name).string());
      written.push_back(out / v.name);
    }
    for (const auto& d : files.dicomSeries) {
      fs::remove_all(out / d.name);
      written.push_back(out / d.name);
      imaging::writeDicomSeries(d.ct, (out / d.name).string(), -1024.0);
    }
    imaging::writeTextAtomically((out / "truth.json").string(), files.truth.dump(2) + "\n");
  } catch (...) {
    std::error_code ec;
    for (const auto& p : written) fs::remove_all(p, ec);
    if (created) fs::remove(out, ec);
    throw;
  }
}

} // namespace cementsph::phantom
