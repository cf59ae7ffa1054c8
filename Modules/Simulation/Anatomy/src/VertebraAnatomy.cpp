#include "cementsph/anatomy/VertebraAnatomy.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace cementsph::anatomy {

namespace {

using Mask = std::vector<std::uint8_t>;

std::string fmt(double v, int digits = 1) {
  char b[64];
  std::snprintf(b, sizeof b, "%.*f", digits, v);
  return b;
}

// Index helpers over one grid (x fastest).
struct Lattice {
  int nx, ny, nz;
  std::size_t n;
  explicit Lattice(const Grid& g)
      : nx(g.size[0]), ny(g.size[1]), nz(g.size[2]), n(std::size_t(nx) * std::size_t(ny) * std::size_t(nz)) {}
  std::size_t at(int i, int j, int k) const { return std::size_t(i) + std::size_t(nx) * (std::size_t(j) + std::size_t(ny) * std::size_t(k)); }
  void ijk(std::size_t v, int& i, int& j, int& k) const {
    i = int(v % std::size_t(nx));
    j = int((v / std::size_t(nx)) % std::size_t(ny));
    k = int(v / (std::size_t(nx) * std::size_t(ny)));
  }
  bool inside(int i, int j, int k) const { return i >= 0 && j >= 0 && k >= 0 && i < nx && j < ny && k < nz; }
  bool onBorder(int i, int j, int k) const { return i == 0 || j == 0 || k == 0 || i == nx - 1 || j == ny - 1 || k == nz - 1; }
};

constexpr int kD6[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};

// Dilation by a box of half-widths r (per index axis), separable: a running count along each line of each axis.
// The lines are walked directly (no index arithmetic per voxel): the rule runs this on every injection's region.
Mask dilateBox(const Lattice& L, const Mask& m, const std::array<int, 3>& r) {
  Mask cur = m, next(L.n);
  const int dims[3] = {L.nx, L.ny, L.nz};
  const std::size_t strides[3] = {1, std::size_t(L.nx), std::size_t(L.nx) * std::size_t(L.ny)};
  std::vector<int> prefix;
  for (int a = 0; a < 3; ++a) {
    const int reach = r[std::size_t(a)];
    if (reach <= 0) continue;
    const int len = dims[a];
    const std::size_t stride = strides[a];
    const int b = a == 0 ? 1 : 0, c = a == 2 ? 1 : 2; // the two axes across the lines
    prefix.assign(std::size_t(len) + 1, 0);
    for (int q = 0; q < dims[c]; ++q)
      for (int p = 0; p < dims[b]; ++p) {
        const std::size_t v = std::size_t(p) * strides[b] + std::size_t(q) * strides[c]; // the line's first voxel
        // A voxel is on if any voxel within reach along the line is on: prefix counts along the line.
        for (int t = 0; t < len; ++t) prefix[std::size_t(t) + 1] = prefix[std::size_t(t)] + (cur[v + std::size_t(t) * stride] ? 1 : 0);
        for (int t = 0; t < len; ++t) {
          const int lo = std::max(0, t - reach), hi = std::min(len - 1, t + reach);
          next[v + std::size_t(t) * stride] = prefix[std::size_t(hi) + 1] - prefix[std::size_t(lo)] > 0 ? 1 : 0;
        }
      }
    std::swap(cur, next);
  }
  return cur;
}

// The in-grid 6-neighbours of voxel v.
template <class F> void forNeighbours6(const Lattice& L, std::size_t v, F&& f) {
  int i, j, k;
  L.ijk(v, i, j, k);
  for (const auto& d : kD6) {
    const int a = i + d[0], b = j + d[1], c = k + d[2];
    if (L.inside(a, b, c)) f(L.at(a, b, c));
  }
}

// Grows from the voxels on `stack` (already taken) to every 6-neighbour that take(w) accepts (and marks).
template <class Take> std::vector<std::size_t> grow6(const Lattice& L, std::vector<std::size_t> stack, Take&& take) {
  std::vector<std::size_t> out;
  while (!stack.empty()) {
    const std::size_t v = stack.back();
    stack.pop_back();
    out.push_back(v);
    forNeighbours6(L, v, [&](std::size_t w) {
      if (take(w)) stack.push_back(w);
    });
  }
  return out;
}

// 6-connected flood over `passable` from seed; returns the visited voxels (and marks them in `label`).
std::vector<std::size_t> flood6(const Lattice& L, const Mask& passable, std::size_t seed, std::vector<int>& label, int id) {
  label[seed] = id;
  return grow6(L, {seed}, [&](std::size_t w) {
    if (!passable[w] || label[w] != 0) return false;
    label[w] = id;
    return true;
  });
}

// 3-D hole filling: every voxel not in `m` that cannot reach the grid's border through voxels not in `m`
// (6-connected) is added. Only the box of `m`, one voxel wider on each side where the grid allows, is flooded:
// every voxel beyond it reaches the border in a straight line outside `m`, and so does every voxel of the box's
// own faces (the widening keeps `m` off them, except where a face is the grid's border), so the outside within
// the box is what floods in from its faces; outside the box nothing is a hole. The flood carries each voxel's
// (i, j, k) rather than dividing its index back. (A vertebral body is a tenth of the region the rule is given.)
Mask fillHoles3D(const Lattice& L, const Mask& m) {
  int lo[3] = {L.nx, L.ny, L.nz}, hi[3] = {-1, -1, -1};
  {
    std::size_t v = 0;
    for (int k = 0; k < L.nz; ++k)
      for (int j = 0; j < L.ny; ++j)
        for (int i = 0; i < L.nx; ++i, ++v) {
          if (!m[v]) continue;
          lo[0] = std::min(lo[0], i), hi[0] = std::max(hi[0], i);
          lo[1] = std::min(lo[1], j), hi[1] = std::max(hi[1], j);
          lo[2] = std::min(lo[2], k), hi[2] = std::max(hi[2], k);
        }
  }
  Mask filled(L.n, 0);
  if (hi[0] < 0) return filled; // nothing in m: no holes
  const int dims[3] = {L.nx, L.ny, L.nz};
  for (int a = 0; a < 3; ++a) {
    lo[a] = std::max(0, lo[a] - 1);
    hi[a] = std::min(dims[a] - 1, hi[a] + 1);
  }
  auto inBox = [&](int i, int j, int k) {
    return i >= lo[0] && j >= lo[1] && k >= lo[2] && i <= hi[0] && j <= hi[1] && k <= hi[2];
  };
  auto onBoxFace = [&](int i, int j, int k) {
    return i == lo[0] || j == lo[1] || k == lo[2] || i == hi[0] || j == hi[1] || k == hi[2];
  };
  Mask outside(L.n, 0);
  std::vector<std::array<int, 3>> stack;
  for (int k = lo[2]; k <= hi[2]; ++k)
    for (int j = lo[1]; j <= hi[1]; ++j)
      for (int i = lo[0]; i <= hi[0]; ++i) {
        if (!onBoxFace(i, j, k)) { // an inner line: on to its last voxel (the loop's ++i)
          i = hi[0] - 1;
          continue;
        }
        const std::size_t v = L.at(i, j, k);
        if (m[v]) continue;
        outside[v] = 1;
        stack.push_back({i, j, k});
      }
  while (!stack.empty()) {
    const auto [i, j, k] = stack.back();
    stack.pop_back();
    for (const auto& d : kD6) {
      const int a = i + d[0], b = j + d[1], c = k + d[2];
      if (!inBox(a, b, c)) continue;
      const std::size_t w = L.at(a, b, c);
      if (m[w] || outside[w]) continue;
      outside[w] = 1;
      stack.push_back({a, b, c});
    }
  }
  for (int k = lo[2]; k <= hi[2]; ++k)
    for (int j = lo[1]; j <= hi[1]; ++j)
      for (int i = lo[0]; i <= hi[0]; ++i) {
        const std::size_t v = L.at(i, j, k);
        filled[v] = outside[v] ? 0 : 1;
      }
  return filled;
}

// The holes of `m` in each slice across index axis `a`: the 4-connected regions of pixels not in `m` that do
// not reach the slice's border; f(voxels) for each. Slices without any voxel of `m` are skipped.
template <class F> void forEachHole2D(const Lattice& L, const Mask& m, int a, F&& f) {
  const int u = a == 0 ? 1 : 0, w = a == 2 ? 1 : 2;
  const int dims[3] = {L.nx, L.ny, L.nz};
  const int nu = dims[u], nw = dims[w];
  std::vector<std::uint8_t> seen(std::size_t(nu) * std::size_t(nw));
  for (int s = 0; s < dims[a]; ++s) {
    auto at = [&](int p, int q) {
      int c[3];
      c[a] = s;
      c[u] = p;
      c[w] = q;
      return L.at(c[0], c[1], c[2]);
    };
    bool any = false;
    for (int p = 0; p < nu && !any; ++p)
      for (int q = 0; q < nw && !any; ++q) any = m[at(p, q)] != 0;
    if (!any) continue;
    std::fill(seen.begin(), seen.end(), std::uint8_t(0));
    for (int p0 = 0; p0 < nu; ++p0)
      for (int q0 = 0; q0 < nw; ++q0) {
        if (m[at(p0, q0)] || seen[std::size_t(p0) * std::size_t(nw) + std::size_t(q0)]) continue;
        std::vector<std::pair<int, int>> stack{{p0, q0}};
        std::vector<std::size_t> pix;
        seen[std::size_t(p0) * std::size_t(nw) + std::size_t(q0)] = 1;
        bool border = false;
        while (!stack.empty()) {
          const auto [p, q] = stack.back();
          stack.pop_back();
          pix.push_back(at(p, q));
          if (p == 0 || q == 0 || p == nu - 1 || q == nw - 1) border = true;
          const int nb[4][2] = {{p + 1, q}, {p - 1, q}, {p, q + 1}, {p, q - 1}};
          for (const auto& e : nb) {
            if (e[0] < 0 || e[1] < 0 || e[0] >= nu || e[1] >= nw) continue;
            const std::size_t key = std::size_t(e[0]) * std::size_t(nw) + std::size_t(e[1]);
            if (seen[key] || m[at(e[0], e[1])]) continue;
            seen[key] = 1;
            stack.push_back({e[0], e[1]});
          }
        }
        if (!border) f(pix);
      }
  }
}

// The index axis nearest patient z (the spine's axis, assumed within 45 degrees of it).
int spineAxis(const Grid& g) {
  int best = 2;
  double bestAbs = -1;
  for (int a = 0; a < 3; ++a) {
    const double z = std::abs(g.direction[std::size_t(6 + a)]); // row 2 (z), column a
    if (z > bestAbs) {
      bestAbs = z;
      best = a;
    }
  }
  return best;
}

std::size_t tipVoxel(const Grid& g, const std::array<double, 3>& tipMm) {
  const auto c = g.continuousIndex(tipMm);
  int idx[3];
  for (int a = 0; a < 3; ++a) {
    idx[a] = int(std::lround(c[std::size_t(a)]));
    if (idx[a] < 0 || idx[a] >= g.size[std::size_t(a)])
      throw std::invalid_argument("the tip at (" + fmt(tipMm[0]) + ", " + fmt(tipMm[1]) + ", " + fmt(tipMm[2]) +
                                  ") mm is outside the CT region");
  }
  return Lattice(g).at(idx[0], idx[1], idx[2]);
}

void finish(Anatomy& a) {
  const Lattice L(a.grid);
  double s[3] = {0, 0, 0};
  std::size_t count = 0;
  for (std::size_t v = 0; v < L.n; ++v) {
    if (a.at(v) != TissueClass::TargetVertebra) continue;
    int i, j, k;
    L.ijk(v, i, j, k);
    const auto p = a.grid.centreMm(i, j, k);
    for (int d = 0; d < 3; ++d) s[d] += p[std::size_t(d)];
    ++count;
  }
  a.targetFound = count > 0;
  if (count > 0) a.targetCentroidMm = {s[0] / double(count), s[1] / double(count), s[2] / double(count)};
}

} // namespace

