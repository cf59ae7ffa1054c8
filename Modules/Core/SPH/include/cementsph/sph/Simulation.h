// The particle model of Basafa et al. 2013 (weakly compressible SPH with fixed particles for the porous
// solid) and the models that replace its parts (ModelInterfaces.h, docs/architecture.md).
//
// One step: neighbour lists (reused while the skin allows) -> viscosity law -> pressure model's density
// (Eq. 2, or the incompressible model's volume fractions) -> resistance (Eq. 9 drag or k/mu) -> pressure
// (Eq. 6, or the incompressible solve) -> symmetric pressure force (Eq. 5), body force and, for Morris
// viscosity, Eq. 7 -> integration (Eq. 8 with the Eq. 9 drag implicit; explicit; or overdamped) -> a
// health check that stops a run going unstable with a message saying where and why -> domain sides.
//
// Fixed particles count as fluid particles for the density and pressure of moving ones but keep
// their own density, pressure, position and (zero) velocity (the paper, "Particle Fluid Model").
#pragma once

#include "cementsph/sph/Domain.h"
#include "cementsph/sph/FixedParticleField.h"
#include "cementsph/sph/Kernels.h"
#include "cementsph/sph/ModelInterfaces.h"
#include "cementsph/sph/ModelParameters.h"
#include "cementsph/sph/NeighbourSearch.h"
#include "cementsph/sph/PairIteration.h"
#include "cementsph/sph/Particles.h"

#include <memory>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace cementsph::sph {

// Thrown when the parameters are inconsistent or a run becomes unstable; what() says where and why.
class SimulationError : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

// A volume source [m^3/s] spread over the fluid particles within `radius` of `centre` (the cannula outlet
// for the incompressible model: the cement enters there at the flow rate).
struct VolumeSource {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double radius = 0.0;
  double rate = 0.0;
};

struct StepStatistics {
  std::uint64_t steps = 0;
  std::uint64_t neighbourRebuilds = 0;
  std::uint64_t relistings = 0; // list updates of the relisted particles alone (no full rebuild)
  double smallestStep = 0.0, largestStep = 0.0;
};

class Simulation {
public:
  Simulation(const ModelParameters& parameters, const Domain& domain);
  Simulation(const Simulation&) = delete; // the fixed field points into this object
  Simulation& operator=(const Simulation&) = delete;

  // --- set-up ------------------------------------------------------------------------------------
  std::uint64_t addFluidParticle(const Eigen::Vector3d& position, const Eigen::Vector3d& velocity, double mass);
  // `volume` [m^3]: the solid volume the particle stands for (0: mass / rho0), used by the incompressible
  // model's volume fractions.
  void addFixedParticle(const Eigen::Vector3d& position, double mass, double volume = 0.0);
  void reserveFluid(std::size_t n) { fluid_.reserve(n); }

  // --- running -----------------------------------------------------------------------------------
  // Advances one step and returns its length [s]. Throws SimulationError if the run goes unstable.
  double step();
  // Density and pressure of the current configuration (done by step(); exposed for tests and output).
  void updateDensityAndPressure();
  // Accelerations from pressure, body force and explicit viscosity (done by step()).
  void updateAccelerations();

