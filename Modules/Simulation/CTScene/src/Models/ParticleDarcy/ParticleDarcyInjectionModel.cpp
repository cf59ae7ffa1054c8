// An incompressible SPH for creeping Darcy flow (issue 19, item 2), registered as "particle-darcy"
// ("incompressible-darcy-on-particles-isph"): a projection ISPH (Cummins & Rudman 1999, J Comput Phys
// 152:584) whose "projection" is Darcy's law itself, with the drag implicit in it.
//
// Model (SI inside; assumptions and regime):
//  * Creeping flow (Re << 1, inertia dropped) of an incompressible cement (Newtonian: the scene's viscosity
//    schedule mu(t); or a shear-thinning law, below) through a rigid pore-resolved medium: pore voxels open
//    (porosity phi = 1, permeability k = pore_permeability_m2, or the preset's k0 = h^5 / (Cf d^3) as the
//    voxel model), solid voxels closed.
//    Darcy's law u = -(M / phi) grad p, M = k / mu; div(M grad p) = -s with s the cannula's outflow. The
//    displaced fluid is at p = 0 (gauge) at the front (its viscosity neglected; cement/marrow ratio >> 1).
//    Dimensionless: the Darcy number k / d^2 and Re enter nowhere (no inertia); the solution scales with
//    mu Q / k, so the pressure is proportional to mu and the motion independent of it (exactly, here: the
//    CG is scale-equivariant and the step is chosen by displacement).
//  * Cement rheology: any law of the shared registry (Modules/Core/Rheology, rheology::makeRheology:
//    newtonian, power-law, carreau). A shear-thinning law is evaluated per particle at its Darcy-scale shear
//    rate gamma_i = rheology::darcyShearRate(|u_i| phi, k, phi, n) (Christopher & Middleman 1965, the voxel
//    model's per voxel), and mu_i enters the pressure matrix itself (mobility k / mu_i in its rows, the
//    harmonic mean of two particles' in a pair, the drag implicit in the solve): each step takes
//    kPicardRounds solves, the viscosities from the previous round's Darcy speeds (of p alone, not the
//    density correction). The cannula's drop is the law's tube integral (Rabinowitsch-Mooney, TubeFlow.h).
//    Curing (a time factor) is refused with one line: not built here yet.
//  * Particles on a lattice of spacing d = 2 particle_radius_mm each carry a fixed cement volume phi d^3:
//    the cement's volume is the count times that, exact; the emitted volume is inserted one particle at a
//    time as it accumulates.
//  * Kernel: Wendland C2 (Wendland 1995), h = 1.5 d, support 2h; F(r) = -dW/dr >= 0.
//  * Each particle's space volume Omega_i = d^3 n0 / n_i from its number density n_i = sum_j W_ij completed by
//    the closed voxels and the open space about it (n0: a full lattice's), so Omega_i = d^3 on a regular
//    packing and the operators below stay consistent where the packing is not.
//  * Pressure: -div(M grad p) = s with the symmetric pairwise Laplacian of Brookshaw 1985 (Proc. ASA 6:207)
//    / Cleary & Monaghan 1999 (J Comput Phys 148:227): A_ii = sum_j w_ij + g_i, A_ij = -w_ij,
//    w_ij = 2 Omega_i Omega_j M_ij F(r_ij) / r_ij (M_ij the harmonic mean of the mobilities: one M in a
//    pore-resolved medium), b_i = Q_i; and the same matrix with b_i = (d^3 - Omega_i) / tau for the
//    density-invariant correction pc of Shao & Lo 2003 (Adv Water Resour 26:787), relaxing each particle's
//    volume to d^3 over tau = 4 steps (without it the projection's divergence error let the cloud expand to
//    0.4 of its density), solved apart (Hu & Adams 2007: solvePressure) so that the pressure reported is the
//    Darcy pressure alone while the particles move with p + pc. Symmetric positive
//    definite: a Jacobi-preconditioned conjugate gradient, matrix-free over the pairs, warm-started,
//    single-threaded (deterministic; Eigen's OpenMP product was 200x slower on a loaded 2-core machine).
//  * Wall correction of the Laplacian (ours): a particle whose support is cut by solid (closed voxels, open space
//    hidden behind them, neighbours hidden behind solid) loses that part of its support's second moment
//    m_i = sum Omega_j F/r r^2 (3 on a full support), and with it the same share of the flux its pairs carry
//    along the wall. In the phantom's pore throats (one or two 0.47 mm voxels, a few spacings wide) that layer of
//    about h choked the throats: the tip pressure was 1.89 / 1.55 / 1.25 / 1.06 x the voxel model's at
//    d = 0.8 / 0.57 / 0.4 / 0.285 mm (0.1 ml, the voxel model's k). Each row is scaled by
//    s_i = 1 / (1 - m_missing,i / 3) (at most 4), a pair's weight by (s_i + s_j) / 2 (symmetric: the CG stands),
//    the ghosts' by s_i: the Laplacian's analogue of the gradient's renormalisation (Bonet & Lok 1999). Where
//    the support holds no solid s_i = 1 exactly (the uniform medium is unchanged). With it the same runs give
//    0.96 / 0.88 / 0.83 / 0.81 x: it converges from the first spacings to what the uncorrected Laplacian reaches
//    only at d -> 0 (about 0.8 x the voxel model on 0.47 mm voxels; the voxel model is the coarser there).
//    Measured on a plane wall: the near-wall pressure against the image solution 1.045 -> 0.987.
//  * The free surface needs no tuned threshold: open space is every pore voxel where the cement's share of
//    the open space about it, C(x) = sum_j d^3 W(x - x_j) / (1 - sum_c V_c W(x - x_c)) (the particles' colour
//    Shepard-normalised over the part of the kernel support that is not closed), is below 1/2 (on a lattice
//    the level 1/2 lies half a spacing beyond the last particles; a missing particle lowers C by 0.12 only;
//    against a wall C is 1 inside the cement as in open space, and 0 in an empty pore however narrow). g_i is
//    the part of particle i's support on open space, each such voxel a ghost at p = 0 placed by the
//    ghost-fluid rule (Gibou et al. 2002, J Comput Phys 176:205, as the voxel model's front): the surface
//    lies theta = (C_i - 1/2)/(C_i - C_g) of the way to the ghost, its weight 2 Omega_i V_c M F/r / theta
//    (theta >= 0.2). Interior particles have g_i = 0 exactly; a void that opens inside the cement becomes
//    open space at p = 0 and draws cement into it. Solid voxels and the region's sides contribute nothing
//    (no flux, a Neumann condition), so no pressure drives cement into solid.
//  * Velocity: u_i = -(M_i / phi) grad p_i with the corrected (renormalised) gradient of Bonet & Lok 1999
//    (Comput Methods Appl Mech Eng 180:97), grad p_i = B_i^-1 sum_j Omega_j (F/r)(p_j - p_i)(x_j - x_i),
//    B_i = sum_j Omega_j (F/r)(x_j - x_i)(x_j - x_i)^T, over the cement and the same ghosts (their p by the
//    ghost-fluid rule).
//  * No penetration: a particle never steps into a closed voxel (solid, the cannula's shaft, outside the
//    region): its step is taken axis by axis and a component that would cross into one is dropped.
//  * The outlet (the cannula as a flux inlet): the same inlet as the voxel model's (VoxelDarcyFilling::
//    setSource): a source uniform per unit volume in the ball of radius a = max(inner radius, d) about the
//    tip. Particle i takes Q_i = Q w_i / sum w, w_i = Omega_i s_i with s_i the share of its own volume (a
//    sphere of volume d^3, radius rp = (3/(4 pi))^(1/3) d) inside the ball (Omega_i: uniform per unit volume
//    where the particles pack unevenly, as the voxel model's share by pore volume): continuous as a particle crosses the ball's surface, the
//    ball's indicator as d -> 0. The outlet (tip) pressure is sum Q_i p_i / Q (the power the cannula delivers
//    over Q), for a uniform source the ball's volume mean, as the voxel model's sourcePressure. A spherical
//    source of this profile in a uniform medium gives p_tip = mu Q / (4 pi k)(1/r0 - 1/R),
//    1/r0 = 1/b + int_0^b f(r)^2 / r^2 dr (b = a + rp, f the enclosed share; 5a/6 as d -> 0), reported as
//    outlet_effective_radius_mm. Why not the earlier profile (1 - (r/a)^2)^2: it is a different inlet
//    (r0 = 0.61 a instead of 0.83 a), so on the same scene the two engines' tip pressures differed by about
//    1.36x by definition, not by physics. New particles go into the outlet ball's largest
//    gap (the farthest candidate point, on a d/2 lattice, from every particle) once the emitted volume holds
//    one particle's; the first ones fill the ball's lattice sites nearest the tip.
//  * Particle shifting (Lind et al. 2012, J Comput Phys 231:1499, Eqs. 9, 13): dr_s = -D grad C_i,
//    D = A h |u_i| dt (A = 2), grad C_i = sum_j Omega_j (1 + 0.2 (W_ij / W(d))^4) grad W_ij, with closed voxels
//    counted as occupied (no pull toward walls) and, for a particle with open space in its support, the
//    component normal to the free surface removed (Lind's free-surface rule); at most 0.1 d a step; never
//    into a closed voxel.
//  * Time step, multi-rate: the pressure is quasi-static (no inertia), so one solve serves a macro step in which
//    the bulk of the particles (all but the fastest 5 %) moves at most 0.2 d, the cement grows by at most 2 %, and
//    the fastest particle needs at most 4 sub-steps (and at most the driver's dtMax). The particles faster than
//    that (the outlet ball and its throats) are sub-stepped (each sub-step <= 0.2 d, the no-penetration test
//    each time) along the macro step's frozen Darcy field (residual-corrected Shepard interpolation of the
//    particles' Darcy velocities, fading beyond the front); the emitted volume is inserted sub-step by sub-step.
//    Before, the fastest particle (at the outlet) set a single-rate step: one step per ~4 inserted particles.
//  * Evaluation of the closed space's sums (ours, issue 19's speed; an approximation, bounded here): the closed
//    voxels' part of each particle's number density n_i, of its concentration gradient (shifting) and of its
//    support's second moment (the wall correction) depends only on the particle's position (the closed set is
//    static). Each is summed exactly, once, at the voxel centres a particle comes near (closedNode) and
//    interpolated between the eight about the particle (closedSumsAt): the mean of the trilinear value and the
//    trilinear blend of the corners' first-order Taylor expansions (particle_darcy::blendedTrilinear, exact on
//    quadratics: it cancels trilinear interpolation's O(spacing^2) error), the gradients summed exactly at the
//    corners too (the number density's is the concentration gradient / d^3; the second moment's and the
//    concentration gradient's Jacobian are their own sums). Measured against the exact sums at every
//    particle-step of the 1 ml phantom run (68 264): number density max 0.082 % (mean 0.015 %) of a full
//    lattice's; second moment max 0.0022 (mean 0.0003) of a full support's 3, the wall factor s_i max 0.11 %
//    (mean 0.016 %); concentration gradient max 0.0020 / h (mean 0.0006 / h; its mean size 0.30 / h). Plain
//    trilinear values erred 20-25x more (number density max 1.7 %, s_i 1.8 %, gradient 0.038 / h; with the gradient read
//    trilinearly the plate's near-wall pressure fell from 0.976 to 0.949 of the image solution's, 0.984 blended).
//    Before, every particle summed its ~530 closed voxels every step. The open space about the cement (ghosts,
//    open space behind solid) is still summed voxel by voxel, each run of closed or cement voxels jumped at once;
//    the particles' colour is summed in single precision (it is stored so), four voxels at a time where SSE2 is
//    there, over the runs of open voxels (so its last bits depend on where a run starts).
//    Effect on the phantom oracles (against the voxel model; before -> after): 1 ml Dice 0.891 -> 0.889,
//    spreading +0.265 -> +0.271 mm, tip 0.931 -> 0.955x; 5 ml Dice 0.875 -> 0.885, spreading +0.386 -> +0.351 mm,
//    tip 1.006 -> 1.021x. The 5 ml run moves about this much with a change in the last bits (Dice 0.865 to 0.885,
//    +0.351 to +0.425 mm, 0.99 to 1.04x over four builds with the blended interpolant, two pairs of which differ
//    only in rounding; with plain trilinear values 0.865, +0.444 mm, 1.03x). Uniform medium, plates and hemisphere:
//    each figure within 1.1 points of before (ParticleDarcyTest). CPU (whole process, 1 thread, bundled phantom,
//    paper scene): about 0.71x of before at 1 ml, 0.65x at 5 ml; 41x the voxel model's at 5 ml (issue 19's 3x is
//    not met). Memory: the field holds 14 floats per node, in blocks of 8^3 nodes allocated where the cement
//    comes (peak memory at 1 ml 166 MB against 163 MB before; 220 MB with the whole grid's field).
// Published designs read for this: SPlisHSPlasH's DFSPH step (Bender & Koschier 2017), PySPH's ISPH/IISPH
// (Ihmsen et al. 2014), SPHinXsys's free-surface indicator (Zhang et al.), porous-media ISPH (Shao 2010).
#include "cementsph/scene/InjectionModel.h"
#include "../PointArrays.h"
#include "ParticleDarcyStepping.h"

#include "cementsph/rheology/Rheology.h"
#include "cementsph/rheology/TubeFlow.h"
#include "cementsph/sph/HagenPoiseuille.h"
#include "cementsph/sph/Simulation.h"

