// The particle-darcy model's time stepping rules, its closed sums' interpolant and cell lookup, and its colour
// pass's pieces (ParticleDarcyInjectionModel.cpp), apart so that its tests (ParticleDarcyTest) can hold each rule to a
// number without running a scene. Header-only; used by that model only.
#pragma once
#include "cementsph/sph/Simulation.h"

#include <Eigen/Dense>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

namespace cementsph::scene::particle_darcy {

// A move that never enters a closed voxel nor crosses one: taken axis by axis, a component dropped when its path
// along its axis meets a closed voxel. The path is tested at points no farther apart than the voxel spacing along
// that axis (so every voxel it crosses holds one: a voxel is one spacing long), not at its end point alone: a
// component longer than a voxel used to jump a one-voxel wall whose far side was open. closedAt(point) says
// whether the point lies in a closed voxel (or outside the region).
template <class ClosedAt>
void stepAround(Eigen::Vector3d& pos, const Eigen::Vector3d& step, const Eigen::Vector3d& spacing, const ClosedAt& closedAt) {
  for (int a = 0; a < 3; ++a) {
    const int pieces = std::max(1, int(std::ceil(std::abs(step[a]) / spacing[a])));
    Eigen::Vector3d trial = pos;
    bool blocked = false;
    for (int k = 1; k <= pieces && !blocked; ++k) {
      trial[a] = pos[a] + (k == pieces ? step[a] : step[a] * k / pieces);
      blocked = closedAt(trial);
    }
    if (!blocked) pos = trial;
  }
}

// A particle's move over a macro step outside its sub-steps: its density correction (u - u_darcy) dt, at most
// limit (0.2 d) for every particle, plus its shift, plus (when it is not sub-stepped) its Darcy move u_darcy dt,
// itself at most limit (a particle whose Darcy move is longer is sub-stepped). So no particle moves more than
// 2 limit + its shift (<= 0.1 d) in one call. Before, a particle that was not sub-stepped took its correction
// uncapped (u dt), and the step's speed is clipped to kMaxCorrectionOverDarcy times the fastest Darcy speed, so a
// strong correction could carry it farther than the no-penetration test looks.
inline Eigen::Vector3d macroMove(const Eigen::Vector3d& u, const Eigen::Vector3d& darcy, const Eigen::Vector3d& shift,
                                 double dt, bool subStepped, double limit) {
  Eigen::Vector3d correction = (u - darcy) * dt;
  if (const double c = correction.norm(); c > limit) correction *= limit / c;
  return subStepped ? Eigen::Vector3d(correction + shift) : Eigen::Vector3d(darcy * dt + correction + shift);
}

// The macro step's length (multi-rate stepping, moveMultiRate):
//  * the particle at the (1 - subSteppedShare) quantile of speed moves limit (the bulk is not sub-stepped);
//  * the emitted volume is at most maxGrowthDt's worth (given: maxGrowth x the cement's volume / Q);
//  * the fastest particle needs at most maxSubSteps sub-steps of limit, by its Darcy speed (the speed it is
//    sub-stepped with): dt <= maxSubSteps limit / vFast, vFast >= the fastest Darcy speed;
//  * never shorter than limit / vFast (progress), never longer than dtMax.
// speeds: each particle's whole speed |u| (Darcy and density correction); vmaxDarcy: the fastest Darcy speed;
// the whole speed counts at most maxCorrectionOverDarcy x vmaxDarcy (the correction's own speed scales as 1 / dt).
// vFast = max(min(max |u|, maxCorrectionOverDarcy vmaxDarcy), vmaxDarcy): it used to be the clipped whole speed
// alone, which can lie below the fastest Darcy speed (a correction against the flow), so the fastest particle
// needed more than maxSubSteps sub-steps and fell behind its Darcy displacement.
struct MacroStepRule {
  double limit = 0, subSteppedShare = 0.05, maxCorrectionOverDarcy = 2.0;
  int maxSubSteps = 4;
};
inline double macroStep(std::vector<double> speeds, double vmaxDarcy, double dtMax, double maxGrowthDt, const MacroStepRule& rule) {
  double vmax = 0;
  for (double s : speeds) vmax = std::max(vmax, s);
  const double vFast = std::max(std::min(vmax, rule.maxCorrectionOverDarcy * vmaxDarcy), vmaxDarcy);
  if (!(vFast > 0) || speeds.empty()) return dtMax;
  for (double& s : speeds) s = std::min(s, vFast);
  const std::size_t rank = std::size_t(std::floor((1.0 - rule.subSteppedShare) * double(speeds.size() - 1)));
  std::nth_element(speeds.begin(), speeds.begin() + std::ptrdiff_t(rank), speeds.end());
  const double bulk = speeds[rank];
  double dt = bulk > 0 ? rule.limit / bulk : dtMax;
  dt = std::min(dt, maxGrowthDt);
  dt = std::min(dt, rule.maxSubSteps * rule.limit / vFast);
  return std::min(dtMax, std::max(dt, rule.limit / vFast));
}

// A static field f known with its gradient at the eight corners of a grid cell (corner c = di + 2 dj + 4 dk, di, dj,
// dk in {0, 1}), read at the point with cell coordinates t (0..1 per axis; spacing: the cell's size): the mean of
// the trilinear value and the trilinear blend of the corners' first-order Taylor expansions f_c + grad f_c . (x - x_c).
// On a quadratic the first errs by +1/2 sum_a f_aa t_a (1 - t_a) spacing_a^2 and the second by as much the other
// way (the trilinear weights' first moments about the point vanish, so no cross term enters), so the mean is exact
// for every quadratic; plain trilinear interpolation is exact only for the multilinear ones. The model's closed
// space sums are read this way (ParticleDarcyInjectionModel.cpp: closedSumsAt).
inline double blendedTrilinear(const double value[8], const Eigen::Vector3d grad[8], const Eigen::Vector3d& t,
                               const Eigen::Vector3d& spacing) {
  double plain = 0, slope = 0;
  for (int c = 0; c < 8; ++c) {
    const int d[3] = {c & 1, (c >> 1) & 1, (c >> 2) & 1};
    double w = 1;
    Eigen::Vector3d dx;
    for (int a = 0; a < 3; ++a) w *= d[a] ? t[a] : 1 - t[a], dx[a] = (t[a] - d[a]) * spacing[a];
    plain += w * value[c];
    slope += w * grad[c].dot(dx);
  }
  return plain + 0.5 * slope;
}

// The cell of a static field's grid (node (i, j, k) at origin + (i, j, k) spacing, size nodes per axis) that
// blendedTrilinear reads at p: its lower corner c (clamped so that the cell lies in -1 .. size per axis) and p's cell
// coordinates t. A position that is not finite is a run gone unstable: it throws sph::SimulationError with
// where() (a callable returning the particle, its step and time: built only then) and why, instead of indexing the
// field with the integer a NaN converts to (ParticleDarcyInjectionModel.cpp: closedSumsAt).
template <class Where>
void fieldCell(const Eigen::Vector3d& p, const Eigen::Vector3d& origin, const Eigen::Vector3d& spacing, const int size[3],
               int c[3], Eigen::Vector3d& t, const Where& where) {
  if (!p.allFinite())
    throw sph::SimulationError(where() + ": its position is not finite (" + std::to_string(p.x()) + ", " + std::to_string(p.y()) +
                               ", " + std::to_string(p.z()) + " m): the run went unstable");
  for (int a = 0; a < 3; ++a) {
    const double u = std::clamp((p[a] - origin[a]) / spacing[a], -1.0, double(size[a]));
    c[a] = std::min(int(std::floor(u)), size[a] - 1);
    t[a] = u - c[a];
  }
}
// A sum the run goes on with (the closed space's number density, second moment, concentration gradient at a
// particle): one that is not finite throws sph::SimulationError naming where() and what, rather than entering the
// pressure matrix.
template <class Where>
[[noreturn]] void throwNotFinite(double value, const char* what, const Where& where) {
  throw sph::SimulationError(where() + ": its " + what + " is not finite (" + std::to_string(value) + "): the run went unstable");
}
template <class Where>
inline void requireFiniteSum(double value, const char* what, const Where& where) {
  if (__builtin_expect(!std::isfinite(value), 0)) throwNotFinite(value, what, where);
}

// A solve's solution the run goes on with (the pressure solve's p and its density correction pc, one entry per
// particle): the first entry that is not finite throws sph::SimulationError naming where() (the step, the time, the
// solve's figures), what and the particle. Without it a NaN solve went on silently: its residual compares false
// against the tolerance (not counted as unconverged, nor as the worst residual), and a NaN step is refused as a
// closed voxel's would be (particle_darcy::stepAround), so the particles stood still.
template <class Where>
void requireFiniteSolution(const Eigen::VectorXd& x, const char* what, const Where& where) {
  for (Eigen::Index i = 0; i < x.size(); ++i)
    if (!std::isfinite(x[i]))
      throw sph::SimulationError(where() + ": the " + what + " of particle " + std::to_string(i) + " is not finite (" +
                                 std::to_string(x[i]) + "): the run went unstable");
}

// The kernel of the colour pass (colourRun) in single precision: the voxels' x spacing sx, invH = 1 / h,
// wn = d^3 x W's norm, cs2 = (2h)^2, and their SSE2 broadcasts, made once per pass.
struct ColourKernel {
  float sx = 1, invH = 1, wn = 1, cs2 = 1;
#if defined(__SSE2__)
  __m128 vsx, vinvH, vwn, vcs2;
#endif
  ColourKernel(float spacingX, float inverseH, float norm, float support2) : sx(spacingX), invH(inverseH), wn(norm), cs2(support2) {
#if defined(__SSE2__)
    vsx = _mm_set1_ps(sx), vinvH = _mm_set1_ps(invH), vwn = _mm_set1_ps(wn), vcs2 = _mm_set1_ps(cs2);
#endif
  }
};

// The particles' colour d^3 W(r) of one particle added to n consecutive open voxels of a grid row (the first at
// colour[0], region index v0; room: the voxels from colour[0] to the array's end; rx0 the first one's x offset from
// the particle, ryz2 the row's squared y and z offsets), in single precision (the colour is stored as float), four
// voxels at a time where SSE2 is there (x86-64 always); a voxel past the support adds 0. The run's last n % 4 voxels
// take the scalar formula (1 - q/2 unclamped, d^3 W's factors multiplied left to right), also four lanes at once
// where the array has room (the lanes past the run add 0 and are stored unchanged), so each voxel's colour is the
// same bits as summed one voxel at a time; the run's first voxels take the four-lane formula (1 - q/2 clamped at 0).
// A voxel is listed in touched when it first gets a colour above 0: so the listed voxels are exactly those with
// colour > 0, each once. Before, a voxel was listed when a particle's support first reached it (r^2 < (2h)^2 in
// float), though its weight could round to 0 there (q = r / h rounds to 2: the kernel's factor 1 - q/2 is 0): its
// colour stayed 0, and the next particle to reach it listed it again (the report's colour and label volumes summed
// it twice).
inline void colourRun(float* colour, std::size_t v0, int n, std::size_t room, float rx0, float ryz2, const ColourKernel& kern,
                      std::vector<std::size_t>& touched) {
  int k = 0;
#if defined(__SSE2__)
  const __m128 lane = _mm_set_ps(3, 2, 1, 0), vrx0 = _mm_set1_ps(rx0), vryz = _mm_set1_ps(ryz2), zero = _mm_setzero_ps();
  const __m128 one = _mm_set1_ps(1.0f), half = _mm_set1_ps(0.5f), two = _mm_set1_ps(2.0f);
  for (; k + 4 <= n; k += 4) {
    const __m128 rx = _mm_add_ps(vrx0, _mm_mul_ps(kern.vsx, _mm_add_ps(_mm_set1_ps(float(k)), lane)));
    const __m128 r2 = _mm_add_ps(_mm_mul_ps(rx, rx), vryz);
    const __m128 q = _mm_mul_ps(_mm_sqrt_ps(r2), kern.vinvH);
    const __m128 t = _mm_max_ps(zero, _mm_sub_ps(one, _mm_mul_ps(half, q)));
    const __m128 t2 = _mm_mul_ps(t, t);
    // Outside the support (r^2 >= 4 h^2) exactly 0: q's rounding can leave t a hair above 0 there.
    const __m128 inside = _mm_cmplt_ps(r2, kern.vcs2);
    const __m128 w = _mm_and_ps(inside, _mm_mul_ps(_mm_mul_ps(kern.vwn, _mm_mul_ps(t2, t2)), _mm_add_ps(_mm_mul_ps(two, q), one)));
    const __m128 old = _mm_loadu_ps(colour + k);
    if (const int first = _mm_movemask_ps(_mm_and_ps(_mm_cmpgt_ps(w, zero), _mm_cmpeq_ps(old, zero))))
      for (int l = 0; l < 4; ++l)
        if (first & (1 << l)) touched.push_back(v0 + std::size_t(k + l));
    _mm_storeu_ps(colour + k, _mm_add_ps(old, w));
  }
  if (k < n && std::size_t(k) + 4 <= room) { // the tail, four lanes with the scalar formula below
    const __m128 valid = _mm_cmplt_ps(lane, _mm_set1_ps(float(n - k)));
    const __m128 rx = _mm_add_ps(vrx0, _mm_mul_ps(kern.vsx, _mm_add_ps(_mm_set1_ps(float(k)), lane)));
    const __m128 r2 = _mm_add_ps(_mm_mul_ps(rx, rx), vryz);
    const __m128 q = _mm_mul_ps(_mm_sqrt_ps(r2), kern.vinvH);
    const __m128 t = _mm_sub_ps(one, _mm_mul_ps(half, q));
    const __m128 t2 = _mm_mul_ps(t, t);
    const __m128 inside = _mm_and_ps(valid, _mm_cmplt_ps(r2, kern.vcs2));
    const __m128 w = _mm_and_ps(inside, _mm_mul_ps(_mm_mul_ps(_mm_mul_ps(kern.vwn, t2), t2), _mm_add_ps(_mm_mul_ps(two, q), one)));
    const __m128 old = _mm_loadu_ps(colour + k);
    if (const int first = _mm_movemask_ps(_mm_and_ps(_mm_cmpgt_ps(w, zero), _mm_cmpeq_ps(old, zero))))
      for (int l = 0; l < 4; ++l)
        if (first & (1 << l)) touched.push_back(v0 + std::size_t(k + l));
    _mm_storeu_ps(colour + k, _mm_add_ps(old, w));
    return;
  }
#endif
  for (; k < n; ++k) {
    const float rx = rx0 + kern.sx * float(k), r2 = rx * rx + ryz2;
    if (!(r2 < kern.cs2)) continue;
    const float q = std::sqrt(r2) * kern.invH, t = 1.0f - 0.5f * q, t2 = t * t;
    const float w = kern.wn * t2 * t2 * (2.0f * q + 1.0f);
    if (colour[k] == 0.0f && w > 0.0f) touched.push_back(v0 + std::size_t(k));
    colour[k] += w;
  }
}

// The cement's share of the open space per region voxel for this step (share): the voxels listed last step
// (previous) are set to 0 first, then each voxel listed now (current: those with colour > 0, colourRun) takes
// shareOf(v). So every voxel not listed now reads 0, as its colour is. Before, only the listed voxels were written:
// a voxel listed in an earlier step and not now kept its old share, and the ghosts' pass, which decides a voxel's
// support edge in double where the colour pass does in float, could read it (weight ~1e-21 of a ghost's).
template <class ShareOf>
void updateShares(std::vector<double>& share, const std::vector<std::size_t>& previous, const std::vector<std::size_t>& current,
                  const ShareOf& shareOf) {
  for (std::size_t v : previous) share[v] = 0.0;
  for (std::size_t v : current) share[v] = shareOf(v);
}

} // namespace cementsph::scene::particle_darcy