const char* className(TissueClass c) {
  switch (c) {
  case TissueClass::OtherSoftTissue: return "other_soft_tissue";
  case TissueClass::TargetVertebra: return "target_vertebra";
  case TissueClass::Disc: return "disc";
  case TissueClass::Canal: return "canal";
  case TissueClass::Vessel: return "vessel";
  case TissueClass::OtherBone: return "other_bone";
  case TissueClass::Air: return "air";
  }
  return "unknown";
}

const char* tissueWords(TissueClass c) {
  switch (c) {
  case TissueClass::OtherSoftTissue: return "soft tissue outside the vertebra";
  case TissueClass::TargetVertebra: return "the target vertebra";
  case TissueClass::Disc: return "the intervertebral disc";
  case TissueClass::Canal: return "the spinal canal";
  case TissueClass::Vessel: return "a blood vessel";
  case TissueClass::OtherBone: return "another bone (not the target vertebra)";
  case TissueClass::Air: return "air";
  }
  return "an unknown tissue";
}

TissueClass classFromName(const std::string& name) {
  for (int c = 0; c <= 6; ++c)
    if (name == className(TissueClass(c))) return TissueClass(c);
  if (name == "soft_tissue") return TissueClass::OtherSoftTissue;
  if (name == "bone") return TissueClass::OtherBone;
  throw std::invalid_argument("unknown tissue class '" + name +
                              "': use target_vertebra, disc, canal, vessel, other_bone, air or other_soft_tissue");
}

