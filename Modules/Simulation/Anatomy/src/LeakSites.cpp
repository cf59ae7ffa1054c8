#include "cementsph/anatomy/LeakSites.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace cementsph::anatomy {

const char* leakKind(TissueClass c) {
  switch (c) {
  case TissueClass::TargetVertebra: return "";
  case TissueClass::Disc: return "disc";
  case TissueClass::Canal: return "canal";
  case TissueClass::Vessel: return "venous";
  case TissueClass::OtherBone: return "other_bone";
  case TissueClass::OtherSoftTissue:
  case TissueClass::Air: return "cortex_breach";
  }
  return "cortex_breach";
}

nlohmann::json LeakReport::toJson() const {
  nlohmann::json s = nlohmann::json::array();
  for (const auto& site : sites) {
    nlohmann::json j = {{"kind", site.kind},
                        {"tissue", className(site.tissue)},
                        {"volume_ml", site.volumeMl},
                        {"position_mm", site.positionMm},
                        {"voxels", site.voxels}};
    j["first_time_s"] = site.firstTimeS >= 0 ? nlohmann::json(site.firstTimeS) : nlohmann::json(nullptr);
    s.push_back(j);
  }
  return {{"rule", rule},         {"leaked_ml", leakedMl},          {"inside_target_ml", insideMl},
          {"sites", s},           {"volume_ml_by_kind", volumeMlByKind}, {"sites_by_kind", sitesByKind}};
}

LeakReport classifyLeaks(const Anatomy& anatomy, const std::vector<double>& fill, const std::vector<double>& arrivalS,
                         const std::vector<double>& porosity, const LeakOptions& options) {
  const Grid& g = anatomy.grid;
  const std::size_t n = g.count();
  if (anatomy.classes.size() != n) throw std::invalid_argument("classifyLeaks: the anatomy's classes do not match its grid");
  if (fill.size() != n)
    throw std::invalid_argument("classifyLeaks: fill has " + std::to_string(fill.size()) + " values, the grid " +
                                std::to_string(n) + " voxels");
  if (!arrivalS.empty() && arrivalS.size() != n)
    throw std::invalid_argument("classifyLeaks: arrival times have " + std::to_string(arrivalS.size()) +
                                " values, the grid " + std::to_string(n) + " voxels");
  if (!porosity.empty() && porosity.size() != n)
    throw std::invalid_argument("classifyLeaks: porosity has " + std::to_string(porosity.size()) + " values, the grid " +
                                std::to_string(n) + " voxels");
  const double voxelMl = g.voxelVolumeMm3() / 1000.0;
  auto cementMl = [&](std::size_t v) { return fill[v] * (porosity.empty() ? 1.0 : porosity[v]) * voxelMl; };

  LeakReport r;
  r.rule = anatomy.rule;
  for (const char* k : {"disc", "canal", "venous", "other_bone", "cortex_breach"}) {
    r.volumeMlByKind[k] = 0.0;
    r.sitesByKind[k] = 0;
  }
  const int nx = g.size[0], ny = g.size[1], nz = g.size[2];
  std::vector<std::uint8_t> done(n, 0);
  for (std::size_t v0 = 0; v0 < n; ++v0) {
    if (!(fill[v0] > options.minFill)) continue;
    const TissueClass c0 = anatomy.at(v0);
    if (c0 == TissueClass::TargetVertebra) {
      r.insideMl += cementMl(v0);
      continue;
    }
    if (done[v0]) continue;
    // A site: 26-connected filled voxels of the same leak kind (disc and canal cement that touch are two sites).
    const std::string kind = leakKind(c0);
    LeakSite site;
    site.kind = kind;
    site.tissue = c0;
    double cx = 0, cy = 0, cz = 0;
    std::vector<std::size_t> stack{v0};
    done[v0] = 1;
    while (!stack.empty()) {
      const std::size_t v = stack.back();
      stack.pop_back();
      const int i = int(v % std::size_t(nx)), j = int((v / std::size_t(nx)) % std::size_t(ny)),
                k = int(v / (std::size_t(nx) * std::size_t(ny)));
      const double ml = cementMl(v);
      const auto p = g.centreMm(i, j, k);
      site.volumeMl += ml;
      cx += ml * p[0];
      cy += ml * p[1];
      cz += ml * p[2];
      ++site.voxels;
      if (!arrivalS.empty() && arrivalS[v] >= 0 && (site.firstTimeS < 0 || arrivalS[v] < site.firstTimeS))
        site.firstTimeS = arrivalS[v];
      for (int dk = -1; dk <= 1; ++dk)
        for (int dj = -1; dj <= 1; ++dj)
          for (int di = -1; di <= 1; ++di) {
            const int a = i + di, b = j + dj, c = k + dk;
            if (a < 0 || b < 0 || c < 0 || a >= nx || b >= ny || c >= nz) continue;
            const std::size_t w = std::size_t(a) + std::size_t(nx) * (std::size_t(b) + std::size_t(ny) * std::size_t(c));
            if (done[w] || !(fill[w] > options.minFill)) continue;
            const TissueClass cw = anatomy.at(w);
            if (cw == TissueClass::TargetVertebra || kind != leakKind(cw)) continue;
            done[w] = 1;
            stack.push_back(w);
          }
    }
    if (site.volumeMl > 0) site.positionMm = {cx / site.volumeMl, cy / site.volumeMl, cz / site.volumeMl};
    r.leakedMl += site.volumeMl;
    r.volumeMlByKind[kind] += site.volumeMl;
    r.sitesByKind[kind] += 1;
    r.sites.push_back(site);
  }
  std::sort(r.sites.begin(), r.sites.end(), [](const LeakSite& a, const LeakSite& b) { return a.volumeMl > b.volumeMl; });
  return r;
}

} // namespace cementsph::anatomy