#include <Eigen/Dense>
#include <vtkCellArray.h>
#include <vtkDoubleArray.h>
#include <vtkPointData.h>
#include <vtkPoints.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace cementsph::scene {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kHOverD = 1.5;          // smoothing length / lattice spacing
constexpr double kMinOpenShare = 0.05;  // the open share of a support never counts as less (cementShare)
constexpr double kMinTheta = 0.2;        // ghost-fluid: smallest share of the way to a ghost (conditioning)
constexpr double kMinWallShare = 0.25;   // the wall correction never scales a row by more than 4
constexpr double kRelaxSteps = 4.0;      // density-invariant relaxation time / dt
constexpr int kPicardRounds = 2;         // pressure solves per step for a shear-thinning cement
constexpr double kMaxMoveOverD = 0.2;    // largest advective move per step (sub-step)
// Multi-rate stepping (moveMultiRate; chosen on the phantom at 1 ml against the voxel model, BENCHMARKS):
constexpr double kSubSteppedShare = 0.05; // at most this share of the particles, the fastest, is sub-stepped
constexpr double kMaxGrowth = 0.02;       // largest emitted volume per macro step / the cement's
constexpr int kMaxSubSteps = 4;           // largest number of sub-steps per macro step
constexpr double kMaxCorrectionOverDarcy = 2.0; // the step's speed is at most this times the fastest Darcy speed
constexpr double kShiftA = 2.0;          // Lind et al. 2012: D = A h |u| dt
constexpr double kMaxShiftOverD = 0.1;   // largest shift per step
constexpr double kCannulaWallM = 0.33e-3; // 11G regular wall (as the voxel model)
constexpr double kMaxSightTableBytes = 256e6; // the ghosts' sight tables' memory bound (ghostHidden)

// Wendland C2 in 3D, support 2h: W = 21/(16 pi h^3) (1 - q/2)^4 (2q + 1); F/r = -W'(r)/r = 105/(16 pi h^5) (1 - q/2)^3.
struct Kernel {
  double h = 1, support = 2, wNorm = 0, fNorm = 0, invH = 1; // invH = 1 / h: a product per evaluation, not a division
  explicit Kernel(double hh) : h(hh), support(2 * hh), wNorm(21.0 / (16 * kPi * hh * hh * hh)),
                               fNorm(105.0 / (16 * kPi * std::pow(hh, 5))), invH(1.0 / hh) {}
  double w(double r) const {
    const double q = r * invH;
    if (q >= 2) return 0;
    const double t = 1 - 0.5 * q;
    return wNorm * t * t * t * t * (2 * q + 1);
  }
  double fOverR(double r) const { // -dW/dr / r
    const double q = r * invH;
    if (q >= 2) return 0;
    const double t = 1 - 0.5 * q;
    return fNorm * t * t * t;
  }
};

// The outlet: a uniform source per unit volume in the ball of radius a (header). A particle's share is the
// part of its own volume (a sphere of volume d^3, radius rp) inside the ball, so the share changes
// continuously as a particle crosses the ball's surface and tends to the ball's indicator as d -> 0.
double sourceWeight(double r, double a, double rp) {
  if (r >= a + rp) return 0;
  if (r + rp <= a) return 1;
  const double vp = 4.0 / 3 * kPi * rp * rp * rp;
  if (r + a <= rp) return 4.0 / 3 * kPi * a * a * a / vp; // the ball inside the particle
  const double t = a + rp - r; // lens of two spheres a distance r apart
  return kPi * t * t * (r * r + 2 * r * (a + rp) - 3 * (a - rp) * (a - rp)) / (12 * r) / vp;
}
// The effective radius of the outlet's mean pressure: for a spherically symmetric source with enclosed share
// f(r), the source-weighted mean of the continuum pressure is mu Q / (4 pi k)(1/r0 - 1/R) with
// 1/r0 = 1/b + int_0^b f(r)^2 / r^2 dr, b the source's outer radius (for a uniform ball f = (r/a)^3: r0 = 5a/6).
double effectiveOutletRadius(double a, double rp) {
  const double b = a + rp;
  const int n = 20000;
  std::vector<double> enclosed(n + 1, 0.0);
  for (int k = 1; k <= n; ++k) {
    const double r0 = b * (k - 1) / n, r1 = b * k / n, rm = 0.5 * (r0 + r1);
    enclosed[k] = enclosed[k - 1] + sourceWeight(rm, a, rp) * rm * rm * (r1 - r0);
  }
  double integral = 0;
  for (int k = 1; k <= n; ++k) {
    const double rm = b * (k - 0.5) / n, f = 0.5 * (enclosed[k] + enclosed[k - 1]) / enclosed[n];
    integral += f * f / (rm * rm) * (b / n);
  }
  return 1.0 / (1.0 / b + integral);
}

class ParticleDarcyInjectionModel final : public InjectionModel {
public:
  void start(const InjectionSetup& in) override {
    const SceneConfig& scene = *in.scene;
    if (in.continuum)
      throw std::invalid_argument("scene: bone_model \"continuum\" needs pressure_model \"voxel-darcy\" (particle-darcy "
                                  "runs on pore-resolved CTs)");
    if (scene.hasSecondTip())
      throw std::invalid_argument("scene: second_tip_withdrawal_mm needs pressure_model \"voxel-darcy\" (particle-darcy "
                                  "has one outlet)");
    if (scene.curing().kind() != "none")
      throw std::invalid_argument("scene: curing_model \"" + scene.curing().kind() +
                                  "\" needs pressure_model \"voxel-darcy\" (particle-darcy has no curing yet)");
    scene_ = &scene;
    solid_ = in.solid;
    rho0_ = in.model.restDensity;
    tip_ = *scene.tipMm * 1e-3;
    axis_ = scene.direction.normalized();
    flowRate_ = scene.flowRateM3PerS();
    innerDiameter_ = scene.cannulaInnerDiameterMm * 1e-3;
    cannulaLength_ = scene.cannulaLengthMm * 1e-3;
    d_ = scene.spacingM();
    volume_ = d_ * d_ * d_; // phi = 1 in a pore voxel
    kernel_ = Kernel(kHOverD * d_);
    const double hPreset = in.model.smoothingLength;
    poreK_ = scene.porePermeabilityM2.value_or(std::pow(hPreset, 5) / (in.model.dragCoefficient * d_ * d_ * d_));
    if (!(poreK_ >= 1e-18 && poreK_ <= 1e-3))
      throw std::invalid_argument("scene: the pore permeability k0 = h^5 / (Cf d^3) = " + std::to_string(poreK_) +
                                  " m^2 is outside 1e-18 .. 1e-3 m^2 (give pore_permeability_m2)");
    viscosity_ = scene.viscositySchedule();
    // The cement's law from the shared registry (rheology::makeRheology: every law it holds, with the scene's
    // bounds; an unknown name or a parameter out of range is its one-line refusal), per particle if it thins.
    law_ = rheology::makeRheology(scene.viscosityLaw, scene.rheology);
    shearThinning_ = scene.viscosityLaw != "newtonian";
    const sph::VoxelGrid& g = solid_->grid;
    closed_.assign(g.count(), 0);
    for (std::size_t c = 0; c < g.count(); ++c) closed_[c] = solid_->solid[c];
    closeShaft();
    // Per voxel the closed voxels (closedRun_) or the open ones (openRun_) from it along +x, at most 255, 0 on the
    // other kind (particleColour's runs).
    closedRun_.assign(g.count(), 0), openRun_.assign(g.count(), 0);
    for (int k = 0; k < g.size[2]; ++k)
      for (int j = 0; j < g.size[1]; ++j) {
        const std::size_t row = g.index(0, j, k);
        for (int i = g.size[0]; i-- > 0;) {
          const std::size_t v = row + std::size_t(i);
          std::vector<std::uint8_t>& run = closed_[v] ? closedRun_ : openRun_;
          run[v] = std::uint8_t(i + 1 < g.size[0] && run[v + 1] ? std::min(run[v + 1] + 1, 255) : 1);
        }
      }
    inverseSpacingX_ = 1.0 / g.spacing[0];
    padClosed();
    markSightChecks();
    indexSightOffsets();
    sourceRadius_ = std::max(0.5 * innerDiameter_, d_);
    particleRadius_ = std::cbrt(3.0 / (4 * kPi)) * d_;
    effectiveRadius_ = effectiveOutletRadius(sourceRadius_, particleRadius_);
    if (shearThinning_) { // the scale of the viscosities: the law at the outlet ball's surface speed
      referenceViscosity_ = law_->viscosity(
          rheology::darcyShearRate(flowRate_ / (4 * kPi * sourceRadius_ * sourceRadius_), poreK_, 1.0, law_->flowIndex()));
      if (scene.viscosityLaw == "power-law")
        cannulaDrop_ = rheology::powerLawTubePressureDrop(scene.rheology.consistencyPaSn, scene.rheology.flowIndex,
                                                          cannulaLength_, flowRate_, innerDiameter_);
      else
        cannulaDrop_ = rheology::tubePressureDrop(*law_, cannulaLength_, flowRate_, innerDiameter_);
    }
    if (closedAt(tip_)) throw std::invalid_argument("scene: tip_mm lies in a closed voxel");
    // The outlet ball's lattice sites (filled first, nearest the tip first) and gap candidates (d/2 lattice),
    // those the tip sees: the ball does not reach through a strut or plate into the pore behind it.
    const int n = int(std::ceil(sourceRadius_ / d_));
    for (int i = -n; i <= n; ++i)
      for (int j = -n; j <= n; ++j)
        for (int k = -n; k <= n; ++k) {
          const Eigen::Vector3d p = tip_ + d_ * Eigen::Vector3d(i, j, k);
          if ((p - tip_).norm() <= sourceRadius_ && !closedAt(p) && !lineOfSightBlocked(tip_, p)) seeds_.push_back(p);
        }
    std::stable_sort(seeds_.begin(), seeds_.end(), [this](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
      return (a - tip_).squaredNorm() < (b - tip_).squaredNorm();
    });
    for (int i = -2 * n; i <= 2 * n; ++i)
      for (int j = -2 * n; j <= 2 * n; ++j)
        for (int k = -2 * n; k <= 2 * n; ++k) {
          const Eigen::Vector3d p = tip_ + 0.5 * d_ * Eigen::Vector3d(i, j, k);
          if ((p - tip_).norm() <= sourceRadius_ && !closedAt(p) && !lineOfSightBlocked(tip_, p)) candidates_.push_back(p);
        }
    if (seeds_.empty()) throw std::invalid_argument("scene: the outlet ball holds no open lattice site");
    {
      const int m = int(std::ceil(kernel_.support / d_));
      latticeNumber_ = 0;
      for (int i = -m; i <= m; ++i)
        for (int j = -m; j <= m; ++j)
          for (int k = -m; k <= m; ++k) latticeNumber_ += kernel_.w(d_ * std::sqrt(double(i * i + j * j + k * k)));
    }
    // The region's cell list (cells of the kernel support).
    lower_ = solid_->lowerM;
    for (int a = 0; a < 3; ++a)
      cells_[a] = std::max(1, int(std::ceil((solid_->upperM[a] - lower_[a]) / kernel_.support)));
  }

  double time() const override { return time_; }

  void advance(double dtMax) override {
    const double mu = shearThinning_ ? referenceViscosity_ : viscosity_->at(time_);
    mobility_ = poreK_ / mu;
    if (!shearThinning_) std::fill(mu_.begin(), mu_.end(), mu);
    if (x_.size() < seeds_.size()) { // the outlet ball fills first: no motion
      const double dt = std::min(dtMax, std::max((double(seeds_.size()) * volume_ - injected()) / flowRate_, 1e-12 * dtMax));
      time_ += dt;
      ++steps_;
      while (x_.size() < seeds_.size() && double(x_.size() + 1) * volume_ <= injected() * (1 + 1e-12)) add(seeds_[x_.size()], 0.0, mu);
      solveIfAny();
      outlet_ = {time_, outletPressure(), cannulaDrop(mu)};
      return;
    }
    geometry();
    // A shear-thinning cement: Picard rounds on the per-particle viscosity (solve, Darcy speeds, the law at
    // each particle's Darcy-scale shear rate); the first round takes the last step's viscosities.
    const int rounds = shearThinning_ ? kPicardRounds : 1;
    for (int k = 0; k < rounds; ++k) {
      if (k > 0) updateViscosity();
      solvePressure();
      velocities();
    }
    if (shearThinning_) updateViscosity();
    outlet_ = {time_, outletPressure(), cannulaDrop(mu)};
    // The step follows the particles' whole speed (p + pc: the uniform medium's pressure just outside the
    // outlet ball needs the correction's motion resolved there, +9 % against the oracle with the step set by the
    // Darcy speed alone), but never falls below 0.2 d / (kMaxCorrectionOverDarcy x the fastest Darcy speed): the
    // correction's speed scales as 1 / tau = 1 / (kRelaxSteps dt), so a step set by it alone fed back into
    // itself. Seen on the phantom at 5 ml (about 4.5 ml in, a particle the correction could not move): dt fell
    // 1e-2 -> 1e-146 s within 50 steps, and the run never ended (BENCHMARKS' 'did not finish in 22 CPU-min').
    double vmax = 0, vmaxDarcy = 0;
    for (std::size_t i = 0; i < u_.size(); ++i) vmax = std::max(vmax, u_[i].norm()), vmaxDarcy = std::max(vmaxDarcy, speed_[i]);
    vmax = std::min(vmax, kMaxCorrectionOverDarcy * vmaxDarcy);
    const double dt = macroStep(dtMax, vmaxDarcy);
    moveMultiRate(dt);
    lastDt_ = dt;
    ++steps_;
    trace(dt, vmax);
  }

  TipRecord outlet() const override { return outlet_; }
  double injectedVolumeM3() const override { return injected(); }
  double cementVolumeM3() const override { return double(x_.size()) * volume_; }

  std::string state() const override {
    return std::to_string(x_.size()) + " particles, " + std::to_string(steps_) + " steps";
  }