std::array<double, 3> Grid::centreMm(int i, int j, int k) const {
  const double s[3] = {i * spacingMm[0], j * spacingMm[1], k * spacingMm[2]};
  std::array<double, 3> p = originMm;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) p[std::size_t(r)] += direction[std::size_t(3 * r + c)] * s[c];
  return p;
}

std::array<double, 3> Grid::continuousIndex(const std::array<double, 3>& pointMm) const {
  // direction is orthonormal (a CT's axes): its inverse is its transpose.
  std::array<double, 3> c{};
  for (int a = 0; a < 3; ++a) {
    double s = 0;
    for (int r = 0; r < 3; ++r) s += direction[std::size_t(3 * r + a)] * (pointMm[std::size_t(r)] - originMm[std::size_t(r)]);
    c[std::size_t(a)] = s / spacingMm[std::size_t(a)];
  }
  return c;
}

void Grid::validate() const {
  for (int a = 0; a < 3; ++a) {
    if (size[std::size_t(a)] < 1) throw std::invalid_argument("anatomy grid: size must be at least 1 voxel per axis");
    if (!(spacingMm[std::size_t(a)] > 0)) throw std::invalid_argument("anatomy grid: spacing_mm must be positive");
  }
  for (int a = 0; a < 3; ++a) {
    double len = 0;
    for (int r = 0; r < 3; ++r) len += direction[std::size_t(3 * r + a)] * direction[std::size_t(3 * r + a)];
    if (std::abs(len - 1.0) > 1e-3) throw std::invalid_argument("anatomy grid: direction columns must be unit vectors");
  }
}

void AnatomyOptions::validate() const {
  if (!(corticalHu > softTissueMaxHu)) throw std::invalid_argument("cortical_hu must be above soft_tissue_max_hu");
  if (!(airMaxHu < softTissueMaxHu)) throw std::invalid_argument("air_max_hu must be below soft_tissue_max_hu");
  if (!(wallHu > softTissueMaxHu && wallHu <= corticalHu))
    throw std::invalid_argument("wall_hu must be above soft_tissue_max_hu and at most cortical_hu");
  if (!(wallCloseMm >= 0 && wallCloseMm <= 10)) throw std::invalid_argument("wall_close_mm must be 0 .. 10 mm");
  if (!(minEnclosure >= 0 && minEnclosure <= 1)) throw std::invalid_argument("min_enclosure must be 0 .. 1");
  if (!(seedSearchMm >= 0 && seedSearchMm <= 100)) throw std::invalid_argument("seed_search_mm must be 0 .. 100 mm");
  if (!(minBodyMl >= 0)) throw std::invalid_argument("min_body_ml must not be negative");
  if (!(maxDiscHeightMm > 0)) throw std::invalid_argument("max_disc_height_mm must be positive");
  if (!(minCanalAreaMm2 >= 0)) throw std::invalid_argument("min_canal_area_mm2 must not be negative");
  if (!(maxVeinRadiusMm > 0)) throw std::invalid_argument("max_vein_radius_mm must be positive");
  if (!(minVesselMl >= 0)) throw std::invalid_argument("min_vessel_ml must not be negative");
}

LabelTable LabelTable::totalSegmentator() {
  // TotalSegmentator v2, task "total" (totalsegmentator/map_to_binary.py, class_map["total"]).
  LabelTable t;
  for (int l = 26; l <= 50; ++l) t.vertebrae.push_back(l); // vertebrae_S1 .. vertebrae_C1
  for (int l : {25, 69, 70, 71, 72, 73, 74, 75, 76, 77, 78, 116}) t.classes[l] = TissueClass::OtherBone; // sacrum, limbs' girdles, sternum
  for (int l = 92; l <= 115; ++l) t.classes[l] = TissueClass::OtherBone;                                  // ribs
  for (int l : {52, 53, 54, 55, 56, 57, 58, 59, 60, 62, 63, 64, 65, 66, 67, 68}) t.classes[l] = TissueClass::Vessel;
  t.classes[79] = TissueClass::Canal; // spinal_cord (the canal around it is not segmented)
  return t;
}

