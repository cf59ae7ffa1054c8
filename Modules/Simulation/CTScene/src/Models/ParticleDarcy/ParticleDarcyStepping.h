// The particle-darcy model's time stepping rules (ParticleDarcyInjectionModel.cpp), apart so that its tests
// (ParticleDarcyTest) can hold each rule to a number without running a scene. Header-only; used by that model only.
#pragma once
#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstddef>
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

} // namespace cementsph::scene::particle_darcy