  // --- state -------------------------------------------------------------------------------------
  const ModelParameters& parameters() const { return parameters_; }
  // The viscosity the viscosity law starts from; it may change during a run (the cement cures).
  void setViscosity(double viscosityPaS);
  void setVolumeSource(const VolumeSource& source) { source_ = source; }
  const VolumeSource& volumeSource() const { return source_; }
  // The models of this run (chosen by name from ModelParameters).
  PressureModel& pressureModel() { return *pressureModel_; }
  const PressureModel& pressureModel() const { return *pressureModel_; }
  const Resistance& resistance() const { return *resistance_; }
  const ViscosityLaw& viscosityLaw() const { return *viscosityLaw_; }
  const TimeIntegrator& integrator() const { return *integrator_; }
  // --- for the models --------------------------------------------------------------------------
  // The pair iteration over the current lists (PairIteration.h).
  PairIteration pairs() const;
  // Eq. 2 over fluid and fixed particles into fluid().density (lists must be up to date).
  void sumDensity();
  const CubicSplineKernel& densityKernel() const { return densityKernel_; }
  const SpikyKernel& pressureKernel() const { return pressureKernel_; }
  bool tabulatedFixedSums() const { return tabulated_; }
  // Fills the table's bricks at the fluid particles' positions (tabulated sums; then fixedField().sample).
  void prepareFixedField() { field_.prepare(fluid_.x.data(), fluid_.y.data(), fluid_.z.data(), fluid_.size()); }
  double maxDragRate() const;
  double minDragRate() const;
  std::uint64_t stepCount() const { return statistics_.steps; }
  void setBodyForce(const Eigen::Vector3d& force) { parameters_.bodyForce = force; }
  const Domain& domain() const { return domain_; }
  const FluidParticles& fluid() const { return fluid_; }
  FluidParticles& fluid() { return fluid_; }
  const FixedParticles& fixed() const { return fixed_; }
  double time() const { return time_; }
  const StepStatistics& statistics() const { return statistics_; }
  std::uint64_t escapedCount() const { return escaped_; }
  double kineticEnergy() const;
  StepLimits currentLimits() const;
  // The step the next call to step() will take, given the current state.
  double nextTimeStep() const;
  std::size_t neighbourPairCount() const {
    return fluidNeighbours_.size() + fixedNeighbours_.size() + relistedFluid_.size() + relistedFixed_.size();
  }
  // The tabulated fixed-particle sums (FixedSumMethod::Tabulated), for tests and reports.
  const FixedParticleField& fixedField() const { return field_; }
  std::size_t bytesPerFixedParticle() const;
  // Messages about the run that are not errors (e.g. a user's time step clamped to a limit).
  const std::vector<std::string>& warnings() const { return warnings_; }

private:
  void validateParameters() const;
  // The minimum-image separation on periodic axes (halfExtent_ is +inf on open ones, so they pass).
  void wrapMinimumImage(double& dx, double& dy, double& dz) const {
    if (dx > halfExtent_[0]) dx -= extent_[0]; else if (dx < -halfExtent_[0]) dx += extent_[0];
    if (dy > halfExtent_[1]) dy -= extent_[1]; else if (dy < -halfExtent_[1]) dy += extent_[1];
    if (dz > halfExtent_[2]) dz -= extent_[2]; else if (dz < -halfExtent_[2]) dz += extent_[2];
  }
  void updateNeighbourLists();
  void rebuildNeighbourLists();
  template <bool Periodic> void buildLists();
  void buildRelistedLists();
  template <bool Morris> void forcePass();
  double chooseTimeStep(const StepLimits& limits);
  void checkHealth(double dt) const;
  std::string describeParticle(std::size_t i) const;

  ModelParameters parameters_;
  Domain domain_;
  CubicSplineKernel densityKernel_;
  SpikyKernel pressureKernel_;
  FluidParticles fluid_;
  FixedParticles fixed_;

  CellGrid grid_;
  bool anyPeriodic_ = false;
  double halfExtent_[3], extent_[3]; // minimum image: half = +inf on open axes
  std::vector<std::uint32_t> fixedCellStart_, fluidCellStart_;
  bool fixedBinned_ = false;
  NeighbourList fluidNeighbours_, fixedNeighbours_;
  bool listsValid_ = false;
  // Relisting (ours): the lists above belong to particles [0, listed_) and hold while each particle
  // stays within half the skin of its reference position. Where only a few move that far (in an
  // injection, those near the tip), they alone are "relisted": new reference, their own lists
  // (relistedFluid_: every non-relisted neighbour, and relisted ones of lower index; relistedFixed_),
  // and every pair with one of them is summed from those lists for both partners, the others' entries
  // for them being skipped. Particles added since the rebuild are relisted from birth. A full rebuild
  // happens when too many are relisted.
  std::size_t listed_ = 0;
  std::vector<std::uint8_t> relisted_;         // per fluid particle
  std::vector<std::uint32_t> relistedIndex_;   // the relisted particles, ascending
  NeighbourList relistedFluid_, relistedFixed_; // per relisted particle, in relistedIndex_ order
  bool relistsDirty_ = false;
  std::vector<std::vector<std::uint32_t>> listScratch_; // per-thread list buffers of buildLists
  bool tabulated_ = false;
  FixedParticleField field_;
  std::vector<double> fixedGradX_, fixedGradY_, fixedGradZ_; // grad Phi per fluid particle (tabulated)
  std::vector<double> refX_, refY_, refZ_; // positions at the last rebuild (skin test)

  double time_ = 0.0;
  double centralDifferenceStep_ = 0.0; // the constant dt of Eq. 8 once chosen
  std::uint64_t nextId_ = 0;
  std::uint64_t escaped_ = 0;
  StepStatistics statistics_;
  std::vector<std::string> warnings_;
  std::vector<double> pressureOverDensity2_; // p / rho^2 per fluid particle, scratch of the force pass
  VolumeSource source_;
  std::unique_ptr<PressureModel> pressureModel_;
  std::unique_ptr<Resistance> resistance_;
  std::unique_ptr<ViscosityLaw> viscosityLaw_;
  std::unique_ptr<TimeIntegrator> integrator_;
  std::unique_ptr<DomainBoundary> boundary_;

public:
  // "fluid particle #id at (x, y, z) mm", for the models' error messages.
  std::string describeParticleForModels(std::size_t i) const { return describeParticle(i); }
};

} // namespace cementsph::sph