LabelTable LabelTable::fromJson(const nlohmann::json& j) {
  if (!j.is_object()) throw std::invalid_argument("label table: expected a JSON object of class -> [labels]");
  LabelTable t;
  auto labels = [&](const std::string& key) {
    std::vector<int> out;
    const auto& v = j.at(key);
    if (!v.is_array()) throw std::invalid_argument("label table: '" + key + "' must be an array of integer labels");
    for (const auto& e : v) {
      if (!e.is_number_integer()) throw std::invalid_argument("label table: '" + key + "' must be an array of integer labels");
      out.push_back(e.get<int>());
    }
    return out;
  };
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string& key = it.key();
    if (key == "vertebrae") t.vertebrae = labels(key);
    else if (key == "target_vertebra") {
      if (!it->is_number_integer()) throw std::invalid_argument("label table: 'target_vertebra' must be an integer label");
      t.targetVertebra = it->get<int>();
    } else {
      const TissueClass c = key == "bone"          ? TissueClass::OtherBone
                            : key == "disc"        ? TissueClass::Disc
                            : key == "canal"       ? TissueClass::Canal
                            : key == "vessel"      ? TissueClass::Vessel
                            : key == "air"         ? TissueClass::Air
                            : key == "soft_tissue" ? TissueClass::OtherSoftTissue
                                                   : throw std::invalid_argument(
                                                         "label table: unknown key '" + key +
                                                         "' (vertebrae, target_vertebra, bone, disc, canal, vessel, air, soft_tissue)");
      for (int l : labels(key)) t.classes[l] = c;
    }
  }
  if (t.targetVertebra >= 0 && std::find(t.vertebrae.begin(), t.vertebrae.end(), t.targetVertebra) == t.vertebrae.end())
    t.vertebrae.push_back(t.targetVertebra);
  return t;
}

nlohmann::json LabelTable::toJson() const {
  nlohmann::json j;
  j["vertebrae"] = vertebrae;
  if (targetVertebra >= 0) j["target_vertebra"] = targetVertebra;
  const std::pair<const char*, TissueClass> keys[] = {{"bone", TissueClass::OtherBone}, {"disc", TissueClass::Disc},
                                                      {"canal", TissueClass::Canal},    {"vessel", TissueClass::Vessel},
                                                      {"air", TissueClass::Air},        {"soft_tissue", TissueClass::OtherSoftTissue}};
  for (const auto& [key, c] : keys) {
    std::vector<int> ls;
    for (const auto& [l, cl] : classes)
      if (cl == c) ls.push_back(l);
    if (!ls.empty()) j[key] = ls;
  }
  return j;
}

TissueClass Anatomy::atPoint(const std::array<double, 3>& pointMm) const {
  const auto c = grid.continuousIndex(pointMm);
  int idx[3];
  for (int a = 0; a < 3; ++a) {
    idx[a] = int(std::lround(c[std::size_t(a)]));
    if (idx[a] < 0 || idx[a] >= grid.size[std::size_t(a)]) return TissueClass::OtherSoftTissue;
  }
  return at(Lattice(grid).at(idx[0], idx[1], idx[2]));
}

double Anatomy::volumeMl(TissueClass c) const {
  std::size_t count = 0;
  for (auto v : classes)
    if (v == std::uint8_t(c)) ++count;
  return double(count) * grid.voxelVolumeMm3() / 1000.0;
}

nlohmann::json Anatomy::toJson() const {
  nlohmann::json j = {{"rule", rule}, {"description", description}, {"target_found", targetFound}};
  if (targetFound) j["target_centroid_mm"] = targetCentroidMm;
  nlohmann::json vol;
  for (int c = 0; c <= 6; ++c) vol[className(TissueClass(c))] = volumeMl(TissueClass(c));
  j["volume_ml"] = vol;
  j["class_codes"] = {{"0", "other_soft_tissue"}, {"1", "target_vertebra"}, {"2", "disc"}, {"3", "canal"},
                      {"4", "vessel"},            {"5", "other_bone"},      {"6", "air"}};
  return j;
}

