#include "cementsph/planning/InjectionPlanner.h"

#include "cementsph/parallel/CaseFarm.h"
#include "cementsph/planning/PlanTrajectory.h"
#include "cementsph/scene/AxisAlignedCT.h"
#include "cementsph/imaging/ItkVtkBridge.h"
#include "cementsph/scene/InjectionRunner.h"
#include "vtkSPHInjectionFilter.h"

#include <nlopt.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <stdexcept>
#include <tuple>
#include <utility>

namespace cementsph::planning {

namespace {
constexpr double kPi = 3.14159265358979323846;

std::string mm(const Eigen::Vector3d& p) {
  std::ostringstream s;
  s << std::setprecision(6) << "(" << p.x() << ", " << p.y() << ", " << p.z() << ") mm";
  return s.str();
}

bool insideCt(const imaging::ImageType* ct, const Eigen::Vector3d& pMm) {
  imaging::ImageType::PointType p;
  for (unsigned a = 0; a < 3; ++a) p[a] = pMm[int(a)];
  imaging::ImageType::IndexType i;
  return ct->TransformPhysicalPointToIndex(p, i);
}

const char* stopText(nlopt_result r) {
  switch (r) {
  case NLOPT_SUCCESS: return "success";
  case NLOPT_STOPVAL_REACHED: return "objective reached the stop value";
  case NLOPT_FTOL_REACHED: return "objective converged (ftol)";
  case NLOPT_XTOL_REACHED: return "plan converged: depth within 0.25 mm and volume within 0.05 ml (xtol)";
  case NLOPT_MAXEVAL_REACHED: return "the evaluation budget ran out (max evaluations)";
  case NLOPT_MAXTIME_REACHED: return "the time budget ran out";
  case NLOPT_ROUNDOFF_LIMITED: return "round-off limited";
  case NLOPT_FORCED_STOP: return "stopped";
  default: return "NLopt failed";
  }
}

struct Context {
  vtkSPHInjectionFilter* injection; // the start's filter on the CT, without image outputs
  const PlanRequest* request;
  int start;
  std::vector<PlanEvaluation>* evaluations;
};

double evaluate(unsigned, const double* x, double*, void* data) {
  auto* c = static_cast<Context*>(data);
  const PlanRequest& r = *c->request;
  const Eigen::Vector3d axis = r.direction.normalized();
  PlanEvaluation e;
  e.index = int(c->evaluations->size());
  e.start = c->start;
  e.depthMm = x[0];
  e.volumeMl = x[1];
  e.tipMm = r.entryMm + x[0] * axis;
  if (r.secondTip) {
    e.secondDepthMm = r.minDepthMm + x[2] * (x[0] - r.minDepthMm);
    // Less than half a millimetre back is the same outlet: one tip.
    e.secondTip = x[0] - e.secondDepthMm >= 0.5;
    if (e.secondTip) {
      e.secondVolumeMl = x[3] * x[1];
      e.secondTipMm = r.entryMm + e.secondDepthMm * axis;
    } else {
      e.secondDepthMm = 0;
    }
  }
  try {
    scene::SceneConfig s = r.scene;
    s.tipMm = e.tipMm;
    s.direction = axis;
    s.explicitKeys.insert("direction"); // the trajectory is given, whatever its value (a vertebra needs one)
    s.volumeMl = x[1];
    s.snapshotIntervalS = 1e9;
    if (e.secondTip) {
      s.secondTipWithdrawalMm = e.depthMm - e.secondDepthMm;
      s.secondTipVolumeMl = e.secondVolumeMl;
    }
    // Through vtkSPHInjectionFilter, as runBestPlan and inject run, but without its image outputs: the simulated
    // CT and label map pasted onto the whole input grid are a pass over every voxel of the scan per injection
    // (tens of millions on a clinical CT) that an evaluation, which reads only the summary and the cement
    // points, would pay for nothing. The same runInjection underneath, so the driver's figures.
    c->injection->SetScene(s);
    c->injection->Update();
    c->injection->RethrowIfFailed();
    const scene::InjectionRunResult& run = *c->injection->GetResult();
    e.coverage = targetCoverage(run.particles, r.targetCentreMm, r.targetRadiusMm);
    e.syringeMpa = run.summary.maxInjectionPressurePa * 1e-6;
    e.leakageMl = run.summary.leakageVolumeMl;
    e.withinLimits = e.syringeMpa <= r.maxSyringeMpa && e.leakageMl <= r.maxLeakageMl;
    e.objective = planObjective(r, e.coverage, x[1], e.syringeMpa, e.leakageMl);
    // Cement at the scan's or the region's edge: the injection is not fully seen, so the plan is outside its limits.
    for (const std::string& w : run.summary.warnings)
      if (w.find("reached the edge") != std::string::npos) {
        e.withinLimits = false;
        e.objective -= 5.0;
        e.warnings.push_back(w);
      }
  } catch (const std::exception& ex) {
    e.failure = ex.what();
    e.objective = -1.0;
  }
  c->evaluations->push_back(e);
  return e.objective;
}

// Where start s of K begins: its share of the depth range, at its middle, and the largest volume.
std::pair<double, double> startPoint(const PlanRequest& r, int s) {
  return {r.minDepthMm + (s + 0.5) * (r.maxDepthMm - r.minDepthMm) / r.starts, r.maxVolumeMl};
}

// One start's local search: its evaluations (numbered within the start) and NLopt's stop reason, as JSON
// (the bytes a worker rank sends back; doubles read back to the same bits).
nlohmann::json runStart(const imaging::ImageType* ct, const PlanRequest& r, int start) {
  std::vector<PlanEvaluation> evaluations;
  auto injection = vtkSmartPointer<vtkSPHInjectionFilter>::New();
  injection->SetInputDataObject(0, imaging::toVtk(ct)); // copied once per start, not once per evaluation
  injection->ProduceImageOutputsOff();
  Context context{injection, &r, start, &evaluations};
  const unsigned n = unsigned(r.parameters());
  nlopt_opt opt = nlopt_create(NLOPT_LN_BOBYQA, n);
  // Depth and volume; with a second tip, its place t between the shallowest depth and the first tip, and
  // its share s of the volume (InjectionPlanner.h).
  const double lower[4] = {r.minDepthMm, r.minVolumeMl, 0.0, 0.2}, upper[4] = {r.maxDepthMm, r.maxVolumeMl, 0.9, 0.8};
  nlopt_set_lower_bounds(opt, lower);
  nlopt_set_upper_bounds(opt, upper);
  nlopt_set_max_objective(opt, evaluate, &context);
  const double xtol[4] = {0.25, 0.05, 0.02, 0.02};
  nlopt_set_xtol_abs(opt, xtol);
  nlopt_set_maxeval(opt, r.maxEvaluations / r.starts);
  const double step[4] = {std::max(0.5, 0.25 * (r.maxDepthMm - r.minDepthMm) / r.starts),
                          std::max(0.05, 0.25 * (r.maxVolumeMl - r.minVolumeMl)), 0.2, 0.15};
  nlopt_set_initial_step(opt, step);
  const auto [depth, volume] = startPoint(r, start);
  double x[4] = {depth, volume, 0.5, 0.5};
  double value = 0;
  const nlopt_result code = nlopt_optimize(opt, x, &value);
  nlopt_destroy(opt);
  nlohmann::json out{{"stop_reason", stopText(code)}, {"evaluations", nlohmann::json::array()}};
  for (const auto& e : evaluations) out["evaluations"].push_back(e.toJson());
  return out;
}

PlanEvaluation evaluationFromJson(const nlohmann::json& j) {
  PlanEvaluation e;
  e.index = j.at("index").get<int>();
  e.start = j.at("start").get<int>();
  e.depthMm = j.at("depth_mm").get<double>();
  e.volumeMl = j.at("volume_ml").get<double>();
  const auto& tip = j.at("tip_mm");
  e.tipMm = Eigen::Vector3d(tip[0].get<double>(), tip[1].get<double>(), tip[2].get<double>());
  e.coverage = j.at("coverage").get<double>();
  e.syringeMpa = j.at("max_syringe_pressure_mpa").get<double>();
  e.leakageMl = j.at("leakage_volume_ml").get<double>();
  e.objective = j.at("objective").get<double>();
  e.withinLimits = j.at("within_limits").get<bool>();
  e.secondTip = !j.at("second_tip_mm").is_null();
  if (e.secondTip) {
    e.secondDepthMm = j.at("second_tip_depth_mm").get<double>();
    e.secondVolumeMl = j.at("second_tip_volume_ml").get<double>();
    const auto& second = j.at("second_tip_mm");
    e.secondTipMm = Eigen::Vector3d(second[0].get<double>(), second[1].get<double>(), second[2].get<double>());
  }
  e.failure = j.at("failure").is_null() ? std::string() : j.at("failure").get<std::string>();
  e.warnings = j.at("warnings").get<std::vector<std::string>>();
  e.volumeTrim = j.at("volume_trim").get<bool>();
  return e;
}

// The volume trim (InjectionPlanner.h): at the search's best depth, bisect the volume for the smallest whose
// coverage is within the tolerance of the best's and which keeps within the limits. Runs on the coordinator.
void trimVolume(const imaging::ImageType* ct, const PlanRequest& r, PlanResult& result,
                const std::function<void(const PlanEvaluation&)>& onEvaluation) {
  const PlanEvaluation found = result.best;
  result.searchBest = found;
  if (!(r.trimCoverageTolerance > 0) || r.secondTip || !found.failure.empty() || !found.withinLimits) return;
  auto injection = vtkSmartPointer<vtkSPHInjectionFilter>::New();
  injection->SetInputDataObject(0, imaging::toVtk(ct));
  injection->ProduceImageOutputsOff();
  std::vector<PlanEvaluation> trims;
  Context context{injection, &r, found.start, &trims};
  const double wanted = found.coverage - r.trimCoverageTolerance;
  // Runs the injection at the best depth; when it keeps the coverage and the limits it is the smallest so far.
  auto enough = [&](double volumeMl) {
    const double x[2] = {found.depthMm, volumeMl};
    evaluate(2, x, nullptr, &context);
    PlanEvaluation& e = trims.back();
    e.volumeTrim = true;
    e.index = int(result.evaluations.size());
    result.evaluations.push_back(e);
    if (onEvaluation) onEvaluation(e);
    const bool keeps = e.failure.empty() && e.withinLimits && e.coverage >= wanted;
    if (keeps) result.best = e;
    return keeps;
  };
  double low = r.minVolumeMl, high = found.volumeMl;
  constexpr double kVolumeResolutionMl = 0.05; // BOBYQA's volume xtol
  if (high - low > kVolumeResolutionMl && enough(low)) high = low;
  while (high - low > kVolumeResolutionMl) {
    const double middle = 0.5 * (low + high);
    if (enough(middle)) high = middle;
    else low = middle;
  }
}
} // namespace

void PlanRequest::validate(const imaging::ImageType* ct) const {
  if (!ct) throw std::invalid_argument("plan: no CT");
  if (!(direction.norm() > 0) || !direction.allFinite()) throw std::invalid_argument("--direction must be a non-zero vector");
  if (!entryMm.allFinite() || !insideCt(ct, entryMm))
    throw std::invalid_argument("--entry-mm " + mm(entryMm) + " lies outside the CT");
  if (!(minDepthMm >= 0 && maxDepthMm > minDepthMm && maxDepthMm < 1000))
    throw std::invalid_argument("--min-depth-mm and --max-depth-mm must satisfy 0 <= min < max < 1000 mm");
  const Eigen::Vector3d deepest = entryMm + maxDepthMm * direction.normalized();
  if (!insideCt(ct, deepest))
    throw std::invalid_argument("the trajectory leaves the CT: the deepest tip " + mm(deepest) +
                                " (--max-depth-mm along --direction) is outside it");
  if (!(targetRadiusMm > 0 && targetRadiusMm < 100)) throw std::invalid_argument("--target-radius-mm must be in (0, 100) mm");
  if (!targetCentreMm.allFinite() || !insideCt(ct, targetCentreMm))
    throw std::invalid_argument("--target-mm " + mm(targetCentreMm) + " lies outside the CT");
  if (!(minVolumeMl > 0 && maxVolumeMl >= minVolumeMl && maxVolumeMl <= 50))
    throw std::invalid_argument("--min-volume-ml and --max-volume-ml must satisfy 0 < min <= max <= 50 ml");
  if (!(maxSyringeMpa > 0 && maxSyringeMpa < 100)) throw std::invalid_argument("--max-syringe-mpa must be in (0, 100) MPa");
  if (!(maxLeakageMl >= 0 && maxLeakageMl < 50)) throw std::invalid_argument("--max-leakage-ml must be in [0, 50) ml");
  if (starts < 1 || starts > 64) throw std::invalid_argument("--starts must be 1 .. 64");
  if (!(trimCoverageTolerance >= 0 && trimCoverageTolerance <= 0.5))
    throw std::invalid_argument("the volume trim's coverage tolerance must be in [0, 0.5] (a fraction of the target)");
  const int perStart = 2 * parameters() + 2; // BOBYQA's 2n + 1 to begin with, and one more
  if (maxEvaluations > 10000 || maxEvaluations / starts < perStart)
    throw std::invalid_argument("--max-evaluations " + std::to_string(maxEvaluations) + " with --starts " +
                                std::to_string(starts) + ": at most 10000, and each start needs at least " +
                                std::to_string(perStart) + " injections (BOBYQA's first 2n + 1 and one more, n = " +
                                std::to_string(parameters()) + "), " + std::to_string(perStart * starts) +
                                " for these starts: raise --max-evaluations or lower --starts");
}

void requireASafeTrajectory(const anatomy::TrajectoryCheck& check, const PlanRequest& r) {
  if (check.refused() && !r.allowCanalCrossing)
    throw std::invalid_argument("plan: " + check.message +
                                ": a cannula must not pass the spinal canal; move --entry-mm lateral to the canal "
                                "(through the pedicle), or pass --allow-canal-crossing if the path is deliberate");
}

double targetCoverage(vtkPolyData* points, const Eigen::Vector3d& centre, double radius) {
  if (!points) return 0.0;
  auto* volume = points->GetPointData()->GetArray("cement_volume_mm3");
  auto* fill = points->GetPointData()->GetArray("fill_fraction");
  auto* porosity = points->GetPointData()->GetArray("porosity");
  if (!volume || !fill || !porosity) throw std::invalid_argument("target coverage: the injection has no cement voxels");
  double covered = 0;
  for (vtkIdType i = 0; i < points->GetNumberOfPoints(); ++i) {
    const double* x = points->GetPoint(i);
    if ((Eigen::Vector3d(x[0], x[1], x[2]) - centre).norm() > radius) continue;
    const double f = fill->GetTuple1(i), phi = porosity->GetTuple1(i);
    if (f >= 0.5 && phi > 0) covered += volume->GetTuple1(i) / (f * phi); // the voxel's volume
  }
  return std::min(1.0, covered / (4.0 / 3.0 * kPi * radius * radius * radius));
}

PlanResult planInjection(const imaging::ImageType* ct, const PlanRequest& r,
                         const std::function<void(const PlanEvaluation&)>& onEvaluation, parallel::CaseFarm* farm) {
  r.validate(ct);
  PlanResult result;
  result.mpiRanks = farm ? farm->ranks() : 1;
  result.trajectory = r.trajectoryCheck ? *r.trajectoryCheck : checkPlanTrajectory(ct, r);
  requireASafeTrajectory(result.trajectory, r);
  // An oblique CT is aligned once here, not once per injection (runInjection resamples the whole scan each time
  // it is given one: the oblique plan took 82 s against 11 s). The same grid the runs would make, so the
  // same evaluations. With a label map the runs keep the CT they check it against (its own grid).
  const imaging::ImageType::ConstPointer aligned =
      r.scene.labelsPath.empty() ? scene::axisAligned(ct) : imaging::ImageType::ConstPointer(ct);
  auto work = [&](std::size_t start) { return runStart(aligned.GetPointer(), r, int(start)).dump(); };
  auto onOutcome = [&](const parallel::CaseOutcome& outcome) {
    PlanStart start;
    start.index = int(outcome.index);
    std::tie(start.depthMm, start.volumeMl) = startPoint(r, start.index);
    start.rank = outcome.rank;
    if (!outcome.ok) {
      start.stopReason = "failed: " + outcome.payload;
    } else {
      const nlohmann::json j = nlohmann::json::parse(outcome.payload);
      start.stopReason = j.at("stop_reason").get<std::string>();
      for (const auto& ej : j.at("evaluations")) {
        PlanEvaluation e = evaluationFromJson(ej);
        e.index = int(result.evaluations.size());
        result.evaluations.push_back(e);
        if (result.evaluations.size() == 1 || e.objective > result.best.objective) result.best = e;
        ++start.evaluations;
        if (onEvaluation) onEvaluation(e);
      }
    }
    result.starts.push_back(start);
  };
  if (farm) farm->run(std::size_t(r.starts), work, onOutcome);
  else parallel::runCasesHere(std::size_t(r.starts), work, onOutcome);
  if (farm && !farm->coordinator()) return result;
  if (result.evaluations.empty()) {
    std::string why;
    for (const auto& s : result.starts) why += (why.empty() ? "" : "; ") + s.stopReason;
    throw std::runtime_error("plan: no start made an evaluation (" + why + ")");
  }
  result.stopReason = "start " + std::to_string(result.best.start) + " (the best plan's): " +
                      result.starts[std::size_t(result.best.start)].stopReason;
  trimVolume(aligned.GetPointer(), r, result, onEvaluation);
  return result;
}

double planObjective(const PlanRequest& r, double coverage, double volumeMl, double syringeMpa, double leakageMl) {
  const double penalty = std::max(0.0, syringeMpa / r.maxSyringeMpa - 1.0) + std::max(0.0, leakageMl - r.maxLeakageMl) / 0.1;
  return coverage - r.volumeCostPerMl * volumeMl - 5.0 * penalty;
}

nlohmann::json PlanStart::toJson() const {
  return {{"index", index},       {"depth_mm", depthMm},         {"volume_ml", volumeMl},
          {"rank", rank},         {"stop_reason", stopReason},   {"evaluations", evaluations}};
}

nlohmann::json PlanEvaluation::toJson() const {
  return {{"index", index},
          {"start", start},
          {"depth_mm", depthMm},
          {"volume_ml", volumeMl},
          {"tip_mm", {tipMm.x(), tipMm.y(), tipMm.z()}},
          {"coverage", coverage},
          {"max_syringe_pressure_mpa", syringeMpa},
          {"leakage_volume_ml", leakageMl},
          {"objective", objective},
          {"within_limits", withinLimits},
          {"second_tip_depth_mm", secondTip ? nlohmann::json(secondDepthMm) : nlohmann::json(nullptr)},
          {"second_tip_volume_ml", secondTip ? nlohmann::json(secondVolumeMl) : nlohmann::json(nullptr)},
          {"second_tip_mm", secondTip ? nlohmann::json{secondTipMm.x(), secondTipMm.y(), secondTipMm.z()}
                                      : nlohmann::json(nullptr)},
          {"failure", failure.empty() ? nlohmann::json(nullptr) : nlohmann::json(failure)},
          {"warnings", warnings},
          {"volume_trim", volumeTrim}};
}

nlohmann::json PlanResult::toJson(const PlanRequest& r) const {
  nlohmann::json evaluationsJson = nlohmann::json::array();
  for (const auto& e : evaluations) evaluationsJson.push_back(e.toJson());
  nlohmann::json startsJson = nlohmann::json::array();
  for (const auto& s : starts) startsJson.push_back(s.toJson());
  // Why the best plan won: its objective's terms, against the runner-up's; and what the volume trim saved.
  std::ostringstream why;
  auto terms = [&](const PlanEvaluation& e) {
    why << "objective " << e.objective << " = coverage " << e.coverage << " - " << r.volumeCostPerMl << "/ml x "
        << e.volumeMl << " ml - limit penalty " << e.coverage - r.volumeCostPerMl * e.volumeMl - e.objective;
  };
  why << std::setprecision(4) << "the search's highest ";
  terms(best.volumeTrim ? searchBest : best);
  if (best.volumeTrim) {
    why << "; its volume trimmed to the smallest at its depth that keeps its coverage within "
        << r.trimCoverageTolerance << " and the limits: " << best.volumeMl << " ml, saving "
        << searchBest.volumeMl - best.volumeMl << " ml (";
    terms(best);
    why << ")";
  }
  const PlanEvaluation* second = nullptr;
  for (const auto& e : evaluations)
    if (!e.volumeTrim && e.index != best.index && !(best.volumeTrim && e.index == searchBest.index))
      if (!second || e.objective > second->objective) second = &e;
  if (second)
    why << "; the runner-up (" << second->volumeMl << " ml at depth " << second->depthMm << " mm, coverage "
        << second->coverage << (second->withinLimits ? "" : ", outside the limits") << ") scored " << second->objective;
  return {{"best", best.toJson()},
          {"search_best", searchBest.toJson()},
          {"why_best", why.str()},
          {"trajectory_check", trajectory.toJson()},
          {"objective", "coverage - volume_cost_per_ml x volume_ml - 5 x (syringe excess / limit + leakage excess / 0.1 ml); "
                        "then the best's volume trimmed to the smallest keeping its coverage within trim_coverage_tolerance"},
          {"evaluations", evaluationsJson},
          {"stop_reason", stopReason},
          {"optimiser", "NLopt LN_BOBYQA, " + std::to_string(starts.size()) + " starts along the trajectory"},
          {"starts", startsJson},
          {"request",
           {{"entry_mm", {r.entryMm.x(), r.entryMm.y(), r.entryMm.z()}},
            {"direction", {r.direction.x(), r.direction.y(), r.direction.z()}},
            {"depth_range_mm", {r.minDepthMm, r.maxDepthMm}},
            {"target_mm", {r.targetCentreMm.x(), r.targetCentreMm.y(), r.targetCentreMm.z()}},
            {"target_radius_mm", r.targetRadiusMm},
            {"volume_range_ml", {r.minVolumeMl, r.maxVolumeMl}},
            {"max_syringe_pressure_mpa", r.maxSyringeMpa},
            {"max_leakage_ml", r.maxLeakageMl},
            {"volume_cost_per_ml", r.volumeCostPerMl},
            {"trim_coverage_tolerance", r.trimCoverageTolerance},
            {"max_evaluations", r.maxEvaluations},
            {"starts", r.starts},
            {"second_tip", r.secondTip},
            {"allow_canal_crossing", r.allowCanalCrossing}}},
          {"mpi_ranks", mpiRanks},
          {"frame", "the CT's patient frame, LPS mm"}};
}

std::string PlanResult::csv() const {
  std::ostringstream s;
  s << "index,start,depth_mm,volume_ml,tip_x_mm,tip_y_mm,tip_z_mm,coverage,max_syringe_pressure_mpa,leakage_volume_ml,"
       "objective,within_limits,second_tip_depth_mm,second_tip_volume_ml,failure,volume_trim\n"
    << std::setprecision(10);
  for (const auto& e : evaluations) {
    std::string failure = e.failure;
    std::replace(failure.begin(), failure.end(), '"', '\'');
    s << e.index << ',' << e.start << ',' << e.depthMm << ',' << e.volumeMl << ',' << e.tipMm.x() << ',' << e.tipMm.y() << ','
      << e.tipMm.z() << ',' << e.coverage << ',' << e.syringeMpa << ',' << e.leakageMl << ',' << e.objective << ','
      << (e.withinLimits ? 1 : 0) << ',';
    if (e.secondTip) s << e.secondDepthMm << ',' << e.secondVolumeMl;
    else s << ',';
    s << ",\"" << failure << "\"," << (e.volumeTrim ? 1 : 0) << "\n";
  }
  return s.str();
}

} // namespace cementsph::planning