  std::vector<double> cementDensity() const override {
    const sph::VoxelGrid& g = solid_->grid;
    std::vector<double> rho(g.count(), 0.0);
    const double perVoxel = rho0_ * volume_ / g.voxelVolume();
    for (const auto& p : x_) {
      const long c = voxel(p);
      if (c >= 0) rho[std::size_t(c)] += perVoxel;
    }
    return rho;
  }

  // Label 1 on the open voxels the cement occupies: where its share of the open space is at least 1/2, the
  // same surface the pressure solve puts p = 0 on (so the label map's volume is the particles' to within the
  // front's half voxel). No leak classes: this engine runs on pore-resolved CTs only.
  std::vector<std::uint8_t> cementLabels() const override {
    std::vector<float> colour;
    std::vector<std::size_t> touched;
    particleColour(colour, touched);
    std::vector<std::uint8_t> labels(solid_->grid.count(), 0);
    for (std::size_t v : touched)
      if (!closed_[v] && double(colour[v]) / openShare(closedColourAt(v)) >= 0.5) labels[v] = 1;
    return labels;
  }

  vtkSmartPointer<vtkPolyData> cement() const override {
    const vtkIdType n = vtkIdType(x_.size());
    auto points = vtkSmartPointer<vtkPoints>::New();
    points->SetDataTypeToDouble();
    points->SetNumberOfPoints(n);
    auto make = [n](const char* name, int components) { return detail::pointArray(name, components, n); };
    auto pressure = make("pressure_pa", 1), velocity = make("velocity_m_per_s", 3), volume = make("cement_volume_mm3", 1),
         age = make("age_s", 1), density = make("density_kg_per_m3", 1);
    auto verts = vtkSmartPointer<vtkCellArray>::New();
    for (vtkIdType i = 0; i < n; ++i) {
      const std::size_t k = std::size_t(i);
      points->SetPoint(i, x_[k].x() * 1e3, x_[k].y() * 1e3, x_[k].z() * 1e3);
      pressure->SetTuple1(i, k < p_.size() ? p_[k] : 0.0);
      const Eigen::Vector3d v = k < u_.size() ? u_[k] : Eigen::Vector3d::Zero();
      velocity->SetTuple3(i, v.x(), v.y(), v.z());
      volume->SetTuple1(i, volume_ * 1e9);
      age->SetTuple1(i, time_ - birth_[k]);
      density->SetTuple1(i, rho0_);
      verts->InsertNextCell(1, &i);
    }
    auto poly = vtkSmartPointer<vtkPolyData>::New();
    poly->SetPoints(points);
    poly->SetVerts(verts);
    for (auto* a : {pressure.Get(), velocity.Get(), volume.Get(), age.Get(), density.Get()}) poly->GetPointData()->AddArray(a);
    return poly;
  }

  void report(InjectionSummary& s, nlohmann::json& e) const override {
    double spread = 0;
    std::size_t inSolid = 0;
    for (const auto& p : x_) {
      spread += (p - tip_).norm();
      const long c = voxel(p);
      if (c < 0 || solid_->solid[std::size_t(c)]) ++inSolid;
    }
    if (!x_.empty()) spread /= double(x_.size());
    s.steps = steps_;
    s.particles = ParticleCounts{x_.size(), 0, 0, 0};
    s.solidVoxelsKept = solid_->solidVoxels;
    s.resistance = scene_->porePermeabilityM2 ? "pore-permeability (scene)" : "pore-permeability (preset drag k0)";
    s.viscosityLaw = scene_->viscosityLaw;
    s.pressureIsPhysical = true;
    s.meanSpreadingDistanceMm = spread * 1e3;
    s.massBalanceError = injected() > 0 ? (injected() - cementVolumeM3()) / injected() : 0.0;
    s.fluidInSolidFraction = x_.empty() ? 0.0 : double(inSolid) / double(x_.size());
    s.finalViscosityPaS = shearThinning_ ? referenceViscosity_ : viscosity_->at(time_);
    if (!mu_.empty()) {
      e["apparent_viscosity_min_pa_s"] = *std::min_element(mu_.begin(), mu_.end());
      e["apparent_viscosity_max_pa_s"] = *std::max_element(mu_.begin(), mu_.end());
    }
    s.leakageAssessed = false;
    addPressureSolverFigures(e, solves_, iterations_, worstResidual_, unconverged_, solveSeconds_);
    e["pore_permeability_m2"] = poreK_;
    e["density_correction_iterations_mean"] = solves_ ? double(correctionIterations_) / double(solves_) : 0.0;
    e["outlet_source_radius_mm"] = sourceRadius_ * 1e3;
    e["outlet_effective_radius_mm"] = effectiveRadius_ * 1e3;
    // The voxel model's outlet pressure definition (the plain mean over the outlet ball), for comparison.
    double ballSum = 0;
    std::size_t ballCount = 0;
    for (std::size_t i = 0; i < x_.size() && i < p_.size(); ++i)
      if ((x_[i] - tip_).norm() <= sourceRadius_) ballSum += p_[i], ++ballCount;
    e["outlet_ball_mean_pressure_pa"] = ballCount ? ballSum / double(ballCount) : 0.0;
    {
      // The label map's volume against the particles' (the front's half voxel apart), and the colour's volume
      // on open voxels (the share of the kernel sums that falls on closed space is missing from it).
      std::vector<float> colour;
      std::vector<std::size_t> touched;
      particleColour(colour, touched);
      double labelled = 0, colourVolume = 0;
      const double vc = solid_->grid.voxelVolume();
      for (std::size_t v : touched) {
        colourVolume += vc * colour[v];
        if (double(colour[v]) / openShare(closedColourAt(v)) >= 0.5) labelled += vc;
      }
      e["cement_label_volume_ml"] = labelled * 1e6;
      e["colour_volume_on_open_voxels_ml"] = colourVolume * 1e6;
    }
    e["particle_spacing_mm"] = d_ * 1e3;
    e["smoothing_length_mm"] = kernel_.h * 1e3;
    e["particle_volume_mm3"] = volume_ * 1e9;
    e["front_particles"] = frontParticles_;
    e["sub_steps"] = subSteps_; // the fast particles' sub-steps, summed over the macro steps (moveMultiRate)
    e["sub_steps_clamped"] = subStepsClamped_; // macro steps whose fastest particle needed more than kMaxSubSteps
    e["sub_step_moves_capped"] = cappedSubStepMoves_; // particle sub-steps cut to 0.2 d (fell behind the field)
    e["pairs_hidden_behind_solid_per_step"] = steps_ ? double(hiddenPairs_) / double(steps_) : 0.0;
    e["geometry_wall_s"] = geometrySeconds_;
    e["cannula_shaft_voxels_closed"] = shaftVoxels_;
  }

private:
  double injected() const { return flowRate_ * time_; }

  // By hand only (not in CI): PARTICLE_DARCY_TRACE_STEPS=N prints a line every N steps to stderr (step, time,
  // dt, particles, pairs, CG iterations so far, unconverged solves, geometry and solve seconds) to find where a
  // long run spends its time.
  void trace(double dt, double vmax) const {
    static const long every = [] {
      const char* v = std::getenv("PARTICLE_DARCY_TRACE_STEPS");
      return v && *v ? std::atol(v) : 0L;
    }();
    if (every <= 0 || steps_ % std::size_t(every) != 0) return;
    std::fprintf(stderr, "particle-darcy step %zu t %.4g s dt %.3g s vmax %.3g m/s particles %zu pairs %zu front %zu "
                 "cg %zu (+%zu corr) unconverged %zu worst %.2g geometry %.1f s solve %.1f s\n",
                 steps_, time_, dt, vmax, x_.size(), pairI_.size(), frontParticles_, iterations_, correctionIterations_,
                 unconverged_, worstResidual_, geometrySeconds_, solveSeconds_);
  }

  // ROI voxel index holding p, or -1 outside the region.
  long voxel(const Eigen::Vector3d& p) const {
    const sph::VoxelGrid& g = solid_->grid;
    long idx[3];
    for (int a = 0; a < 3; ++a) {
      const double u = (p[a] - g.origin[a]) / g.spacing[a];
      const long i = long(std::floor(u + 0.5));
      if (i < 0 || i >= g.size[a]) return -1;
      idx[a] = i;
    }
    return long(g.index(int(idx[0]), int(idx[1]), int(idx[2])));
  }
  bool closedAt(const Eigen::Vector3d& p) const {
    const long c = voxel(p);
    return c < 0 || closed_[std::size_t(c)];
  }

  // The cannula's shaft behind the outlet is closed (as the voxel model's closeShaft).
  void closeShaft() {
    if (!scene_->cannulaWall) return;
    const sph::VoxelGrid& g = solid_->grid;
    const double outer = 0.5 * innerDiameter_ + kCannulaWallM, behind = 0.5 * g.spacing.maxCoeff();
    for (int k = 0; k < g.size[2]; ++k)
      for (int j = 0; j < g.size[1]; ++j)
        for (int i = 0; i < g.size[0]; ++i) {
          const Eigen::Vector3d r = g.centre(i, j, k) - tip_;
          const double s = r.dot(axis_);
          const std::size_t c = g.index(i, j, k);
          if (s < -behind && s >= -cannulaLength_ && (r - s * axis_).norm() <= outer && !closed_[c]) {
            closed_[c] = 1;
            ++shaftVoxels_;
          }
        }
  }

  // The closed space's share of the colour function at an open voxel, sum_c V_c W(x - x_c) over the closed
  // voxels and the space outside the region: static (the closed set does not change), so computed once per
  // voxel when first asked for (only the voxels the cement comes near ever are).
  double closedColourAt(std::size_t v) const {
    if (closedColour_.empty()) closedColour_.assign(solid_->grid.count(), -1.0f);
    if (closedColour_[v] >= 0.0f) return closedColour_[v];
    const sph::VoxelGrid& g = solid_->grid;
    const int i = int(v % std::size_t(g.size[0])), j = int((v / std::size_t(g.size[0])) % std::size_t(g.size[1]));
    const int k = int(v / (std::size_t(g.size[0]) * std::size_t(g.size[1])));
    const std::uint8_t* centre = closedPad_.data() + paddedIndex(i, j, k);
    double c = 0;
    // Four sums (entry q into sum q % 4, the last size % 4 entries into the first), no chain of dependent additions.
    // Only the closed voxels add: an open one would add weight x 0 = +0, which changes no sum (none is ever -0), so
    // skipping it gives the same bits; in pore space most of the support is open.
    double part[4] = {0, 0, 0, 0};
    const std::size_t whole = stencil_.size() - stencil_.size() % 4;
    for (std::size_t q = 0; q < stencil_.size(); ++q)
      if (centre[stencilOffsets_[q]]) part[q < whole ? q & 3 : 0] += stencil_[q].weight;
    c = (part[0] + part[1]) + (part[2] + part[3]);
    // Stored as a float and returned as stored: the first call's answer is every later call's (it used to
    // return the unrounded sum once, so a voxel's share depended on whether it had been asked before).
    closedColour_[v] = float(c);
    return closedColour_[v];
  }
  // The closed space's sums at a point x (static: the closed set does not change): its number density
  // sum_c (V_c / d^3) W, its concentration gradient sum_c V_c F/r (x_c - x) and its second moment sum_c V_c F/r |x_c - x|^2,
  // over the closed voxels and the space outside the region. Evaluated exactly on the voxel centres (closedNode:
  // once per node, with their gradients, the first time a particle needs it) and interpolated between them by
  // particle_darcy::blendedTrilinear (exact on quadratics; each sum is a C2 function of x, Wendland C2: header).
  struct ClosedSums {
    double num = 0, missing = 0;
    Eigen::Vector3d grad = Eigen::Vector3d::Zero();
  };
  const float* closedNode(int i, int j, int k) {
    // The nodes are kept in blocks of 8 x 8 x 8, each allocated when a particle first needs one of its nodes: the
    // memory follows the cement, not the CT (a fine micro-CT's whole grid at 14 floats a voxel would not fit).
    const int I = i + pad_, J = j + pad_, K = k + pad_;
    std::unique_ptr<float[]>& block =
        closedField_[std::size_t(I >> 3) + std::size_t(fieldBlocks_[0]) * (std::size_t(J >> 3) + std::size_t(fieldBlocks_[1]) * std::size_t(K >> 3))];
    if (!block) {
      block.reset(new float[std::size_t(kFieldValues) * 512]);
      std::fill(block.get(), block.get() + std::size_t(kFieldValues) * 512, std::numeric_limits<float>::quiet_NaN());
    }
    float* node = block.get() + std::size_t(kFieldValues) * std::size_t((I & 7) + 8 * ((J & 7) + 8 * (K & 7)));
    if (!std::isnan(node[0])) return node;
    const std::uint8_t* centre = closedPad_.data() + paddedIndex(i, j, k);
    // Only the closed voxels add (closed is 0 or 1: an open one would add +-0, which changes no sum, none being -0
    // ever, so skipping it gives the same bits); the offsets are read apart from the entries (stencilOffsets_: the
    // same offsets in the same order), so an open voxel costs a byte read, not an entry's 15 values.
    double s[kFieldValues] = {};
    for (std::size_t q = 0; q < fieldStencil_.size(); ++q) {
      if (!centre[stencilOffsets_[q]]) continue;
      const FieldEntry& e = fieldStencil_[q];
      s[0] += e.w, s[1] += e.fr[0], s[2] += e.fr[1], s[3] += e.fr[2], s[4] += e.fr2;
      s[5] += e.dm[0], s[6] += e.dm[1], s[7] += e.dm[2];
      for (int a = 0; a < 6; ++a) s[8 + a] += e.dg[a];
    }
    for (int a = 0; a < kFieldValues; ++a) node[a] = float(s[a]);
    return node;
  }
  // A position or sum that is not finite (a run gone unstable) throws sph::SimulationError naming the particle, the
  // step and the time (particle_darcy::fieldCell, requireFiniteSum): a NaN would index the field out of its bounds.
  ClosedSums closedSumsAt(std::size_t particle) {
    const sph::VoxelGrid& g = solid_->grid;
    const Eigen::Vector3d& p = x_[particle];
    const auto where = [&] {
      return "particle-darcy: particle " + std::to_string(particle) + " of " + std::to_string(x_.size()) + " at step " +
             std::to_string(steps_) + " (t = " + std::to_string(time_) + " s), the closed space's sums (closedSumsAt)";
    };
    int c[3];
    Eigen::Vector3d t;
    particle_darcy::fieldCell(p, g.origin, g.spacing, g.size.data(), c, t, where);
    // Each sum with its gradient (the number density's is the concentration gradient / d^3; the second moment's
    // and the concentration gradient's Jacobian are stored): particle_darcy::blendedTrilinear, exact on quadratics.
    double num[8], missing[8], gradA[3][8];
    Eigen::Vector3d numGrad[8], missingGrad[8], gradGrad[3][8];
    for (int corner = 0; corner < 8; ++corner) {
      const float* node = closedNode(c[0] + (corner & 1), c[1] + ((corner >> 1) & 1), c[2] + ((corner >> 2) & 1));
      const Eigen::Vector3d nodeGrad(node[1], node[2], node[3]);
      num[corner] = node[0], numGrad[corner] = nodeGrad / volume_;
      missing[corner] = node[4], missingGrad[corner] = Eigen::Vector3d(node[5], node[6], node[7]);
      // The concentration gradient's Jacobian (symmetric: xx, yy, zz, xy, xz, yz), one row per component.
      const float* J = node + 8;
      gradGrad[0][corner] = Eigen::Vector3d(J[0], J[3], J[4]), gradGrad[1][corner] = Eigen::Vector3d(J[3], J[1], J[5]);
      gradGrad[2][corner] = Eigen::Vector3d(J[4], J[5], J[2]);
      for (int a = 0; a < 3; ++a) gradA[a][corner] = node[1 + a];
    }
    ClosedSums out;
    out.num = particle_darcy::blendedTrilinear(num, numGrad, t, g.spacing);
    out.missing = particle_darcy::blendedTrilinear(missing, missingGrad, t, g.spacing);
    for (int a = 0; a < 3; ++a) out.grad[a] = particle_darcy::blendedTrilinear(gradA[a], gradGrad[a], t, g.spacing);
    particle_darcy::requireFiniteSum(out.num, "number density", where);
    particle_darcy::requireFiniteSum(out.missing, "second moment", where);
    particle_darcy::requireFiniteSum(out.grad.squaredNorm(), "concentration gradient", where);
    return out;
  }
  // The open share of a kernel support, 1 - (closed share), bounded below so that a voxel walled in on almost
  // every side still has a finite indicator.
  static double openShare(double closedColour) { return std::max(1.0 - closedColour, kMinOpenShare); }
  // The cement's share of the open space about open voxel v: the particles' colour sum_j d^3 W(x - x_j)
  // over the open part of the kernel support (Shepard-normalised over the space cement can occupy). It is 1
  // inside the cement, against a wall as in open space, and 0 in an empty pore however narrow: the earlier
  // indicator (particles' colour plus the closed share, >= 1/2) read an empty pore whose walls filled half the
  // support as cement, so the front lost its p = 0 ghosts there.
  double cementShare(std::size_t v) const { return double(colour_[v]) / openShare(closedColourAt(v)); }