namespace {

// The bone rule on one grid (steps 1-9 of VertebraAnatomy.h); tipV: the tip's voxel on it. Its caller has
// validated the grid and the options.
Anatomy classifyOnGrid(const float* hu, const Grid& grid, std::size_t tipV, const AnatomyOptions& o) {
  const Lattice L(grid);
  const int ax = spineAxis(grid);
  const double voxelMl = grid.voxelVolumeMm3() / 1000.0;

  // 1. Cortex and the bone band.
  Mask cortex(L.n), band(L.n);
  for (std::size_t v = 0; v < L.n; ++v) {
    cortex[v] = hu[v] > o.corticalHu ? 1 : 0;
    band[v] = hu[v] >= o.softTissueMaxHu && hu[v] <= o.corticalHu ? 1 : 0;
  }
  // 2. The wall: the shell (HU above wall_hu: a 1 mm end plate averaged over a 2 mm slice shows 250-350 HU, below
  //    cortical_hu) thickened by wall_close_mm, rounded up to whole voxels per axis (gaps up to twice that are
  //    shut, whatever the spacing).
  Mask shell(L.n);
  for (std::size_t v = 0; v < L.n; ++v) shell[v] = hu[v] > o.wallHu ? 1 : 0;
  std::array<int, 3> r{};
  for (int a = 0; a < 3; ++a) r[std::size_t(a)] = int(std::ceil(o.wallCloseMm / grid.spacingMm[std::size_t(a)] - 1e-9));
  const Mask wall = dilateBox(L, shell, r);
  Mask passable(L.n);
  for (std::size_t v = 0; v < L.n; ++v) passable[v] = band[v] && !wall[v] ? 1 : 0;

  // 3. The core: candidate seeds, nearest the tip first (the tip's own voxel first), each a region grown over
  //    passable voxels; the first region that is big enough and enclosed on all six sides is the target's.
  std::vector<std::pair<double, std::size_t>> seeds;
  {
    int ti, tj, tk;
    L.ijk(tipV, ti, tj, tk);
    int reach[3];
    for (int a = 0; a < 3; ++a) reach[a] = int(std::ceil(o.seedSearchMm / grid.spacingMm[std::size_t(a)]));
    for (int k = std::max(0, tk - reach[2]); k <= std::min(L.nz - 1, tk + reach[2]); ++k)
      for (int j = std::max(0, tj - reach[1]); j <= std::min(L.ny - 1, tj + reach[1]); ++j)
        for (int i = std::max(0, ti - reach[0]); i <= std::min(L.nx - 1, ti + reach[0]); ++i) {
          const std::size_t v = L.at(i, j, k);
          if (!passable[v]) continue;
          // Seeds other than the tip's own voxel must be interior (all six neighbours passable): noise specks
          // in soft tissue that reach the band are not worth a try each.
          if (v != tipV) {
            bool interior = true;
            for (const auto& d : kD6) {
              const int a = i + d[0], b = j + d[1], c = k + d[2];
              interior = interior && L.inside(a, b, c) && passable[L.at(a, b, c)];
            }
            if (!interior) continue;
          }
          const double dx = (i - ti) * grid.spacingMm[0], dy = (j - tj) * grid.spacingMm[1], dz = (k - tk) * grid.spacingMm[2];
          const double d = std::sqrt(dx * dx + dy * dy + dz * dz);
          if (d <= o.seedSearchMm) seeds.emplace_back(d, v);
        }
    std::sort(seeds.begin(), seeds.end());
  }
  std::vector<int> label(L.n, 0);
  Mask core;
  std::string coreNote;
  int tried = 0;
  for (const auto& [distance, seed] : seeds) {
    if (label[seed] != 0) continue;
    const auto region = flood6(L, passable, seed, label, ++tried);
    if (double(region.size()) * voxelMl < o.minBodyMl) continue;
    if (tried > 10000) break; // a region of nothing but small pieces: stop looking
    Mask m(L.n, 0);
    for (auto v : region) m[v] = 1;
    m = fillHoles3D(L, m); // marrow fat and anything else the band region encloses
    // Enclosure: per direction, the share of boundary faces that meet the wall.
    std::size_t faces[6] = {0, 0, 0, 0, 0, 0}, onWall[6] = {0, 0, 0, 0, 0, 0};
    for (std::size_t v = 0; v < L.n; ++v) {
      if (!m[v]) continue;
      int i, j, k;
      L.ijk(v, i, j, k);
      for (int d = 0; d < 6; ++d) {
        const int a = i + kD6[d][0], b = j + kD6[d][1], c = k + kD6[d][2];
        if (L.inside(a, b, c) && m[L.at(a, b, c)]) continue;
        ++faces[d];
        if (L.inside(a, b, c) && wall[L.at(a, b, c)]) ++onWall[d];
      }
    }
    double least = 1.0;
    for (int d = 0; d < 6; ++d) least = std::min(least, faces[d] ? double(onWall[d]) / double(faces[d]) : 0.0);
    if (least < o.minEnclosure) continue;
    core = std::move(m);
    coreNote = distance < 1e-9 ? "grown from the tip" : "grown from " + fmt(distance) + " mm from the tip (the tip is not in it)";
    break;
  }

  Anatomy out;
  out.grid = grid;
  out.rule = "ct-bone-rule";
  out.classes.assign(L.n, std::uint8_t(TissueClass::OtherSoftTissue));
  for (std::size_t v = 0; v < L.n; ++v)
    if (hu[v] < o.airMaxHu) out.classes[v] = std::uint8_t(TissueClass::Air);
  auto setIf = [&](std::size_t v, TissueClass c) { out.classes[v] = std::uint8_t(c); };

  Mask target(L.n, 0), body(L.n, 0);
  if (!core.empty()) {
    // 4. The body: the core grown back over the wall's strip and the cortex (one voxel further than the wall's
    //    width reaches the cortex and no further: a vein's opening is its own length, not the tissue beyond).
    std::array<int, 3> r1 = r;
    for (auto& x : r1) x += 1;
    const Mask grown = dilateBox(L, core, r1);
    for (std::size_t v = 0; v < L.n; ++v) body[v] = core[v] || (grown[v] && (band[v] || cortex[v])) ? 1 : 0;
    body = fillHoles3D(L, body);
    // Marrow that reaches a gap of the cortex (fat against the basivertebral foramen, a fracture) is open in
    // 3-D; it is still bone where the body encloses it in a sagittal or a coronal slice (the slices along the
    // spine: in an axial slice the vertebral foramen, the canal, is enclosed too, so axial slices are not used).
    for (int a = 0; a < 3; ++a) {
      if (a == ax) continue;
      Mask add(L.n, 0);
      forEachHole2D(L, body, a, [&](const std::vector<std::size_t>& hole) {
        for (auto v : hole) add[v] = 1;
      });
      for (std::size_t v = 0; v < L.n; ++v) body[v] = body[v] || add[v] ? 1 : 0;
    }
    // The target: the body, the cortex 26-connected to it within its axial extent +- 2 mm (posterior elements;
    // beyond that, facets and ribs touching a neighbour are not followed), and the rim of band voxels on it.
    int lo = std::numeric_limits<int>::max(), hi = -1;
    for (std::size_t v = 0; v < L.n; ++v) {
      if (!body[v]) continue;
      int c[3];
      L.ijk(v, c[0], c[1], c[2]);
      lo = std::min(lo, c[ax]);
      hi = std::max(hi, c[ax]);
    }
    const int margin = int(std::ceil(2.0 / grid.spacingMm[std::size_t(ax)]));
    lo -= margin;
    hi += margin;
    target = body;
    std::vector<std::size_t> stack;
    for (std::size_t v = 0; v < L.n; ++v)
      if (body[v] && cortex[v]) stack.push_back(v);
    while (!stack.empty()) {
      const std::size_t v = stack.back();
      stack.pop_back();
      int i, j, k;
      L.ijk(v, i, j, k);
      for (int dk = -1; dk <= 1; ++dk)
        for (int dj = -1; dj <= 1; ++dj)
          for (int di = -1; di <= 1; ++di) {
            const int c[3] = {i + di, j + dj, k + dk};
            if (!L.inside(c[0], c[1], c[2]) || c[ax] < lo || c[ax] > hi) continue;
            const std::size_t w = L.at(c[0], c[1], c[2]);
            if (cortex[w] && !target[w]) {
              target[w] = 1;
              stack.push_back(w);
            }
          }
    }
  }

  // 5. Discs: in each column of the body along the spine axis, from its end plate to the next cortex.
  Mask disc(L.n, 0);
  if (!core.empty()) {
    const int len = ax == 0 ? L.nx : ax == 1 ? L.ny : L.nz;
    const int maxRun = int(std::floor(o.maxDiscHeightMm / grid.spacingMm[std::size_t(ax)]));
    const int u = ax == 0 ? 1 : 0, w = ax == 2 ? 1 : 2; // the other two axes
    const int dims[3] = {L.nx, L.ny, L.nz};
    for (int p = 0; p < dims[u]; ++p)
      for (int q = 0; q < dims[w]; ++q) {
        auto at = [&](int s) {
          int c[3];
          c[ax] = s;
          c[u] = p;
          c[w] = q;
          return L.at(c[0], c[1], c[2]);
        };
        int top = -1, bottom = -1;
        for (int s = 0; s < len; ++s)
          if (body[at(s)]) {
            if (bottom < 0) bottom = s;
            top = s;
          }
        if (top < 0) continue;
        for (int dir : {+1, -1}) {
          int s = dir > 0 ? top + 1 : bottom - 1;
          while (s >= 0 && s < len && target[at(s)]) s += dir; // the end plate (cortex and its rim) is the target's
          const int start = s;
          bool closed = false, air = false;
          while (s >= 0 && s < len && std::abs(s - start) < maxRun) {
            const std::size_t v = at(s);
            if (shell[v]) { // the neighbour's end plate
              closed = true;
              break;
            }
            if (hu[v] < o.airMaxHu) air = true;
            s += dir;
          }
          if (!closed || air || s == start) continue;
          for (int t = start; t != s; t += dir) disc[at(t)] = 1;
        }
      }
  }

  // The target's partial-volume rim: band voxels 26-adjacent to its cortex, not in a disc.
  if (!core.empty()) {
    Mask cortexOfTarget(L.n);
    for (std::size_t v = 0; v < L.n; ++v) cortexOfTarget[v] = target[v] && cortex[v] ? 1 : 0;
    const Mask near = dilateBox(L, cortexOfTarget, {1, 1, 1});
    for (std::size_t v = 0; v < L.n; ++v)
      if (near[v] && band[v] && !disc[v]) target[v] = 1;
  }
  for (std::size_t v = 0; v < L.n; ++v) {
    if (target[v]) setIf(v, TissueClass::TargetVertebra);
    else if (disc[v]) setIf(v, TissueClass::Disc);
  }

  // 6. The canal: axial slices, non-target regions enclosed by the target (4-connected in the slice).
  Mask canal(L.n, 0);
  if (!core.empty()) {
    const int u = ax == 0 ? 1 : 0, w = ax == 2 ? 1 : 2;
    const double pixelMm2 = grid.spacingMm[std::size_t(u)] * grid.spacingMm[std::size_t(w)];
    forEachHole2D(L, target, ax, [&](const std::vector<std::size_t>& hole) {
      if (double(hole.size()) * pixelMm2 < o.minCanalAreaMm2) return;
      for (auto v : hole) canal[v] = 1;
    });
    for (std::size_t v = 0; v < L.n; ++v)
      if (canal[v] && !disc[v]) setIf(v, TissueClass::Canal);
  }

  // 7. Other bone: cortex not the target's, the band voxels touching it (its rim), and what bone encloses.
  {
    Mask otherCortex(L.n);
    for (std::size_t v = 0; v < L.n; ++v) otherCortex[v] = cortex[v] && !target[v] ? 1 : 0;
    const Mask near = dilateBox(L, otherCortex, {1, 1, 1});
    Mask barrier(L.n);
    for (std::size_t v = 0; v < L.n; ++v) barrier[v] = cortex[v] || target[v] ? 1 : 0;
    const Mask enclosed = fillHoles3D(L, barrier);
    for (std::size_t v = 0; v < L.n; ++v) {
      const auto c = out.at(v);
      if (c != TissueClass::OtherSoftTissue && c != TissueClass::Air) continue;
      if (otherCortex[v] || (near[v] && band[v]) || (enclosed[v] && !target[v])) setIf(v, TissueClass::OtherBone);
    }
  }

  // The disc's partial-volume rim (its edge against the soft tissue, a bulging annulus): band voxels not yet
  // classed, 6-adjacent to the disc, are disc.
  {
    std::vector<std::size_t> rim;
    for (std::size_t v = 0; v < L.n; ++v) {
      if (!band[v] || out.at(v) != TissueClass::OtherSoftTissue) continue;
      bool onDisc = false;
      forNeighbours6(L, v, [&](std::size_t w) { onDisc = onDisc || disc[w]; });
      if (onDisc) rim.push_back(v);
    }
    for (auto v : rim) setIf(v, TissueClass::Disc);
  }

  // 8. Vessels: band components left over; thin ones on the target are its draining veins, contrast-filled
  //    ones anywhere are enhanced vessels. Depth inside a component: a chamfer distance (mm) to its outside.
  {
    Mask cand(L.n);
    for (std::size_t v = 0; v < L.n; ++v) cand[v] = band[v] && out.at(v) == TissueClass::OtherSoftTissue ? 1 : 0;
    std::vector<double> depth(L.n, 0.0);
    const double big = 1e9;
    for (std::size_t v = 0; v < L.n; ++v) depth[v] = cand[v] ? big : 0.0;
    const double sp[3] = {grid.spacingMm[0], grid.spacingMm[1], grid.spacingMm[2]};
    // Two passes, 6-neighbour steps weighted by the spacing (an upper bound of the Euclidean depth).
    for (int pass = 0; pass < 2; ++pass) {
      for (std::size_t t = 0; t < L.n; ++t) {
        const std::size_t v = pass == 0 ? t : L.n - 1 - t;
        if (!cand[v]) continue;
        int i, j, k;
        L.ijk(v, i, j, k);
        for (int d = 0; d < 6; ++d) {
          const int a = i + kD6[d][0], b = j + kD6[d][1], c = k + kD6[d][2];
          const double step = sp[d / 2];
          const double nd = L.inside(a, b, c) ? depth[L.at(a, b, c)] : 0.0;
          depth[v] = std::min(depth[v], nd + step);
        }
      }
    }
    std::vector<int> comp(L.n, 0);
    int id = 0;
    for (std::size_t v0 = 0; v0 < L.n; ++v0) {
      if (!cand[v0] || comp[v0]) continue;
      const auto region = flood6(L, cand, v0, comp, ++id);
      if (double(region.size()) * voxelMl < o.minVesselMl) continue;
      bool touches = false;
      double maxDepth = 0, sumHu = 0;
      for (auto v : region) {
        maxDepth = std::max(maxDepth, depth[v]);
        sumHu += hu[v];
        forNeighbours6(L, v, [&](std::size_t w) { touches = touches || target[w]; });
      }
      // The depth of the centre voxel counts one step to the first outside voxel: radius ~ depth - spacing / 2.
      const double radius = maxDepth - 0.5 * std::min({sp[0], sp[1], sp[2]});
      const bool vein = touches && radius <= o.maxVeinRadiusMm;
      const bool contrast = sumHu / double(region.size()) >= o.contrastHu;
      if (vein || contrast)
        for (auto v : region) setIf(v, TissueClass::Vessel);
    }
    // Noise holes: a voxel of soft tissue with at least 4 of its 6 neighbours vessel is vessel (a 60 HU vein
    // under 10 HU noise falls below the band in 2 % of its voxels).
    // Counted from the vessels' side (each vessel voxel adds one to its neighbours): the vessels are few, the
    // soft tissue most of the region.
    std::vector<std::uint8_t> vesselNeighbours(L.n, 0);
    for (std::size_t v = 0; v < L.n; ++v)
      if (out.at(v) == TissueClass::Vessel) forNeighbours6(L, v, [&](std::size_t w) { ++vesselNeighbours[w]; });
    for (std::size_t v = 0; v < L.n; ++v)
      if (vesselNeighbours[v] >= 4 && out.at(v) == TissueClass::OtherSoftTissue) setIf(v, TissueClass::Vessel);
  }

  finish(out);
  std::ostringstream d;
  d << "CT bone rule (cortex > " << fmt(o.corticalHu, 0) << " HU, bone band " << fmt(o.softTissueMaxHu, 0) << " .. "
    << fmt(o.corticalHu, 0) << " HU, shell > " << fmt(o.wallHu, 0) << " HU with gaps up to " << fmt(2 * o.wallCloseMm)
    << " mm closed): ";
  if (out.targetFound)
    d << "the target vertebra " << coreNote << ", " << fmt(out.volumeMl(TissueClass::TargetVertebra)) << " ml, closed over its marrow";
  else
    d << "no vertebra enclosed by cortex within " << fmt(o.seedSearchMm) << " mm of the tip";
  out.description = d.str();
  return out;
}

} // namespace

