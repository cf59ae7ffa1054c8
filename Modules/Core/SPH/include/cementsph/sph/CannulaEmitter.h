// The injection source: cement leaving a cannula tip (Basafa et al. 2013, "Simulations": "fluid particles were
// added to the scene at the location of the cannula insertion ... The rate of adding fluid particles was
// determined based on their initial volume and the rate of injection. New fluid particles were assigned an
// initial velocity v0 = Q / (pi D^2 / 4)").
//
// Decisions (docs/injection-figures.md):
//  * Particle volume d^3, mass rho0 d^3 (VALIDATION.md: d = 2r).
//  * Volume-exact emission: particle k (k = 0, 1, ...) carries the injected volume [k d^3, (k+1) d^3) and is
//    emitted when the requested volume Q t reaches k d^3. So while injecting, 0 <= count d^3 - Q t < d^3 and
//    the remainder is carried over exactly (the count is computed from t, not accumulated, so it cannot drift).
//    Emission stops at floor(V_total / d^3) particles.
//  * Pattern: a square lattice of spacing d over the bore disc (diameter D) in the tip plane, rotated to the
//    cannula axis; of the two lattice offsets (a point on the axis, or the axis between four points) the one
//    whose count is nearest the area ratio (pi D^2 / 4) / d^2 is used. Both are symmetric under quarter turns,
//    so a full layer has its centroid on the axis. Particles fill the slots of a layer one at a time; a layer
//    holds N d^3 of cement, i.e. it is the slab of thickness N d^3 / (pi D^2 / 4) that the bore cement
//    advances at v0 in the time N d^3 / Q: emitting per volume and emitting per distance travelled agree.
//  * Position: the slot, moved along the axis by v0 (t - t_k) (t_k the particle's due time; at most one layer
//    thickness): where it would be had it left on time at v0. Exactly in the tip plane, a layer stays planar
//    under the overdamped integrator in empty space (nothing pushes it off the plane): measured, a flat disc.
//  * Velocity v0 along the axis (used by the central-difference and explicit integrators; the overdamped one
//    sets v = a / gamma, so there the cement is pushed out by the pressure of the particles behind it).
//  * Optional wall: fixed particles on rings of radius
//    D/2 + s/2 + k s (k < wallLayers), one ring every s from the tip plane back a length L, and the bore from
//    one fluid spacing d behind the tip to L filled with fixed particles (square lattice of spacing s), so
//    cement cannot flow back into the cannula. s = d/2 by default. Fixed particles of mass rho0 s^3 (the
//    paper's rho0 V) are permeable to this cloud: its model pressure (~1.5-2.5 kPa at 100-400 Pa.s, 0.05 ml/s)
//    exceeds rho0 cs^2 = 1.18 kPa, and cement was pushed 5-6 mm into the filled bore. The wall mass factor
//    (default 8, measured: nothing past the bore face at 100 and 400 Pa.s; factor 4 leaked at 400 Pa.s)
//    makes the wall stiffer than the cloud. Cement may still creep back along the outside of the shaft.
//  * At most one particle per step: run the simulation with ModelParameters::maxTimeStep = maxTimeStep().
#pragma once

#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace cementsph::sph {

class Simulation;

struct CannulaSpec {
  Eigen::Vector3d tip = Eigen::Vector3d::Zero();           // [m], centre of the bore at the cannula's end
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();    // along the flow (normalised by the emitter)
  double innerDiameter = 2.388e-3;                         // D [m] (11G regular wall)
  double flowRate = 0.05e-6;                               // Q [m^3/s] (0.05 ml/s)
  double totalVolume = 5e-6;                               // [m^3] (5 ml syringe)
  double spacing = 1.14e-3;                                // d [m] = 2r (r = 0.57 mm, the paper's choice)
  double restDensity = 1180.0;                             // rho0 [kg/m^3]
  double startTime = 0.0;                                  // [s] simulation time at which injection starts
  // Wall (fixed particles); off for injection into empty space without a cannula.
  bool buildWall = true;
  double wallLength = 10e-3;                               // L [m] behind the tip
  int wallLayers = 2;                                      // rings of radius D/2 + s/2 + k s
  bool fillBore = true;                                    // bore behind the tip filled with fixed particles
  double wallSpacingFraction = 0.5;                        // wall particle spacing s over d
  double wallMassFactor = 8.0;                             // wall particle mass = factor rho0 s^3 (see above)
};

class CannulaEmitter {
public:
  // Throws std::invalid_argument for non-positive D, Q, volume, spacing or density, or a zero direction.
  explicit CannulaEmitter(const CannulaSpec& spec);

  const CannulaSpec& spec() const { return spec_; }
  const Eigen::Vector3d& axis() const { return axis_; }
  // The slots of one layer, world positions in the tip plane.
  const std::vector<Eigen::Vector3d>& layerPattern() const { return pattern_; }
  std::size_t particlesPerLayer() const { return pattern_.size(); }
  double particleVolume() const { return spec_.spacing * spec_.spacing * spec_.spacing; }
  double particleMass() const { return spec_.restDensity * particleVolume(); }
  double layerVolume() const { return double(pattern_.size()) * particleVolume(); }
  double boreArea() const;
  double wallSpacing() const { return spec_.wallSpacingFraction * spec_.spacing; }
  double wallParticleMass() const {
    const double s = wallSpacing();
    return spec_.wallMassFactor * spec_.restDensity * s * s * s;
  }
  double layerThickness() const { return layerVolume() / boreArea(); }
  double exitSpeed() const { return spec_.flowRate / boreArea(); } // v0 = Q / (pi D^2 / 4)
  double particleInterval() const { return particleVolume() / spec_.flowRate; } // d^3 / Q [s]
  // The largest simulation step that emits at most one particle per step.
  double maxTimeStep() const { return particleInterval(); }
  std::size_t totalParticles() const { return totalParticles_; }

  // Adds the wall and the filled bore as fixed particles (nothing if buildWall is off); returns how many. Call before
  // the first step. Wall particles outside the simulation domain are skipped (counted in the return value only
  // when added).
  std::size_t addWall(Simulation& sim) const;
  // The wall and filled-bore positions (empty if buildWall is off).
  std::vector<Eigen::Vector3d> wallPositions() const;

  // Number of particles due by simulation time t: min(N_total, floor(Q (t - t0) / d^3) + 1), 0 before t0.
  std::size_t dueCount(double time) const;
  // Emits the particles due at sim.time(); returns how many were added now.
  std::size_t emit(Simulation& sim);

  std::size_t emittedCount() const { return emitted_; }
  double emittedVolume() const { return double(emitted_) * particleVolume(); }
  bool finished() const { return emitted_ >= totalParticles_; }
  // Fluid-particle ids assigned by the simulation to the emitted particles, in emission order.
  const std::vector<std::uint64_t>& emittedIds() const { return ids_; }

private:
  CannulaSpec spec_;
  Eigen::Vector3d axis_, e1_, e2_;
  std::vector<Eigen::Vector3d> pattern_;
  std::size_t totalParticles_ = 0;
  std::size_t emitted_ = 0;
  std::vector<std::uint64_t> ids_;
};

} // namespace cementsph::sph