  // The region's voxels whose centres may lie within radius of p: lo..hi per axis (clipped to the region).
  void voxelBox(const Eigen::Vector3d& p, double radius, int lo[3], int hi[3]) const {
    const sph::VoxelGrid& g = solid_->grid;
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::max(0, int(std::ceil((p[a] - radius - g.origin[a]) / g.spacing[a])));
      hi[a] = std::min(g.size[a] - 1, int(std::floor((p[a] + radius - g.origin[a]) / g.spacing[a])));
    }
  }

  // The particles' colour sum_j d^3 W(x_v - x_j) at the open voxels within a support of a particle; the voxels
  // written are listed in touched (and only those of the previous call are reset).
  void particleColour(std::vector<float>& colour, std::vector<std::size_t>& touched) const {
    const sph::VoxelGrid& g = solid_->grid;
    const double cs = kernel_.support;
    colour.resize(g.count(), 0.0f);
    for (std::size_t v : touched) colour[v] = 0.0f;
    touched.clear();
    const particle_darcy::ColourKernel kern(float(g.spacing[0]), float(kernel_.invH), float(volume_ * kernel_.wNorm),
                                            float(kernel_.support * kernel_.support));
    for (const auto& p : x_) {
      int lo[3], hi[3];
      voxelBox(p, cs, lo, hi);
      for (int k = lo[2]; k <= hi[2]; ++k) {
        const double rz = (g.origin[2] + g.spacing[2] * k) - p[2], rz2 = rz * rz;
        for (int j = lo[1]; j <= hi[1]; ++j) {
          const double ry = (g.origin[1] + g.spacing[1] * j) - p[1], ry2 = ry * ry;
          int i0, i1;
          if (!rowRange(p[0], ry2, rz2, lo[0], hi[0], i0, i1)) continue;
          const std::size_t row = g.index(0, j, k);
          for (int i = i0; i <= i1;) {
            const std::size_t v = row + std::size_t(i);
            if (const std::uint8_t skip = closedRun_[v]) { // a run of closed voxels at once
              i += skip;
              continue;
            }
            const int n = std::min(int(openRun_[v]), i1 - i + 1); // an open run, summed four voxels at a time
            particle_darcy::colourRun(colour.data() + v, v, n, colour.size() - v, float((g.origin[0] + g.spacing[0] * i) - p[0]),
                                      float(ry2 + rz2), kern, touched);
            i += n;
          }
        }
      }
    }
  }

  // The voxels of row (j, k) whose centres may lie within the kernel support of a point at x = px, given the
  // row's squared offsets ry2, rz2: the sphere's chord, widened by one voxel each way against rounding and
  // clipped to lo..hi (the callers keep their own r^2 < support^2 test, so the set visited is the box's).
  // False for a row the sphere misses: (rx^2 + ry^2) + rz^2 >= ry^2 + rz^2 in floating point too.
  bool rowRange(double px, double ry2, double rz2, int lo, int hi, int& i0, int& i1) const {
    const sph::VoxelGrid& g = solid_->grid;
    const double rest = kernel_.support * kernel_.support - (ry2 + rz2);
    if (!(rest > 0)) return false;
    const double half = std::sqrt(rest), inverse = inverseSpacingX_; // 1 / spacing, made once (start)
    // Truncation for floor and ceil: it widens the range by at most a voxel (a superset: lo clips it), no rounding call.
    i0 = std::max(lo, int((px - half - g.origin[0]) * inverse) - 1);
    i1 = std::min(hi, int((px + half - g.origin[0]) * inverse) + 1);
    return i0 <= i1;
  }

  // The closed set padded by a kernel support on every side with closed voxels (the space outside the region
  // counts as closed), so the loops over a support need no bounds test; and the stencil of a voxel centre's
  // support (offsets within it, in the padded grid, with V_c W(r)) for closedColourAt.
  void padClosed() {
    const sph::VoxelGrid& g = solid_->grid;
    const double cs = kernel_.support, vc = g.voxelVolume();
    pad_ = 0;
    for (int a = 0; a < 3; ++a) pad_ = std::max(pad_, int(std::ceil(cs / g.spacing[a])) + 2);
    for (int a = 0; a < 3; ++a) padSize_[a] = g.size[a] + 2 * pad_;
    closedPad_.assign(std::size_t(padSize_[0]) * std::size_t(padSize_[1]) * std::size_t(padSize_[2]), 1);
    for (int k = 0; k < g.size[2]; ++k)
      for (int j = 0; j < g.size[1]; ++j)
        for (int i = 0; i < g.size[0]; ++i) closedPad_[paddedIndex(i, j, k)] = closed_[g.index(i, j, k)];
    // The closed voxels' summed-volume table over the padded grid (closedInBox): closedSum_ at (i, j, k) + 1 holds
    // the count in the padded box [0, i] x [0, j] x [0, k].
    const std::size_t sx = std::size_t(padSize_[0]) + 1, sy = std::size_t(padSize_[1]) + 1, sz = std::size_t(padSize_[2]) + 1;
    closedSum_.assign(sx * sy * sz, 0);
    for (std::size_t k = 1; k < sz; ++k)
      for (std::size_t j = 1; j < sy; ++j)
        for (std::size_t i = 1; i < sx; ++i)
          closedSum_[i + sx * (j + sy * k)] =
              std::int32_t(closedPad_[(i - 1) + std::size_t(padSize_[0]) * ((j - 1) + std::size_t(padSize_[1]) * (k - 1))]) +
              closedSum_[(i - 1) + sx * (j + sy * k)] + closedSum_[i + sx * ((j - 1) + sy * k)] + closedSum_[i + sx * (j + sy * (k - 1))] -
              closedSum_[(i - 1) + sx * ((j - 1) + sy * k)] - closedSum_[(i - 1) + sx * (j + sy * (k - 1))] -
              closedSum_[i + sx * ((j - 1) + sy * (k - 1))] + closedSum_[(i - 1) + sx * ((j - 1) + sy * (k - 1))];
    int m[3];
    for (int a = 0; a < 3; ++a) m[a] = int(std::floor(cs / g.spacing[a]));
    stencil_.clear();
    for (int dk = -m[2]; dk <= m[2]; ++dk)
      for (int dj = -m[1]; dj <= m[1]; ++dj)
        for (int di = -m[0]; di <= m[0]; ++di) {
          const double r2 = Eigen::Vector3d(di * g.spacing[0], dj * g.spacing[1], dk * g.spacing[2]).squaredNorm();
          if (r2 < cs * cs)
            stencil_.push_back({std::ptrdiff_t(di) + std::ptrdiff_t(padSize_[0]) * (std::ptrdiff_t(dj) + std::ptrdiff_t(padSize_[1]) * dk),
                                vc * kernel_.w(std::sqrt(r2))});
        }
    // The closed sums' stencil (closedNode): the same offsets with (V_c / d^3) W, V_c F/r r and V_c F/r r^2.
    fieldStencil_.clear();
    for (int dk = -m[2]; dk <= m[2]; ++dk)
      for (int dj = -m[1]; dj <= m[1]; ++dj)
        for (int di = -m[0]; di <= m[0]; ++di) {
          const Eigen::Vector3d r(di * g.spacing[0], dj * g.spacing[1], dk * g.spacing[2]);
          const double r2 = r.squaredNorm();
          if (r2 >= cs * cs) continue;
          const double rn = std::sqrt(r2), f = kernel_.fOverR(rn);
          FieldEntry e;
          e.offset = std::ptrdiff_t(di) + std::ptrdiff_t(padSize_[0]) * (std::ptrdiff_t(dj) + std::ptrdiff_t(padSize_[1]) * dk);
          e.w = vc / volume_ * kernel_.w(rn);
          for (int a = 0; a < 3; ++a) e.fr[a] = vc * f * r[a];
          e.fr2 = vc * f * r2;
          // d/dx of V_c F(r) r at the point x (r = x_c - x): -V_c (F'(r) + F(r) / r) (x_c - x), with F / r = fNorm t^3 and
          // F' = fNorm (t^3 - 1.5 q t^2), t = 1 - q / 2.
          const double q = rn / kernel_.h, t = std::max(0.0, 1 - 0.5 * q);
          const double slope = kernel_.fNorm * (2 * t * t * t - 1.5 * q * t * t);
          for (int a = 0; a < 3; ++a) e.dm[a] = -vc * slope * r[a];
          // d/dx_b of V_c (F/r)(r) r_a: V_c (1.5 fNorm t^2 r_a r_b / (h |r|) - fNorm t^3 delta_ab).
          const double radial = rn > 0 ? 1.5 * kernel_.fNorm * t * t / (kernel_.h * rn) : 0.0, diagonal = -kernel_.fNorm * t * t * t;
          const int ab[6][2] = {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {0, 2}, {1, 2}};
          for (int o = 0; o < 6; ++o) e.dg[o] = vc * (radial * r[ab[o][0]] * r[ab[o][1]] + (ab[o][0] == ab[o][1] ? diagonal : 0.0));
          fieldStencil_.push_back(e);
        }
    // The two stencils hold the same offsets in the same order (the same loops and test): read apart by the sums.
    stencilOffsets_.clear();
    for (const StencilEntry& e : stencil_) stencilOffsets_.push_back(e.offset);
    if (stencilOffsets_.size() != fieldStencil_.size())
      throw std::logic_error("particle-darcy: the closed colour's and the closed sums' stencils differ");
    for (std::size_t q = 0; q < stencilOffsets_.size(); ++q)
      if (stencilOffsets_[q] != fieldStencil_[q].offset)
        throw std::logic_error("particle-darcy: the closed colour's and the closed sums' stencils differ");
    for (int a = 0; a < 3; ++a) fieldBlocks_[a] = (padSize_[a] + 7) / 8;
    closedField_.clear();
    closedField_.resize(std::size_t(fieldBlocks_[0]) * std::size_t(fieldBlocks_[1]) * std::size_t(fieldBlocks_[2]));
  }
  std::size_t paddedIndex(int i, int j, int k) const {
    return std::size_t(i + pad_) + std::size_t(padSize_[0]) * (std::size_t(j + pad_) + std::size_t(padSize_[1]) * std::size_t(k + pad_));
  }

  // Line of sight across thin struts (issue 19): two particles on either side of a one-voxel strut are within
  // a kernel support of each other, and so is an empty pore behind it. Without a test they would exchange
  // flux through solid (the pair's Laplacian weight, the gradient's terms, a p = 0 ghost pulling the cement
  // toward a wall it cannot cross). sightCheck_ marks the region voxels with a closed region voxel within a
  // support plus a voxel's half diagonal (a segment shorter than the support, starting in such a voxel, can
  // cross a closed one only then); elsewhere (a uniform medium, most of a pore) no segment is walked. The
  // region's sides are not walls here: a segment between two points of the region stays inside it.
  void markSightChecks() {
    const sph::VoxelGrid& g = solid_->grid;
    const double reach = kernel_.support + 0.5 * g.spacing.norm();
    std::vector<std::uint8_t> a(closed_.begin(), closed_.end()), b(a.size());
    if (shaftVoxels_ == 0 && std::find(a.begin(), a.end(), std::uint8_t(1)) == a.end()) {
      sightCheck_.assign(a.size(), 0);
      return;
    }
    for (int axis = 0; axis < 3; ++axis) { // separable box dilation, one axis at a time
      const int m = int(std::ceil(reach / g.spacing[axis]));
      const std::size_t stride = axis == 0 ? 1 : axis == 1 ? std::size_t(g.size[0]) : std::size_t(g.size[0]) * std::size_t(g.size[1]);
      for (int k = 0; k < g.size[2]; ++k)
        for (int j = 0; j < g.size[1]; ++j)
          for (int i = 0; i < g.size[0]; ++i) {
            const int at = axis == 0 ? i : axis == 1 ? j : k;
            const std::size_t v = g.index(i, j, k);
            std::uint8_t any = 0;
            for (int o = std::max(0, at - m); o <= std::min(g.size[axis] - 1, at + m) && !any; ++o)
              any = a[v + (std::ptrdiff_t(o) - at) * std::ptrdiff_t(stride)];
            b[v] = any;
          }
      a.swap(b);
    }
    sightCheck_ = std::move(a);
  }

  // The number of closed voxels in the box lo..hi of region indices (inclusive, within the padded grid).
  std::int32_t closedInBox(const int lo[3], const int hi[3]) const {
    const std::size_t sx = std::size_t(padSize_[0]) + 1, sy = std::size_t(padSize_[1]) + 1;
    const std::size_t x0 = std::size_t(lo[0] + pad_), y0 = std::size_t(lo[1] + pad_), z0 = std::size_t(lo[2] + pad_);
    const std::size_t x1 = std::size_t(hi[0] + pad_) + 1, y1 = std::size_t(hi[1] + pad_) + 1, z1 = std::size_t(hi[2] + pad_) + 1;
    auto at = [&](std::size_t i, std::size_t j, std::size_t k) { return closedSum_[i + sx * (j + sy * k)]; };
    return at(x1, y1, z1) - at(x0, y1, z1) - at(x1, y0, z1) - at(x1, y1, z0) + at(x0, y0, z1) + at(x0, y1, z0) +
           at(x1, y0, z0) - at(x0, y0, z0);
  }

  // Whether the segment from a to b passes through a closed voxel (a 3D DDA walk, Amanatides & Woo 1987, over
  // the voxels it crosses; the end points' own voxels are open by construction and not tested). The walk only
  // visits voxels in the index box between the end points' voxels, so a box with no closed voxel in it (the
  // summed-volume table, closedInBox: eight reads) answers "not blocked" without walking: the same answer.
  bool lineOfSightBlocked(const Eigen::Vector3d& a, const Eigen::Vector3d& b) const {
    const sph::VoxelGrid& g = solid_->grid;
    int cur[3], end[3], step[3], lo[3], hi[3];
    double tMax[3], tDelta[3], ua[3], du[3];
    for (int k = 0; k < 3; ++k) {
      // Voxel i spans [i - 1/2, i + 1/2] in grid units about its centre.
      ua[k] = (a[k] - g.origin[k]) / g.spacing[k] + 0.5;
      const double ub = (b[k] - g.origin[k]) / g.spacing[k] + 0.5;
      cur[k] = int(std::floor(ua[k])), end[k] = int(std::floor(ub));
      du[k] = ub - ua[k];
      lo[k] = std::min(cur[k], end[k]), hi[k] = std::max(cur[k], end[k]);
    }
    if (closedInBox(lo, hi) == 0) return false;
    for (int k = 0; k < 3; ++k) {
      step[k] = du[k] > 0 ? 1 : du[k] < 0 ? -1 : 0;
      tDelta[k] = step[k] ? 1.0 / std::abs(du[k]) : std::numeric_limits<double>::infinity();
      tMax[k] = step[k] > 0 ? (cur[k] + 1 - ua[k]) / du[k] : step[k] < 0 ? (cur[k] - ua[k]) / du[k] : std::numeric_limits<double>::infinity();
    }
    const std::ptrdiff_t stride[3] = {1, std::ptrdiff_t(padSize_[0]), std::ptrdiff_t(padSize_[0]) * std::ptrdiff_t(padSize_[1])};
    std::ptrdiff_t at = std::ptrdiff_t(paddedIndex(cur[0], cur[1], cur[2]));
    const std::ptrdiff_t last = std::ptrdiff_t(paddedIndex(end[0], end[1], end[2]));
    int budget = std::abs(end[0] - cur[0]) + std::abs(end[1] - cur[1]) + std::abs(end[2] - cur[2]);
    while (budget-- > 0) {
      const int k = tMax[0] <= tMax[1] ? (tMax[0] <= tMax[2] ? 0 : 2) : (tMax[1] <= tMax[2] ? 1 : 2);
      at += step[k] * stride[k];
      tMax[k] += tDelta[k];
      if (at == last) return false;
      if (closedPad_[std::size_t(at)]) return true;
    }
    return false;
  }

  void voxelIndex(std::size_t v, int idx[3]) const {
    const sph::VoxelGrid& g = solid_->grid;
    idx[0] = int(v % std::size_t(g.size[0])), idx[1] = int((v / std::size_t(g.size[0])) % std::size_t(g.size[1]));
    idx[2] = int(v / (std::size_t(g.size[0]) * std::size_t(g.size[1])));
  }

  // The ghosts' line of sight, tabulated per home voxel: whether an open voxel at offset (i, j, k) - h from a
  // particle's home voxel h is hidden behind solid is answered from the home voxel's centre (nudged by a few
  // hundredths of a voxel so that no ray runs exactly through a voxel edge), once per (home voxel, offset), and
  // read by every later particle there. The exact test was from the particle itself (up to half a voxel away):
  // 34 million walks at 1 ml on the phantom, a third of the run. sightIndex_ numbers the offsets within a support
  // plus a voxel's half diagonal of a centre; each home voxel holds two bits per offset (known, hidden), set
  // atomically (the geometry loop may run on threads: each entry's value is the same whoever computes it).
  void indexSightOffsets() {
    const sph::VoxelGrid& g = solid_->grid;
    const double reach = kernel_.support + 0.5 * g.spacing.norm();
    sightM_ = int(std::ceil(reach / g.spacing.minCoeff()));
    const int side = 2 * sightM_ + 1;
    sightIndex_.assign(std::size_t(side) * std::size_t(side) * std::size_t(side), -1);
    sightEntries_ = 0;
    for (int k = -sightM_; k <= sightM_; ++k)
      for (int j = -sightM_; j <= sightM_; ++j)
        for (int i = -sightM_; i <= sightM_; ++i)
          if (Eigen::Vector3d(i * g.spacing[0], j * g.spacing[1], k * g.spacing[2]).norm() < reach)
            sightIndex_[std::size_t(i + sightM_) + std::size_t(side) * (std::size_t(j + sightM_) + std::size_t(side) * std::size_t(k + sightM_))] =
                sightEntries_++;
    sightSlot_.assign(g.count(), -1);
    sightBits_.clear();
  }
  // table: the home voxel's (sightBits_[sightSlot_[home]]); sightRow: where sightIndex_ numbers the offset of voxel
  // (0, j, k) from home h (sightRowOf; voxel (i, j, k)'s at sightRow + i): the per-particle and per-row parts of the
  // lookup are made once, not per voxel.
  bool ghostHidden(std::atomic<std::uint8_t>* table, std::ptrdiff_t sightRow, const int h[3], int i, int j, int k) const {
    const sph::VoxelGrid& g = solid_->grid;
    const int e = sightIndex_[std::size_t(sightRow + i)];
    const auto from = [&] { return Eigen::Vector3d(g.centre(h[0], h[1], h[2]) + Eigen::Vector3d(0.011, 0.023, 0.037).cwiseProduct(g.spacing)); };
    if (e < 0) return lineOfSightBlocked(from(), g.centre(i, j, k)); // an offset the table lacks (a rounding guard)
    std::atomic<std::uint8_t>& byte = table[std::size_t(e) / 4];
    const int shift = 2 * (e % 4);
    const std::uint8_t known = std::uint8_t((byte.load(std::memory_order_relaxed) >> shift) & 3);
    if (known) return known == 2;
    const bool hidden = lineOfSightBlocked(from(), g.centre(i, j, k));
    byte.fetch_or(std::uint8_t((hidden ? 2 : 1) << shift), std::memory_order_relaxed);
    return hidden;
  }
  std::ptrdiff_t sightRowOf(const int h[3], int j, int k) const {
    const std::ptrdiff_t side = 2 * sightM_ + 1;
    return std::ptrdiff_t(sightM_ - h[0]) + side * (std::ptrdiff_t(j - h[1] + sightM_) + side * std::ptrdiff_t(k - h[2] + sightM_));
  }

  // Moves the pairs whose segment crosses a closed voxel out of the flux's pair list (pairI_ ...) into
  // hiddenI_ ...: they stay in the number density (space is space) and the shifting, not in the pressure
  // matrix or the gradient.
  void hidePairsBehindSolid() {
    hiddenI_.clear(), hiddenJ_.clear(), hiddenF_.clear();
    std::size_t kept = 0;
    for (std::size_t q = 0; q < pairI_.size(); ++q) {
      const std::size_t i = std::size_t(pairI_[q]), j = std::size_t(pairJ_[q]);
      const long home = voxel(x_[i]);
      if (home >= 0 && sightCheck_[std::size_t(home)] && lineOfSightBlocked(x_[i], x_[j])) {
        hiddenI_.push_back(pairI_[q]), hiddenJ_.push_back(pairJ_[q]), hiddenF_.push_back(pairF_[q]);
        continue;
      }
      pairI_[kept] = pairI_[q], pairJ_[kept] = pairJ_[q], pairF_[kept] = pairF_[q], pairW_[kept] = pairW_[q];
      ++kept;
    }
    pairI_.resize(kept), pairJ_.resize(kept), pairF_.resize(kept), pairW_.resize(kept);
    hiddenPairs_ += hiddenI_.size();
  }

  void add(const Eigen::Vector3d& p, double pressure, double viscosity) {
    x_.push_back(p);
    mu_.push_back(viscosity);
    speed_.push_back(0.0);
    p_.push_back(pressure);
    pc_.push_back(0.0);
    u_.push_back(Eigen::Vector3d::Zero());
    darcy_.push_back(Eigen::Vector3d::Zero());
    birth_.push_back(time_);
  }

  // The runs of closed voxels and cement (open, occupied voxels) along x over the particles' supports' bounding box
  // (clipped to the region): the per-particle pass of geometry() skips both (the closed voxels' sums come from
  // closedSumsAt, the cement's from the particles), and jumps over a run at once.
  void markCementRuns() {
    const sph::VoxelGrid& g = solid_->grid;
    int lo[3] = {g.size[0], g.size[1], g.size[2]}, hi[3] = {-1, -1, -1};
    for (const auto& p : x_) {
      int l[3], h[3];
      voxelBox(p, kernel_.support, l, h);
      for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], l[a]), hi[a] = std::max(hi[a], h[a]);
    }
    for (int a = 0; a < 3; ++a) cementLo_[a] = lo[a], cementDim_[a] = std::max(0, hi[a] - lo[a] + 1);
    const std::size_t nx = std::size_t(cementDim_[0]);
    cementRun_.assign(nx * std::size_t(cementDim_[1]) * std::size_t(cementDim_[2]), 0);
    for (int k = 0; k < cementDim_[2]; ++k)
      for (int j = 0; j < cementDim_[1]; ++j) {
        const std::size_t row = g.index(lo[0], lo[1] + j, lo[2] + k);
        std::uint8_t* run = cementRun_.data() + nx * (std::size_t(j) + std::size_t(cementDim_[1]) * std::size_t(k));
        for (std::size_t i = nx; i-- > 0;) // past the box's end no support reaches: a run ends there
          if (closed_[row + i] || occupied_[row + i]) run[i] = std::uint8_t(i + 1 < nx && run[i + 1] ? std::min(run[i + 1] + 1, 255) : 1);
      }
  }

  // The cell list, neighbour pairs (i < j) with F/r, and each particle's ghost and closed-voxel sums.
  void geometry() {
    const auto t0 = std::chrono::steady_clock::now();
    const std::size_t n = x_.size();
    const double cs = kernel_.support, s2 = cs * cs;
    // Cells.
    const std::size_t nc = std::size_t(cells_[0]) * cells_[1] * cells_[2];
    std::vector<int> cellOf(n);
    cellStart_.assign(nc + 1, 0);
    for (std::size_t i = 0; i < n; ++i) {
      int c[3];
      for (int a = 0; a < 3; ++a) c[a] = std::clamp(int(std::floor((x_[i][a] - lower_[a]) / cs)), 0, cells_[a] - 1);
      cellOf[i] = c[0] + cells_[0] * (c[1] + cells_[1] * c[2]);
      ++cellStart_[std::size_t(cellOf[i]) + 1];
    }
    for (std::size_t c = 0; c < nc; ++c) cellStart_[c + 1] += cellStart_[c];
    cellItems_.assign(n, 0);
    {
      std::vector<int> fillPos(cellStart_.begin(), cellStart_.end() - 1);
      for (std::size_t i = 0; i < n; ++i) cellItems_[std::size_t(fillPos[std::size_t(cellOf[i])]++)] = int(i);
    }
    // Pairs.
    pairI_.clear(), pairJ_.clear(), pairF_.clear(), pairW_.clear();
    for (std::size_t i = 0; i < n; ++i) {
      const int ci = cellOf[i];
      const int cx = ci % cells_[0], cy = (ci / cells_[0]) % cells_[1], cz = ci / (cells_[0] * cells_[1]);
      for (int dz = -1; dz <= 1; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int x = cx + dx, y = cy + dy, z = cz + dz;
            if (x < 0 || y < 0 || z < 0 || x >= cells_[0] || y >= cells_[1] || z >= cells_[2]) continue;
            const std::size_t c = std::size_t(x + cells_[0] * (y + cells_[1] * z));
            for (int q = cellStart_[c]; q < cellStart_[c + 1]; ++q) {
              const std::size_t j = std::size_t(cellItems_[std::size_t(q)]);
              if (j <= i) continue;
              const double r2 = (x_[j] - x_[i]).squaredNorm();
              if (r2 >= s2) continue;
              pairI_.push_back(int(i)), pairJ_.push_back(int(j));
              const double r = std::sqrt(r2);
              pairF_.push_back(kernel_.fOverR(r));
              pairW_.push_back(kernel_.w(r));
            }
          }
    }
    // Occupancy of the pore voxels: the cement's share of the open space about each voxel (cementShare), at
    // least 1/2, or the outlet ball. Only the voxels within a kernel support of a particle are visited and
    // reset (touched_): the cost follows the cement, not the region.
    const sph::VoxelGrid& g = solid_->grid;
    occupied_.resize(g.count(), 0);
    share_.resize(g.count(), 0.0);
    for (std::size_t v : touched_) occupied_[v] = 0;
    previousTouched_.assign(touched_.begin(), touched_.end());
    particleColour(colour_, touched_);
    // Every voxel with colour is listed (touched_) and keeps its share for the ghosts; every other reads 0, the last
    // step's list included (particle_darcy::updateShares).
    particle_darcy::updateShares(share_, previousTouched_, touched_,
                                 [this](std::size_t v) { return closed_[v] ? 0.0 : cementShare(v); });
    for (std::size_t v : touched_) occupied_[v] = !closed_[v] && share_[v] >= 0.5;
    auto stamp = [&](const Eigen::Vector3d& p, double radius) {
      int lo[3], hi[3];
      voxelBox(p, radius, lo, hi);
      for (int k = lo[2]; k <= hi[2]; ++k)
        for (int j = lo[1]; j <= hi[1]; ++j)
          for (int i = lo[0]; i <= hi[0]; ++i)
            if ((g.centre(i, j, k) - p).squaredNorm() <= radius * radius) {
              const std::size_t v = g.index(i, j, k);
              if (colour_[v] == 0.0f && !occupied_[v]) touched_.push_back(v); // reset with the others next step
              occupied_[v] = 1;
            }
    };
    stamp(tip_, sourceRadius_);
    markCementRuns();
    // Per particle: the ghost (open, empty) voxels' Laplacian weight, gradient sums, shift sums.
    ghostF_.assign(n, 0.0);
    ghostB_.assign(n, Eigen::Matrix3d::Zero());
    ghostNormal_.assign(n, Eigen::Vector3d::Zero());
    closedGradC_.assign(n, Eigen::Vector3d::Zero());
    std::vector<double> number(n, kernel_.w(0.0));
    for (std::size_t q = 0; q < pairI_.size(); ++q) number[std::size_t(pairI_[q])] += pairW_[q], number[std::size_t(pairJ_[q])] += pairW_[q];
    const double vc = g.voxelVolume();
    std::vector<double> colourAt(n);
    for (std::size_t i = 0; i < n; ++i) { // the cement's share of the open space at the particle
      const long v = voxel(x_[i]);
      colourAt[i] = volume_ * number[i] / openShare(v >= 0 ? closedColourAt(std::size_t(v)) : 0.0);
    }
    ghostPull_.assign(n, Eigen::Vector3d::Zero());
    missingMoment_.assign(n, 0.0);
    for (std::size_t i = 0; i < n; ++i) { // the sight tables the loop below fills (one per home voxel, ghostHidden)
      const long home = voxel(x_[i]);
      // At most kMaxSightTableBytes of tables (a fine CT under coarse particles has many voxels per support):
      // beyond it a particle's home without a table walks from the particle itself, as before the tables.
      const bool room = double(sightBits_.size() + 1) * double((sightEntries_ + 3) / 4) <= kMaxSightTableBytes;
      if (home >= 0 && sightCheck_[std::size_t(home)] && sightSlot_[std::size_t(home)] < 0 && room) {
        sightSlot_[std::size_t(home)] = std::int32_t(sightBits_.size());
        sightBits_.emplace_back(new std::atomic<std::uint8_t>[(sightEntries_ + 3) / 4]());
      }
    }
    frontParticles_ = 0;
    const double cs2 = cs * cs, vcOverV = vc / volume_;
    // Each particle's sums read only shared state (share_ holds every ghost's cement share, so closedColourAt's
    // cache is not written here) and are its own, summed in the same order by whichever thread: the result
    // does not depend on the thread count.
    // The closed space's sums (number density, concentration gradient, second moment) at every particle, from
    // the static field on the voxel centres (closedSumsAt); the nodes a particle needs are computed here, before the
    // threads, the first time any particle needs them.
    std::vector<ClosedSums> closedSums(n);
    for (std::size_t i = 0; i < n; ++i) closedSums[i] = closedSumsAt(i);
#pragma omp parallel for schedule(dynamic, 16)
    for (std::size_t i = 0; i < n; ++i) {
      const Eigen::Vector3d& p = x_[i];
      int lo[3], hi[3];
      voxelBox(p, cs, lo, hi); // the support's box within the region: closed voxels and the space outside it are in closedAt
      double num = number[i] + closedSums[i].num, gF = 0;
      Eigen::Vector3d gNormal = Eigen::Vector3d::Zero(), gPull = Eigen::Vector3d::Zero();
      Eigen::Matrix3d gB = Eigen::Matrix3d::Zero();
      double missing = closedSums[i].missing; // the support's second moment on closed space and behind it (wallFactor_)
      const double ci = colourAt[i];
      const long home = voxel(p);
      const bool checkSight = home >= 0 && sightCheck_[std::size_t(home)];
      const bool tabled = checkSight && sightSlot_[std::size_t(home)] >= 0;
      int h[3] = {0, 0, 0};
      if (checkSight) voxelIndex(std::size_t(home), h);
      std::atomic<std::uint8_t>* const table = tabled ? sightBits_[std::size_t(sightSlot_[std::size_t(home)])].get() : nullptr;
      const int runLo = cementLo_[0]; // read once (the loop's stores could alias the member, so the compiler rereads it)
      for (int k = lo[2]; k <= hi[2]; ++k) {
        const double rz = (g.origin[2] + g.spacing[2] * k) - p[2], rz2 = rz * rz;
        for (int j = lo[1]; j <= hi[1]; ++j) {
          const double ry = (g.origin[1] + g.spacing[1] * j) - p[1], ry2 = ry * ry;
          int i0, i1;
          if (!rowRange(p[0], ry2, rz2, lo[0], hi[0], i0, i1)) continue;
          const std::size_t row = g.index(0, j, k);
          const std::ptrdiff_t sightRow = tabled ? sightRowOf(h, j, k) : 0;
          // Closed voxels and cement are skipped, a run of them at once (markCementRuns): only the open space about
          // the cement is visited. The region lies in the runs' box.
          const std::uint8_t* runRow =
              cementRun_.data() + std::size_t(cementDim_[0]) * (std::size_t(j - cementLo_[1]) +
                                                                std::size_t(cementDim_[1]) * std::size_t(k - cementLo_[2]));
          for (int ii = i0; ii <= i1; ++ii) {
            if (const std::uint8_t skip = runRow[ii - runLo]) {
              ii += skip - 1;
              continue;
            }
            const double rx = (g.origin[0] + g.spacing[0] * ii) - p[0];
            const double r2 = rx * rx + ry2 + rz2;
            if (r2 >= cs2 || r2 == 0) continue; // outside the support: no square root
            const std::size_t v = row + std::size_t(ii);
            const Eigen::Vector3d r(rx, ry, rz);
            const double rn = std::sqrt(r2);
            const double f = kernel_.fOverR(rn);
            num += vcOverV * kernel_.w(rn);
            // An empty pore behind solid is space (it counts in the number density) but no ghost: no
            // pressure coupling crosses a closed voxel (lineOfSightBlocked).
            if (checkSight && (tabled ? ghostHidden(table, sightRow, h, ii, j, k) : lineOfSightBlocked(p, r + p))) {
              missing += vc * f * r2;
              continue;
            }
            // Ghost-fluid (Gibou et al. 2002): the surface C = 1/2 lies theta of the way from the particle
            // to the ghost (C linear between them); p = 0 there, so the ghost's value is p_i (1 - 1/theta).
            const double cg = share_[v];
            const double theta = ci > cg ? std::clamp((ci - 0.5) / (ci - cg), kMinTheta, 1.0) : 1.0;
            const double fv = vc * f;
            gF += fv / theta;
            gB += fv * r * r.transpose();
            gNormal += fv * r;
            gPull += fv / theta * r;
          }
        }
      }
      missingMoment_[i] = missing;
      number[i] = num, ghostF_[i] = gF, closedGradC_[i] = closedSums[i].grad, ghostB_[i] = gB, ghostNormal_[i] = gNormal, ghostPull_[i] = gPull;
    }
    for (std::size_t i = 0; i < n; ++i)
      if (ghostF_[i] > 0) ++frontParticles_;
    hidePairsBehindSolid();
    // Each particle's space volume from its number density completed by the closed and open space about it
    // (a lattice of spacing d: exactly d^3).
    omega_.resize(n);
    for (std::size_t i = 0; i < n; ++i) omega_[i] = volume_ * latticeNumber_ / number[i];
    // The wall correction of the Laplacian (solvePressure): the share of each particle's support second moment
    // that a wall takes away, from the closed voxels (and open space hidden behind them) summed above and the
    // neighbours hidden behind solid.
    for (std::size_t q = 0; q < hiddenI_.size(); ++q) {
      const std::size_t i = std::size_t(hiddenI_[q]), j = std::size_t(hiddenJ_[q]);
      const double r2 = (x_[j] - x_[i]).squaredNorm();
      missingMoment_[i] += omega_[j] * hiddenF_[q] * r2, missingMoment_[j] += omega_[i] * hiddenF_[q] * r2;
    }
    wallFactor_.resize(n);
    for (std::size_t i = 0; i < n; ++i) wallFactor_[i] = 1.0 / std::max(1.0 - missingMoment_[i] / 3.0, kMinWallShare);
    geometrySeconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }

  void solveIfAny() {
    if (x_.empty()) return;
    geometry();
    solvePressure();
  }

  // Row i times Omega_i / M: sum_j 2 Omega_i Omega_j F/r (p_i - p_j) + g_i p_i = Q_i / M for the Darcy pressure
  // p, and the same matrix with (d^3 - Omega_i) / tau / M for the density-invariant correction pc (Shao & Lo
  // 2003, Adv Water Resour 26:787) relaxing each particle's space volume to d^3 over tau = kRelaxSteps steps.
  // Two right-hand sides, as the two projections of Hu & Adams 2007 (J Comput Phys 227:264: one Poisson
  // equation for the velocity divergence, one for the density error): the particles move with
  // -M grad(p + pc), which by linearity is the single solve of before, but the pressure reported (the outlet's,
  // the particles') is p alone, the Darcy pressure of the injected flow. pc is a kinematic correction with no
  // physical pressure behind it: near the outlet, where new particles are inserted into gaps and the packing is
  // densest, it added +5 % to the uniform medium's tip pressure at d = 0.3 mm (+11 % against the oracle with
  // it, +6 % without).
  void solvePressure() {
    const std::size_t n = x_.size();
    const double M = mobility_;
    // The matrix as its pair weights and diagonal: y = A x is one pass over the pairs (matrix-free).
    pairA_.resize(pairI_.size());
    diagA_.assign(n, 0.0);
    const double scale = 1.0 / volume_; // entries ~ 1 / d^2
    // Each particle's mobility relative to M = k / mu_ref: exactly 1 for a Newtonian cement (so the solve is
    // the same for any viscosity, scaled); a pair's is the harmonic mean of its two (as the voxel model's faces).
    rel_.resize(n);
    const double muRef = poreK_ / M;
    for (std::size_t i = 0; i < n; ++i) rel_[i] = shearThinning_ ? muRef / mu_[i] : 1.0;
    for (std::size_t q = 0; q < pairI_.size(); ++q) {
      const std::size_t i = std::size_t(pairI_[q]), j = std::size_t(pairJ_[q]);
      const double m = shearThinning_ ? 2 * rel_[i] * rel_[j] / (rel_[i] + rel_[j]) : 1.0;
      pairA_[q] = 2 * omega_[i] * omega_[j] * pairF_[q] * scale * m * 0.5 * (wallFactor_[i] + wallFactor_[j]);
      diagA_[i] += pairA_[q], diagA_[j] += pairA_[q];
    }
    for (std::size_t i = 0; i < n; ++i) diagA_[i] += 2 * omega_[i] * ghostF_[i] * scale * rel_[i] * wallFactor_[i];
    // A particle cut off from every neighbour and ghost (all of them behind solid: the line-of-sight test) has an
    // empty row; it is held at p = 0 (the row the identity's, its right-hand sides 0) rather than leaving the
    // Jacobi preconditioner a division by zero (seen on the phantom at 5 ml: NaN pressures).
    isolated_.assign(n, 0);
    for (std::size_t i = 0; i < n; ++i)
      if (!(diagA_[i] > 0)) isolated_[i] = 1, diagA_[i] = 1.0;
    // Likewise a cluster cut off behind solid with no p = 0 ghost and no source in it: a pure-Neumann block,
    // singular (the CG would run to its limit every solve). It has no pressure to carry: pinned at p = 0 by a
    // Dirichlet term on its rows (its right-hand sides 0).
    {
      std::vector<std::size_t> root(n);
      for (std::size_t i = 0; i < n; ++i) root[i] = i;
      auto find = [&](std::size_t i) {
        while (root[i] != i) i = root[i] = root[root[i]];
        return i;
      };
      for (std::size_t q = 0; q < pairI_.size(); ++q) root[find(std::size_t(pairI_[q]))] = find(std::size_t(pairJ_[q]));
      std::vector<std::uint8_t> anchored(n, 0);
      for (std::size_t i = 0; i < n; ++i)
        if (ghostF_[i] > 0 || sourceWeight((x_[i] - tip_).norm(), sourceRadius_, particleRadius_) > 0) anchored[find(i)] = 1;
      for (std::size_t i = 0; i < n; ++i)
        if (!isolated_[i] && !anchored[find(i)]) isolated_[i] = 1, diagA_[i] *= 2;
    }
    const Eigen::Index rows = Eigen::Index(n);
    weights_.assign(n, 0.0);
    double sum = 0;
    for (std::size_t i = 0; i < n; ++i) sum += weights_[i] = omega_[i] * sourceWeight((x_[i] - tip_).norm(), sourceRadius_, particleRadius_);
    const double tau = kRelaxSteps * lastDt_;
    Eigen::VectorXd b(rows), x(rows), bc(rows), xc(rows);
    for (std::size_t i = 0; i < n; ++i) {
      const double qi = sum > 0 ? flowRate_ * weights_[i] / sum : 0.0;
      const double relax = tau > 0 ? (volume_ - omega_[i]) / tau : 0.0;
      b[Eigen::Index(i)] = isolated_[i] ? 0.0 : qi * scale / M;
      bc[Eigen::Index(i)] = isolated_[i] ? 0.0 : relax * scale / M;
      x[Eigen::Index(i)] = p_[i];
      xc[Eigen::Index(i)] = pc_[i];
    }
    const auto t0 = std::chrono::steady_clock::now();
    const Cg r = conjugateGradient(b, x, 1e-9, 20000);
    // The correction moves particles by a fraction of a spacing per step: a looser tolerance is enough.
    const Cg rc = conjugateGradient(bc, xc, 1e-6, 20000);
    solveSeconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    ++solves_;
    iterations_ += std::size_t(r.iterations);
    correctionIterations_ += std::size_t(rc.iterations);
    worstResidual_ = std::max(worstResidual_, r.residual);
    if (r.residual > 1e-9) ++unconverged_;
    const auto where = [&] {
      return "particle-darcy: step " + std::to_string(steps_) + " (t = " + std::to_string(time_) + " s, " + std::to_string(n) +
             " particles), the pressure solve (" + std::to_string(r.iterations) + " + " + std::to_string(rc.iterations) +
             " CG iterations, residuals " + std::to_string(r.residual) + ", " + std::to_string(rc.residual) + ")";
    };
    particle_darcy::requireFiniteSolution(x, "Darcy pressure", where);
    particle_darcy::requireFiniteSolution(xc, "density correction", where);
    for (std::size_t i = 0; i < n; ++i) p_[i] = x[Eigen::Index(i)], pc_[i] = xc[Eigen::Index(i)];
  }

  // Jacobi-preconditioned conjugate gradient on the matrix-free A (single-threaded and deterministic); stops
  // at |b - A x| <= tolerance |b| (as Eigen's ConjugateGradient).
  struct Cg {
    int iterations = 0;
    double residual = 0;
  };
  // The pairs come sorted by i (geometry() lists them so, hidePairsBehindSolid keeps the order) with j > i, so y_i
  // is held in a register over its run of pairs: no pair of the run writes it, and its subtractions come in the
  // same order as one pair at a time (the same bits), without a store and reload per pair.
  void multiply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const {
    y = Eigen::Map<const Eigen::VectorXd>(diagA_.data(), x.size()).cwiseProduct(x);
    const double* xd = x.data();
    double* yd = y.data();
    const std::size_t m = pairA_.size();
    for (std::size_t q = 0; q < m;) {
      const int i = pairI_[q];
      const double xi = xd[i];
      double yi = yd[i];
      for (; q < m && pairI_[q] == i; ++q) {
        const double a = pairA_[q];
        const int j = pairJ_[q];
        yi -= a * xd[j];
        yd[j] -= a * xi;
      }
      yd[i] = yi;
    }
  }
  Cg conjugateGradient(const Eigen::VectorXd& b, Eigen::VectorXd& x, double tolerance, int maxIterations) const {
    const double bn = b.norm();
    if (bn == 0) {
      x.setZero();
      return {};
    }
    const Eigen::VectorXd inv = Eigen::Map<const Eigen::VectorXd>(diagA_.data(), b.size()).cwiseInverse();
    Eigen::VectorXd r(b.size()), z, p, q(b.size());
    multiply(x, q);
    r = b - q;
    z = inv.cwiseProduct(r);
    p = z;
    double rz = r.dot(z);
    Cg out;
    while (out.iterations < maxIterations && r.norm() > tolerance * bn) {
      multiply(p, q);
      const double alpha = rz / p.dot(q);
      x += alpha * p;
      r -= alpha * q;
      z = inv.cwiseProduct(r);
      const double rz1 = r.dot(z);
      p = z + (rz1 / rz) * p;
      rz = rz1;
      ++out.iterations;
    }
    out.residual = r.norm() / bn;
    return out;
  }

  // Corrected gradient of p and the Darcy velocity (phi = 1: interstitial = superficial).
  void velocities() {
    const std::size_t n = x_.size();
    std::vector<Eigen::Matrix3d> B(n);
    std::vector<Eigen::Vector3d> s(n, Eigen::Vector3d::Zero());
    std::vector<Eigen::Vector3d> sp(n, Eigen::Vector3d::Zero()); // the same sum for p alone (the Darcy speed)
    std::vector<double> pt(n); // the potential the particles move with: p + pc (solvePressure)
    for (std::size_t i = 0; i < n; ++i) pt[i] = p_[i] + pc_[i];
    for (std::size_t i = 0; i < n; ++i) {
      B[i] = ghostB_[i];
      s[i] = -pt[i] * ghostPull_[i]; // ghosts: (p_g - p_i)(x_c - x_i) V_c F/r, p_g - p_i = -p_i / theta
      sp[i] = -p_[i] * ghostPull_[i];
    }
    for (std::size_t q = 0; q < pairI_.size(); ++q) {
      const std::size_t i = std::size_t(pairI_[q]), j = std::size_t(pairJ_[q]);
      const Eigen::Vector3d r = x_[j] - x_[i];
      const double wj = omega_[j] * pairF_[q], wi = omega_[i] * pairF_[q];
      const Eigen::Matrix3d rr = r * r.transpose();
      B[i] += wj * rr, B[j] += wi * rr;
      s[i] += wj * (pt[j] - pt[i]) * r;
      s[j] += wi * (pt[j] - pt[i]) * r; // (p_i - p_j)(x_i - x_j)
      sp[i] += wj * (p_[j] - p_[i]) * r;
      sp[j] += wi * (p_[j] - p_[i]) * r;
    }
    for (std::size_t i = 0; i < n; ++i) {
      Eigen::Vector3d grad;
      const double tr = B[i].trace();
      // Corrected where B is well conditioned (det >= 1e-3 (tr/3)^3; a full support: B = I), else the plain
      // normalised sum (a particle with its neighbours on one side only).
      Eigen::Matrix3d inverse = Eigen::Matrix3d::Zero();
      if (tr > 0 && B[i].determinant() > 1e-3 * std::pow(tr / 3, 3)) inverse = B[i].inverse();
      else if (tr > 0) inverse = Eigen::Matrix3d::Identity() * (3.0 / tr);
      grad = inverse * s[i];
      const double mobility = mobility_ * rel_[i];
      u_[i] = -mobility * grad;
      darcy_[i] = -mobility * (inverse * sp[i]);
      speed_[i] = darcy_[i].norm();
    }
  }

  // Advection, Lind's shifting, and the no-penetration rule.
  void move(double dt, const std::vector<std::uint8_t>& subStepped) {
    const std::size_t n = x_.size();
    const double wd = kernel_.w(d_);
    std::vector<Eigen::Vector3d> gradC(n);
    for (std::size_t i = 0; i < n; ++i) gradC[i] = closedGradC_[i];
    // Lind's concentration gradient over a pair list (its F/r), each pair once.
    auto addPairs = [&](const std::vector<int>& is, const std::vector<int>& js, const std::vector<double>& fs) {
      for (std::size_t q = 0; q < is.size(); ++q) {
        const std::size_t i = std::size_t(is[q]), j = std::size_t(js[q]);
        const Eigen::Vector3d r = x_[j] - x_[i];
        const double ratio = kernel_.w(r.norm()) / wd;
        const double w = fs[q] * (1 + 0.2 * ratio * ratio * ratio * ratio);
        gradC[i] += omega_[j] * w * r, gradC[j] -= omega_[i] * w * r;
      }
    };
    addPairs(pairI_, pairJ_, pairF_);
    // A neighbour behind a thin strut occupies space as the strut does (the closed voxels count as occupied
    // here too): the shifting keeps it, so the strut's two sides pack alike; only the flux ignores it.
    addPairs(hiddenI_, hiddenJ_, hiddenF_);
    for (std::size_t i = 0; i < n; ++i) {
      Eigen::Vector3d shift = -kShiftA * kernel_.h * u_[i].norm() * dt * gradC[i];
      if (ghostF_[i] > 0 && ghostNormal_[i].norm() > 0) {
        const Eigen::Vector3d nrm = ghostNormal_[i].normalized();
        shift -= shift.dot(nrm) * nrm;
      }
      const double sn = shift.norm();
      if (sn > kMaxShiftOverD * d_) shift *= kMaxShiftOverD * d_ / sn;
      // The density correction (a packing fix about the start, at most 0.2 d) for every particle; a sub-stepped
      // one takes its Darcy velocity in the sub-steps (moveMultiRate), the others here (particle_darcy::macroMove).
      stepAround(x_[i], particle_darcy::macroMove(u_[i], darcy_[i], shift, dt, subStepped[i] != 0, kMaxMoveOverD * d_));
    }
  }

  // A move that never enters or crosses a closed voxel (particle_darcy::stepAround: axis by axis, every voxel on
  // the way tested).
  void stepAround(Eigen::Vector3d& pos, const Eigen::Vector3d& step) const {
    particle_darcy::stepAround(pos, step, solid_->grid.spacing, [this](const Eigen::Vector3d& q) { return closedAt(q); });
  }

  // Multi-rate stepping (issue 19's speed): the Darcy pressure is quasi-static (no inertia: it changes only as
  // the cement's shape does), so one solve serves a macro step set by the bulk of the particles, and only the
  // few fastest (the outlet ball and its throats, up to (R/a)^2 times the front's speed) are sub-stepped along
  // the frozen field. The macro step: the particle at the kSubSteppedShare quantile of speed moves 0.2 d; the
  // emitted volume is at most kMaxGrowth of the cement's (the front moves ~2 % of its radius); the fastest
  // particle takes at most kMaxSubSteps sub-steps; never shorter than the single-rate step 0.2 d / vmax.
  // Before it, the step was the single-rate one, set by the particles leaving the outlet: one step per ~4
  // inserted particles, so the steps grew as the particle count.
  // The rule itself: particle_darcy::macroStep (the sub-step bound by the fastest Darcy speed).
  double macroStep(double dtMax, double vmaxDarcy) const {
    std::vector<double> speeds(u_.size());
    for (std::size_t i = 0; i < u_.size(); ++i) speeds[i] = u_[i].norm();
    particle_darcy::MacroStepRule rule;
    rule.limit = kMaxMoveOverD * d_, rule.subSteppedShare = kSubSteppedShare;
    rule.maxCorrectionOverDarcy = kMaxCorrectionOverDarcy, rule.maxSubSteps = kMaxSubSteps;
    return particle_darcy::macroStep(std::move(speeds), vmaxDarcy, dtMax, kMaxGrowth * double(x_.size()) * volume_ / flowRate_, rule);
  }

  // The frozen field of the macro step: the Shepard interpolant sum_j Omega_j W v_j / sum_j Omega_j W over the
  // macro step's particles (positions xm_, its cell list) in sight of x, of the residual-corrected values
  // v_j = 2 u_j - S[u]_j (S[u]_j the plain interpolant at particle j: one step of iterated Shepard, so the field
  // reproduces the particles' own velocities to second order where the plain one smooths them, e.g. the
  // outflow's peak at the outlet ball's surface).
  Eigen::Vector3d frozenVelocity(const Eigen::Vector3d& x) const {
    const double cs = kernel_.support, s2 = cs * cs;
    int c[3];
    for (int a = 0; a < 3; ++a) c[a] = std::clamp(int(std::floor((x[a] - lower_[a]) / cs)), 0, cells_[a] - 1);
    const long home = voxel(x);
    const bool checkSight = home >= 0 && sightCheck_[std::size_t(home)];
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    double weight = 0;
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int cx = c[0] + dx, cy = c[1] + dy, cz = c[2] + dz;
          if (cx < 0 || cy < 0 || cz < 0 || cx >= cells_[0] || cy >= cells_[1] || cz >= cells_[2]) continue;
          const std::size_t cell = std::size_t(cx + cells_[0] * (cy + cells_[1] * cz));
          for (int q = cellStart_[cell]; q < cellStart_[cell + 1]; ++q) {
            const std::size_t j = std::size_t(cellItems_[std::size_t(q)]);
            const double r2 = (xm_[j] - x).squaredNorm();
            if (r2 >= s2 || (checkSight && lineOfSightBlocked(x, xm_[j]))) continue;
            const double w = omega_[j] * kernel_.w(std::sqrt(r2));
            sum += w * frozen_[j], weight += w;
          }
        }
    // Beyond the front the field fades: the sum is normalised by at least half the open share of the support
    // (the weight sum_j Omega_j W is the cement's share C of the space, 1 inside the cement against a wall as
    // in open space: cementShare), so the field is the plain interpolant where C >= 1/2 (the cement, as the
    // front's definition) and falls as C beyond it. Plain Shepard extended the last particles' velocity into
    // the empty pore ahead: a jet leaving a throat kept its throat speed for the whole macro step (the cement
    // spread 0.5 mm farther than the voxel model's on the phantom at 1 ml).
    const double open = home >= 0 ? openShare(closedColourAt(std::size_t(home))) : 1.0;
    return weight > 0 ? Eigen::Vector3d(sum / std::max(weight, 0.5 * open)) : Eigen::Vector3d::Zero();
  }

  // frozen_ = 2 u - S[u] of the Darcy velocities (of p alone) over the macro step's in-sight pairs (frozenVelocity).
  void frozenValues() {
    const std::size_t n = u_.size();
    std::vector<Eigen::Vector3d> sum(n);
    std::vector<double> weight(n);
    const double w0 = kernel_.w(0.0);
    for (std::size_t i = 0; i < n; ++i) sum[i] = omega_[i] * w0 * darcy_[i], weight[i] = omega_[i] * w0;
    for (std::size_t q = 0; q < pairI_.size(); ++q) {
      const std::size_t i = std::size_t(pairI_[q]), j = std::size_t(pairJ_[q]);
      sum[i] += omega_[j] * pairW_[q] * darcy_[j], weight[i] += omega_[j] * pairW_[q];
      sum[j] += omega_[i] * pairW_[q] * darcy_[i], weight[j] += omega_[i] * pairW_[q];
    }
    frozen_.resize(n);
    for (std::size_t i = 0; i < n; ++i) frozen_[i] = 2 * darcy_[i] - sum[i] / weight[i];
  }

  // One macro step of length dt: the particles whose Darcy velocity would move them more than 0.2 d advance in
  // sub-steps along the frozen Darcy field (frozenVelocity), the no-penetration test per sub-step, and take
  // their density correction once (move); the others move in one step; the emitted volume is inserted sub-step
  // by sub-step, its particles sub-stepped. Tried first and dropped: carrying each particle's own difference
  // from the interpolant along its path (the phantom's cement spread 0.5 mm farther than the voxel model's at
  // 1 ml), and the correction's velocity in the interpolated field (smoothed away where the outlet packs
  // particles in: the uniform medium's pressure 6 % high just outside the outlet ball).
  void moveMultiRate(double dt) {
    const std::size_t n = x_.size();
    const double limit = kMaxMoveOverD * d_;
    std::vector<std::uint8_t> subStepped(n, 0);
    std::vector<std::size_t> fast;
    double vmax = 0;
    for (std::size_t i = 0; i < n; ++i)
      if (speed_[i] * dt > limit * (1 + 1e-9)) subStepped[i] = 1, fast.push_back(i), vmax = std::max(vmax, speed_[i]);
    if (!fast.empty()) {
      xm_.assign(x_.begin(), x_.end());
      frozenValues();
    }
    move(dt, subStepped);
    const double start = time_;
    if (fast.empty()) {
      time_ = start + dt;
      insert();
      return;
    }
    // The macro step bounds the sub-steps by the fastest Darcy speed (particle_darcy::macroStep), so the clamp
    // should never act: counted (sub_steps_clamped) rather than silent.
    const int needed = std::max(1, int(std::ceil(vmax * dt / limit - 1e-9)));
    if (needed > kMaxSubSteps) ++subStepsClamped_;
    const int m = std::min(needed, kMaxSubSteps);
    subSteps_ += std::size_t(m);
    for (int k = 1; k <= m; ++k) {
      const double delta = dt / m;
      for (std::size_t f = 0; f < fast.size(); ++f) {
        Eigen::Vector3d v = frozenVelocity(x_[fast[f]]);
        const double length = v.norm() * delta;
        // A sub-step never moves a particle more than 0.2 d: where the frozen field along its path is faster than
        // its start (toward a throat), it falls behind by the rest; counted (sub_step_moves_capped).
        if (length > limit) v *= limit / length, ++cappedSubStepMoves_;
        stepAround(x_[fast[f]], v * delta);
      }
      time_ = start + dt * k / m;
      const std::size_t before = x_.size();
      insert();
      for (std::size_t i = before; i < x_.size(); ++i) fast.push_back(i);
    }
  }

  // The emitted volume not yet in particles goes into the outlet ball's largest gaps.
  void insert() {
    std::size_t due = 0;
    while (double(x_.size() + due + 1) * volume_ <= injected() * (1 + 1e-12)) ++due;
    if (due == 0) return;
    const double reach = sourceRadius_ + d_;
    std::vector<std::size_t> near;
    for (std::size_t i = 0; i < x_.size(); ++i)
      if ((x_[i] - tip_).norm() <= reach) near.push_back(i);
    std::vector<double> gap(candidates_.size(), std::numeric_limits<double>::infinity());
    for (std::size_t c = 0; c < candidates_.size(); ++c)
      for (std::size_t i : near) gap[c] = std::min(gap[c], (x_[i] - candidates_[c]).squaredNorm());
    const double pNew = outlet_.tipPa; // warm start for the new particles: the outlet pressure
    double muNew = 0; // and the viscosity of the cement about the outlet
    for (std::size_t i : near) muNew += mu_[i];
    muNew = near.empty() ? (shearThinning_ ? referenceViscosity_ : viscosity_->at(time_)) : muNew / double(near.size());
    for (std::size_t k = 0; k < due; ++k) {
      const std::size_t best = std::size_t(std::max_element(gap.begin(), gap.end()) - gap.begin());
      const Eigen::Vector3d p = candidates_[best];
      add(p, pNew, muNew);
      for (std::size_t c = 0; c < candidates_.size(); ++c) gap[c] = std::min(gap[c], (p - candidates_[c]).squaredNorm());
    }
  }

  double outletPressure() const {
    double sum = 0, weight = 0;
    for (std::size_t i = 0; i < x_.size() && i < p_.size() && i < omega_.size(); ++i) {
      const double w = omega_[i] * sourceWeight((x_[i] - tip_).norm(), sourceRadius_, particleRadius_);
      sum += w * p_[i], weight += w;
    }
    return weight > 0 ? sum / weight : 0.0;
  }

  double cannulaDrop(double mu) const {
    if (shearThinning_) return cannulaDrop_; // the law's tube integral (Rabinowitsch-Mooney), once at start
    return sph::hagenPoiseuillePressureDrop(mu, cannulaLength_, flowRate_, innerDiameter_);
  }

  // Each particle's viscosity: the law at its Darcy-scale shear rate (rheology::darcyShearRate of its Darcy
  // speed |u| phi, phi = 1 in a pore voxel), as the voxel model's per voxel.
  void updateViscosity() {
    for (std::size_t i = 0; i < x_.size(); ++i)
      mu_[i] = law_->viscosity(rheology::darcyShearRate(speed_[i], poreK_, 1.0, law_->flowIndex()));
  }

  const SceneConfig* scene_ = nullptr;
  const PorousSolid* solid_ = nullptr;
  double rho0_ = 0, flowRate_ = 0, innerDiameter_ = 0, cannulaLength_ = 0, d_ = 0, volume_ = 0, poreK_ = 0;
  double sourceRadius_ = 0, particleRadius_ = 0, effectiveRadius_ = 0, mobility_ = 0, time_ = 0, latticeNumber_ = 0, lastDt_ = 0;
  Kernel kernel_{1.0};
  Eigen::Vector3d tip_, axis_, lower_;
  std::optional<sph::ViscositySchedule> viscosity_;
  std::vector<std::uint8_t> closed_, occupied_, closedRun_, openRun_; // the runs: per voxel along +x (particleColour)
  std::vector<float> colour_;
  std::vector<double> share_; // cementShare of the touched voxels this step (0 on closed ones)
  mutable std::vector<float> closedColour_; // per voxel, -1 until asked for (closedColourAt)
  // The closed set padded by pad_ closed voxels on every side (padClosed), and a voxel centre's support stencil.
  struct StencilEntry {
    std::ptrdiff_t offset; // in the padded grid
    double weight;         // V_c W(r)
  };
  std::vector<std::uint8_t> closedPad_;
  struct FieldEntry {
    std::ptrdiff_t offset = 0; // in the padded grid
    double w = 0, fr[3] = {0, 0, 0}, fr2 = 0, dm[3] = {0, 0, 0}; // dm: the gradient of V_c F/r r^2 in the point
    double dg[6] = {0, 0, 0, 0, 0, 0}; // the Jacobian of V_c F/r r in the point (xx, yy, zz, xy, xz, yz)
  };
  // Per node: number density, concentration gradient (3), second moment and its gradient (3), the concentration
  // gradient's Jacobian (6).
  static constexpr int kFieldValues = 14;
  std::vector<FieldEntry> fieldStencil_;
  // Per padded voxel centre the kFieldValues closed sums (closedNode), NaN until computed, in blocks of 8^3 nodes
  // allocated on first use (fieldBlocks_: blocks per axis).
  std::vector<std::unique_ptr<float[]>> closedField_;
  int fieldBlocks_[3] = {0, 0, 0};
  std::vector<std::int32_t> closedSum_; // the closed voxels' summed-volume table over the padded grid (closedInBox)
  // Over the box cementLo_ + [0, cementDim_) about the particles, rebuilt every step (markCementRuns): per closed
  // or open occupied voxel the steps along +x to the next voxel that is neither (at most 255), 0 elsewhere.
  std::vector<std::uint8_t> cementRun_;
  int cementLo_[3] = {0, 0, 0}, cementDim_[3] = {0, 0, 0};
  double inverseSpacingX_ = 1; // 1 / the voxels' x spacing (rowRange)
  // The ghosts' sight tables (ghostHidden): offset numbering, per region voxel its table's slot (-1: none yet).
  int sightM_ = 0, sightEntries_ = 0;
  std::vector<int> sightIndex_;
  std::vector<std::int32_t> sightSlot_;
  std::vector<std::unique_ptr<std::atomic<std::uint8_t>[]>> sightBits_;
  std::vector<StencilEntry> stencil_;
  std::vector<std::ptrdiff_t> stencilOffsets_; // stencil_'s (and fieldStencil_'s) offsets alone
  int pad_ = 0, padSize_[3] = {1, 1, 1};
  std::vector<std::size_t> touched_, previousTouched_; // the voxels with colour (and the outlet ball's), this step and the last
  std::size_t shaftVoxels_ = 0, steps_ = 0, subSteps_ = 0, frontParticles_ = 0, subStepsClamped_ = 0, cappedSubStepMoves_ = 0;
  std::vector<Eigen::Vector3d> seeds_, candidates_;
  int cells_[3] = {1, 1, 1};
  std::vector<int> cellStart_, cellItems_;
  // Particles.
  std::vector<Eigen::Vector3d> x_, u_, darcy_, xm_, frozen_; // xm_, frozen_: the macro step's positions and field values (moveMultiRate)
  std::vector<double> p_, pc_, birth_, weights_; // Darcy pressure, density correction (solvePressure)
  std::vector<double> mu_, speed_, rel_; // viscosity [Pa s], Darcy speed [m/s], mobility / (k / mu_ref)
  std::unique_ptr<rheology::Rheology> law_;
  bool shearThinning_ = false;
  double referenceViscosity_ = 0, cannulaDrop_ = 0;
  // Geometry of the step.
  std::vector<int> pairI_, pairJ_, hiddenI_, hiddenJ_; // pairs in sight, and behind solid (hidePairsBehindSolid)
  std::vector<double> hiddenF_;
  std::vector<std::uint8_t> sightCheck_; // per region voxel: a closed voxel within a support (markSightChecks)
  std::size_t hiddenPairs_ = 0;          // pair-steps hidden, summed over the run
  std::vector<double> pairF_, pairW_, ghostF_, omega_, pairA_, diagA_;
  std::vector<double> missingMoment_, wallFactor_; // the wall correction (geometry, solvePressure)
  std::vector<std::uint8_t> isolated_; // rows with no neighbour or ghost in sight (solvePressure)
  std::vector<Eigen::Matrix3d> ghostB_;
  std::vector<Eigen::Vector3d> ghostNormal_, ghostPull_, closedGradC_;
  // Solver figures.
  std::size_t solves_ = 0, iterations_ = 0, correctionIterations_ = 0, unconverged_ = 0;
  double worstResidual_ = 0, solveSeconds_ = 0, geometrySeconds_ = 0;
  TipRecord outlet_{0, 0, 0};
};

} // namespace

std::unique_ptr<InjectionModel> makeParticleDarcyInjectionModel() { return std::make_unique<ParticleDarcyInjectionModel>(); }

// The scene keys this engine reads besides the driver's (InjectionModel.h): the particle spacing, the pore
// permeability (or the preset's drag through k0 = h^5 / (Cf d^3)), and the law and curing only to refuse any but
// a Newtonian cement.
InjectionModelRegistry::SceneKeys particleDarcySceneKeys() {
  return {"particle_radius_mm", "drag_coefficient", "pore_permeability_m2", "viscosity_law", "curing_model",
          "consistency_pa_s_n", "flow_index", "zero_shear_viscosity_pa_s", "infinite_shear_viscosity_pa_s",
          "carreau_time_constant_s"};
}

} // namespace cementsph::scene