Anatomy classifyAnatomyFromCT(const float* hu, const Grid& grid, const std::array<double, 3>& tipMm,
                              const AnatomyOptions& o) {
  grid.validate();
  o.validate();
  if (hu == nullptr) throw std::invalid_argument("anatomy: no CT values given");
  const Lattice L(grid);
  const std::size_t tipV = tipVoxel(grid, tipMm);
  // The rule runs on the box of the voxels that are not air (and the tip), one voxel wider on each side where
  // the grid allows. Outside it everything is air, and the result there is air: no step classes an air voxel
  // that reaches the grid's border through air (holes are only what cannot reach it; dilations are only read
  // on band, cortex or the core's neighbours; a disc run through air is none; a vessel is band). The margin of
  // air keeps every border test as it was: what reached the grid's border now reaches the margin, itself joined
  // to the border through the air cut away. So the classes are the same, voxel for voxel, at the cost of the
  // box: an oblique CT's aligned grid (AxisAlignedCT.h) fills the corners of its tilted box with air, which a
  // region around the tip otherwise carried through every step (a 20 degree tilt: 1.4-1.7x the voxels).
  int ti, tj, tk;
  L.ijk(tipV, ti, tj, tk);
  int lo[3] = {ti, tj, tk}, hi[3] = {ti, tj, tk};
  {
    std::size_t v = 0;
    for (int k = 0; k < L.nz; ++k)
      for (int j = 0; j < L.ny; ++j)
        for (int i = 0; i < L.nx; ++i, ++v) {
          if (hu[v] < o.airMaxHu) continue;
          lo[0] = std::min(lo[0], i), hi[0] = std::max(hi[0], i);
          lo[1] = std::min(lo[1], j), hi[1] = std::max(hi[1], j);
          lo[2] = std::min(lo[2], k), hi[2] = std::max(hi[2], k);
        }
  }
  const int dims[3] = {L.nx, L.ny, L.nz};
  bool whole = true;
  for (int a = 0; a < 3; ++a) {
    lo[a] = std::max(0, lo[a] - 1);
    hi[a] = std::min(dims[a] - 1, hi[a] + 1);
    whole = whole && lo[a] == 0 && hi[a] == dims[a] - 1;
  }
  Anatomy out;
  if (whole) {
    out = classifyOnGrid(hu, grid, tipV, o);
  } else {
    Grid box = grid;
    for (int a = 0; a < 3; ++a) box.size[std::size_t(a)] = hi[a] - lo[a] + 1;
    box.originMm = grid.centreMm(lo[0], lo[1], lo[2]);
    const Lattice B(box);
    std::vector<float> boxHu(B.n);
    for (int k = 0; k < B.nz; ++k)
      for (int j = 0; j < B.ny; ++j)
        std::copy_n(hu + L.at(lo[0], lo[1] + j, lo[2] + k), B.nx, boxHu.begin() + std::ptrdiff_t(B.at(0, j, k)));
    const Anatomy inBox = classifyOnGrid(boxHu.data(), box, B.at(ti - lo[0], tj - lo[1], tk - lo[2]), o);
    out.rule = inBox.rule;
    out.description = inBox.description;
    out.grid = grid;
    out.classes.assign(L.n, std::uint8_t(TissueClass::Air));
    for (int k = 0; k < B.nz; ++k)
      for (int j = 0; j < B.ny; ++j)
        std::copy_n(inBox.classes.begin() + std::ptrdiff_t(B.at(0, j, k)), B.nx,
                    out.classes.begin() + std::ptrdiff_t(L.at(lo[0], lo[1] + j, lo[2] + k)));
  }
  finish(out); // on the whole grid: the centroid as the whole grid's voxel centres give it
  return out;
}

Anatomy classifyAnatomyFromLabels(const float* hu, const std::int32_t* labels, const Grid& grid,
                                  const std::array<double, 3>& tipMm, const LabelTable& table, const AnatomyOptions& o) {
  grid.validate();
  o.validate();
  if (labels == nullptr) throw std::invalid_argument("anatomy: no label map given");
  const Lattice L(grid);
  const std::size_t tipV = tipVoxel(grid, tipMm);
  auto isVertebra = [&](int l) { return std::find(table.vertebrae.begin(), table.vertebrae.end(), l) != table.vertebrae.end(); };
  // The target: the table's, else the vertebra at the tip, else the nearest vertebra voxel within seed_search_mm.
  int target = table.targetVertebra;
  std::string how = "given by the table";
  if (target < 0 && isVertebra(labels[tipV])) {
    target = labels[tipV];
    how = "the label at the tip";
  }
  if (target < 0) {
    int ti, tj, tk;
    L.ijk(tipV, ti, tj, tk);
    double best = o.seedSearchMm;
    for (std::size_t v = 0; v < L.n; ++v) {
      if (!isVertebra(labels[v])) continue;
      int i, j, k;
      L.ijk(v, i, j, k);
      const double dx = (i - ti) * grid.spacingMm[0], dy = (j - tj) * grid.spacingMm[1], dz = (k - tk) * grid.spacingMm[2];
      const double d = std::sqrt(dx * dx + dy * dy + dz * dz);
      if (d <= best) {
        best = d;
        target = labels[v];
        how = "the vertebra nearest the tip (" + fmt(d) + " mm)";
      }
    }
  }
  Anatomy out;
  out.grid = grid;
  out.rule = "labels";
  out.classes.assign(L.n, std::uint8_t(TissueClass::OtherSoftTissue));
  for (std::size_t v = 0; v < L.n; ++v) {
    const int l = labels[v];
    TissueClass c = TissueClass::OtherSoftTissue;
    if (l != 0 && target >= 0 && l == target) c = TissueClass::TargetVertebra;
    else if (l != 0 && isVertebra(l)) c = TissueClass::OtherBone;
    else if (auto it = table.classes.find(l); l != 0 && it != table.classes.end()) c = it->second;
    else if (hu != nullptr && hu[v] < o.airMaxHu) c = TissueClass::Air;
    out.classes[v] = std::uint8_t(c);
  }
  finish(out);
  out.description = out.targetFound ? "labels: the target vertebra is label " + std::to_string(target) + " (" + how + "), " +
                                          fmt(out.volumeMl(TissueClass::TargetVertebra)) + " ml"
                                    : "labels: no vertebra label at or within " + fmt(o.seedSearchMm) + " mm of the tip";
  return out;
}

TissueClass tissueAtTip(const Anatomy& anatomy, const std::array<double, 3>& tipMm) { return anatomy.atPoint(tipMm); }

TissueClass requireTipInVertebra(const Anatomy& anatomy, const float* hu, const std::array<double, 3>& tipMm,
                                 bool allowOutsideBone) {
  const TissueClass c = tissueAtTip(anatomy, tipMm);
  if (c == TissueClass::TargetVertebra || allowOutsideBone) return c;
  std::string huText;
  if (hu != nullptr) {
    const auto ci = anatomy.grid.continuousIndex(tipMm);
    int idx[3];
    bool in = true;
    for (int a = 0; a < 3; ++a) {
      idx[a] = int(std::lround(ci[std::size_t(a)]));
      in = in && idx[a] >= 0 && idx[a] < anatomy.grid.size[std::size_t(a)];
    }
    if (in) huText = " (HU " + fmt(hu[Lattice(anatomy.grid).at(idx[0], idx[1], idx[2])], 0) + ")";
  }
  std::string where = tissueWords(c);
  if (!anatomy.targetFound) where += ", and no vertebra was found around it";
  throw std::invalid_argument("the tip at (" + fmt(tipMm[0]) + ", " + fmt(tipMm[1]) + ", " + fmt(tipMm[2]) + ") mm is in " +
                              where + huText + "; place it in the vertebral body or set allow_tip_outside_bone");
}

} // namespace cementsph::anatomy
