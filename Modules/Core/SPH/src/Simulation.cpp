#include "cementsph/sph/Simulation.h"

#include "cementsph/sph/ModelRegistry.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

namespace cementsph::sph {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();

std::string formatSeconds(double s) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3g s", s);
  return b;
}
} // namespace

Simulation::Simulation(const ModelParameters& parameters, const Domain& domain)
    : parameters_(parameters), domain_(domain), densityKernel_(parameters.smoothingLength),
      pressureKernel_(parameters.smoothingLength) {
  validateParameters();
  const ModelRegistry& registry = ModelRegistry::instance();
  try {
    pressureModel_ = registry.pressure.create(parameters_.pressureModel, parameters_, "pressure model");
    resistance_ = registry.resistance.create(parameters_.resistanceName(), parameters_, "resistance");
    viscosityLaw_ = registry.viscosity.create(parameters_.viscosityLaw, parameters_, "viscosity law");
    integrator_ = registry.integrator.create(toString(parameters_.integrator), parameters_, "integrator");
    boundary_ = registry.boundary.create(parameters_.boundary, parameters_, "boundary");
  } catch (const std::invalid_argument& e) {
    throw SimulationError(e.what());
  }
  const double listRadius = densityKernel_.support() * (1.0 + 0.5 * parameters_.neighbourSkin);
  grid_.configure(domain_, listRadius);
  const Eigen::Vector3d e = domain_.extent();
  for (int a = 0; a < 3; ++a) {
    anyPeriodic_ = anyPeriodic_ || domain_.periodic[a];
    extent_[a] = e[a];
    halfExtent_[a] = domain_.periodic[a] ? 0.5 * e[a] : kInf;
  }
  fixed_.density = parameters_.restDensity;
  fixed_.pressure = parameters_.pressure(fixed_.density);
  tabulated_ = parameters_.fixedSums == FixedSumMethod::Tabulated;
  if (tabulated_)
  {
    field_.configure(domain_, parameters_.fixedFieldSpacing * parameters_.smoothingLength, parameters_.smoothingLength);
    field_.weighByVolume(parameters_.pressureModel == "incompressible");
  }
}

void Simulation::validateParameters() const {
  const ModelParameters& p = parameters_;
  auto require = [](bool ok, const std::string& what) {
    if (!ok) throw SimulationError(what);
  };
  require(std::isfinite(p.restDensity) && p.restDensity > 0, "rest density must be positive");
  require(std::isfinite(p.soundSpeed) && p.soundSpeed > 0, "speed of sound must be positive");
  require(std::isfinite(p.smoothingLength) && p.smoothingLength > 0, "smoothing length h must be positive");
  require(std::isfinite(p.viscosity) && p.viscosity >= 0, "viscosity must be zero or positive");
  require(p.neighbourSkin >= 0 && p.neighbourSkin <= 2, "neighbour skin must be within 0..2 h");
  if (p.viscosityModel != ViscosityModel::None)
    require(p.viscosity > 0, "viscosity must be positive for the " + toString(p.viscosityModel) + " model");
  if (p.viscosityModel == ViscosityModel::Drag)
    require(std::isfinite(p.dragCoefficient) && p.dragCoefficient > 0, "drag coefficient Cf must be positive");
  if (p.integrator == Integrator::Overdamped)
    require(p.resistanceName() != "none",
            "the overdamped integrator is the creeping-flow limit of a resistance (Eq. 9 drag or a permeability): "
            "use --viscosity-model drag");
  if (p.pressureModel == "incompressible") {
    require(p.integrator == Integrator::Overdamped,
            "the incompressible pressure model is a creeping (Darcy) flow: it needs the overdamped integrator");
    require(p.viscosityModel != ViscosityModel::Morris, "the incompressible pressure model takes no Morris viscosity");
  }
  if (p.integrator == Integrator::CentralDifference)
    require(p.viscosityModel != ViscosityModel::Morris,
            "the central-difference integrator (Eq. 8) is implicit in the drag only; Morris viscosity (Eq. 7) "
            "needs the explicit integrator");
  if (p.fixedSums == FixedSumMethod::Tabulated) {
    require(p.viscosityModel != ViscosityModel::Morris,
            "tabulated fixed-particle sums cover density and pressure only: use exact sums with Morris viscosity");
    require(!domain_.periodic[0] && !domain_.periodic[1] && !domain_.periodic[2],
            "tabulated fixed-particle sums need an open box: use exact sums with periodic sides");
    require(p.fixedFieldSpacing > 0 && p.fixedFieldSpacing <= 1, "fixed field spacing must be within 0..1 h");
  }
  if (p.fixedTimeStep) require(std::isfinite(*p.fixedTimeStep) && *p.fixedTimeStep > 0, "time step must be positive");
  if (p.maxTimeStep) require(std::isfinite(*p.maxTimeStep) && *p.maxTimeStep > 0, "maximum time step must be positive");
  const double listRadius = 2.0 * p.smoothingLength * (1.0 + 0.5 * p.neighbourSkin);
  const Eigen::Vector3d e = domain_.extent();
  for (int a = 0; a < 3; ++a) {
    require(e[a] > 0, "simulation domain has zero or negative extent");
    if (domain_.periodic[a])
      require(e[a] > 2.0 * listRadius, "periodic box is narrower than twice the neighbour radius (" +
                                            std::to_string(listRadius * 1e3) + " mm)");
  }
}

void Simulation::setViscosity(double viscosityPaS) {
  if (!(std::isfinite(viscosityPaS) && viscosityPaS > 0)) throw SimulationError("viscosity must be positive");
  parameters_.viscosity = viscosityPaS;
}

std::uint64_t Simulation::addFluidParticle(const Eigen::Vector3d& position, const Eigen::Vector3d& velocity,
                                           double mass) {
  if (!position.allFinite() || !velocity.allFinite() || !(mass > 0))
    throw SimulationError("fluid particle with a non-finite position or velocity, or non-positive mass");
  if (!domain_.contains(position)) throw SimulationError("fluid particle placed outside the domain");
  const std::size_t i = fluid_.add(position, velocity, mass, parameters_.restDensity, time_, nextId_);
  if (centralDifferenceStep_ > 0) { // Eq. 8 needs a previous position: one consistent with v
    fluid_.xp[i] = position.x() - velocity.x() * centralDifferenceStep_;
    fluid_.yp[i] = position.y() - velocity.y() * centralDifferenceStep_;
    fluid_.zp[i] = position.z() - velocity.z() * centralDifferenceStep_;
  }
  // A newcomer is relisted (its lists are made at the next update) instead of rebuilding every list.
  if (listsValid_ && parameters_.relisting && i == refX_.size()) {
    refX_.push_back(fluid_.x[i]);
    refY_.push_back(fluid_.y[i]);
    refZ_.push_back(fluid_.z[i]);
    relisted_.push_back(1);
    relistedIndex_.push_back(static_cast<std::uint32_t>(i));
    relistsDirty_ = true;
  } else {
    listsValid_ = false;
  }
  return nextId_++;
}

void Simulation::addFixedParticle(const Eigen::Vector3d& position, double mass, double volume) {
  if (!position.allFinite() || !(mass > 0)) throw SimulationError("fixed particle with a non-finite position or non-positive mass");
  if (!domain_.contains(position)) throw SimulationError("fixed particle placed outside the domain");
  if (volume <= 0) volume = mass / parameters_.restDensity;
  if (!std::isfinite(volume)) throw SimulationError("fixed particle with a non-finite volume");
  fixed_.add(position, mass, volume);
  fixedBinned_ = false;
  listsValid_ = false;
}

std::size_t Simulation::bytesPerFixedParticle() const {
  if (fixed_.size() == 0) return 0;
  // Positions and masses, plus the share of the fixed grid's cell offsets.
  const std::size_t bytes = fixed_.bytesUsed() + fixedCellStart_.capacity() * sizeof(std::uint32_t);
  return bytes / fixed_.size();
}

// ------------------------------------------------------------------------------------------------
// Neighbour lists
// ------------------------------------------------------------------------------------------------

void Simulation::updateNeighbourLists() {
  const std::size_t n = fluid_.size();
  const double skin = parameters_.neighbourSkin * parameters_.smoothingLength;
  if (!listsValid_ || !fixedBinned_ || refX_.size() != n || skin <= 0) {
    rebuildNeighbourLists();
    return;
  }
  const double limit2 = 0.25 * skin * skin; // a particle may move half the skin from its reference
  auto moved = [&](std::size_t i) {
    double dx = fluid_.x[i] - refX_[i], dy = fluid_.y[i] - refY_[i], dz = fluid_.z[i] - refZ_[i];
    if (anyPeriodic_) wrapMinimumImage(dx, dy, dz);
    return dx * dx + dy * dy + dz * dz > limit2;
  };
  std::size_t count = 0;
#pragma omp parallel for schedule(static) reduction(+ : count) if (n >= kParallelMinimum)
  for (std::size_t i = 0; i < n; ++i) count += moved(i) ? 1 : 0;
  const std::size_t relistLimit = parameters_.relisting ? std::max<std::size_t>(64, n / 16) : 0;
  if (count == 0 && !relistsDirty_) return;
  if (relistedIndex_.size() + count > relistLimit) {
    rebuildNeighbourLists();
    return;
  }
  if (count > 0) {
    bool added = false;
    for (std::size_t i = 0; i < n; ++i)
      if (moved(i)) {
        refX_[i] = fluid_.x[i]; refY_[i] = fluid_.y[i]; refZ_[i] = fluid_.z[i];
        if (!relisted_[i]) {
          relisted_[i] = 1;
          relistedIndex_.push_back(static_cast<std::uint32_t>(i));
          added = true;
        }
      }
    if (added) std::sort(relistedIndex_.begin(), relistedIndex_.end());
  }
  buildRelistedLists();
}

void Simulation::rebuildNeighbourLists() {
  std::vector<std::uint32_t> order;
  if (!fixedBinned_) {
    // Fixed particles are static: bin once and store them cell by cell.
    grid_.bin(fixed_.x.data(), fixed_.y.data(), fixed_.z.data(), fixed_.size(), order, fixedCellStart_);
    std::vector<double> s(order.size());
    for (auto* f : {&fixed_.x, &fixed_.y, &fixed_.z}) {
      for (std::size_t k = 0; k < order.size(); ++k) s[k] = (*f)[order[k]];
      f->swap(s);
      s.resize(order.size());
    }
    std::vector<float> sm(order.size());
    for (auto* f : {&fixed_.mass, &fixed_.volume}) {
      for (std::size_t k = 0; k < order.size(); ++k) sm[k] = (*f)[order[k]];
      f->swap(sm);
      sm.resize(order.size());
    }
    fixed_.x.shrink_to_fit(); fixed_.y.shrink_to_fit(); fixed_.z.shrink_to_fit();
    fixed_.mass.shrink_to_fit(); fixed_.volume.shrink_to_fit();
    fixedBinned_ = true;
    if (tabulated_) field_.attach(&fixed_, &grid_, &fixedCellStart_);
  }
  // Fluid particles are reordered by cell so that neighbours are close in memory.
  grid_.bin(fluid_.x.data(), fluid_.y.data(), fluid_.z.data(), fluid_.size(), order, fluidCellStart_);
  fluid_.permute(order);
  if (anyPeriodic_) buildLists<true>();
  else buildLists<false>();
  refX_ = fluid_.x;
  refY_ = fluid_.y;
  refZ_ = fluid_.z;
  listed_ = fluid_.size();
  relisted_.assign(listed_, 0);
  relistedIndex_.clear();
  relistedFluid_.offset.assign(1, 0);
  relistedFluid_.index.clear();
  relistedFixed_.offset.assign(1, 0);
  relistedFixed_.index.clear();
  relistsDirty_ = false;
  listsValid_ = true;
  ++statistics_.neighbourRebuilds;
}

template <bool Periodic> void Simulation::buildLists() {
  const std::size_t n = fluid_.size();
  const double radius = densityKernel_.support() + parameters_.neighbourSkin * parameters_.smoothingLength;
  const double r2max = radius * radius;
  const double* X = fluid_.x.data(); const double* Y = fluid_.y.data(); const double* Z = fluid_.z.data();
  const double* FX = fixed_.x.data(); const double* FY = fixed_.y.data(); const double* FZ = fixed_.z.data();

  auto within = [&](double xi, double yi, double zi, double xj, double yj, double zj) {
    double dx = xi - xj, dy = yi - yj, dz = zi - zj;
    if constexpr (Periodic) wrapMinimumImage(dx, dy, dz);
    return dx * dx + dy * dy + dz * dz < r2max;
  };
  auto visit = [&](std::size_t i, auto&& onFluid, auto&& onFixed) {
    const int cell = grid_.cellOf(X[i], Y[i], Z[i]);
    for (const std::uint32_t* c = grid_.neighbourCellsBegin(cell); c != grid_.neighbourCellsEnd(cell); ++c) {
      for (std::uint32_t j = fluidCellStart_[*c]; j < fluidCellStart_[*c + 1]; ++j)
        if (j != i && within(X[i], Y[i], Z[i], X[j], Y[j], Z[j])) onFluid(j);
      if (!fixedCellStart_.empty() && !tabulated_) // tabulated: the field holds the fixed sums
        for (std::uint32_t j = fixedCellStart_[*c]; j < fixedCellStart_[*c + 1]; ++j)
          if (within(X[i], Y[i], Z[i], FX[j], FY[j], FZ[j])) onFixed(j);
    }
  };
  // One pass: each thread lists a contiguous block of particles into its own buffers (offsets local to
  // the block), then the blocks are placed one after another. Deterministic, lock-free.
  fluidNeighbours_.offset.resize(n + 1);
  fixedNeighbours_.offset.resize(n + 1);
  fluidNeighbours_.offset[0] = fixedNeighbours_.offset[0] = 0;
  const int threads = omp_get_max_threads();
  listScratch_.resize(2 * static_cast<std::size_t>(threads));
#pragma omp parallel num_threads(threads)
  {
    const int t = omp_get_thread_num(), nt = omp_get_num_threads();
    const std::size_t begin = n * static_cast<std::size_t>(t) / static_cast<std::size_t>(nt);
    const std::size_t end = n * static_cast<std::size_t>(t + 1) / static_cast<std::size_t>(nt);
    std::vector<std::uint32_t>& lf = listScratch_[2 * static_cast<std::size_t>(t)];
    std::vector<std::uint32_t>& ls = listScratch_[2 * static_cast<std::size_t>(t) + 1];
    lf.clear();
    ls.clear();
    for (std::size_t i = begin; i < end; ++i) {
      visit(i, [&](std::uint32_t j) { lf.push_back(j); }, [&](std::uint32_t j) { ls.push_back(j); });
      fluidNeighbours_.offset[i + 1] = lf.size();
      fixedNeighbours_.offset[i + 1] = ls.size();
    }
#pragma omp barrier
#pragma omp single
    {
      // Make the block-local offsets global, block after block.
      std::uint64_t baseF = 0, baseS = 0;
      for (int b = 0; b < nt; ++b) {
        const std::size_t from = n * static_cast<std::size_t>(b) / static_cast<std::size_t>(nt);
        const std::size_t to = n * static_cast<std::size_t>(b + 1) / static_cast<std::size_t>(nt);
        for (std::size_t i = from; i < to; ++i) {
          fluidNeighbours_.offset[i + 1] += baseF;
          fixedNeighbours_.offset[i + 1] += baseS;
        }
        baseF += listScratch_[2 * static_cast<std::size_t>(b)].size();
        baseS += listScratch_[2 * static_cast<std::size_t>(b) + 1].size();
      }
      fluidNeighbours_.index.resize(baseF);
      fixedNeighbours_.index.resize(baseS);
    }
    if (end > begin) {
      std::copy(lf.begin(), lf.end(), fluidNeighbours_.index.begin() + static_cast<std::ptrdiff_t>(fluidNeighbours_.offset[begin]));
      std::copy(ls.begin(), ls.end(), fixedNeighbours_.index.begin() + static_cast<std::ptrdiff_t>(fixedNeighbours_.offset[begin]));
    }
  }
}

void Simulation::buildRelistedLists() {
  // Pairs are judged at reference positions with the list radius, as in a full rebuild: each particle
  // stays within half the skin of its reference, so no pair left out can come within the support. The
  // non-relisted particles' references are their positions at the last rebuild, where the grid binned
  // them (indices < listed_), so the grid finds them; relisted ones are few and searched directly.
  const double radius = densityKernel_.support() + parameters_.neighbourSkin * parameters_.smoothingLength;
  const double r2max = radius * radius;
  auto dist2 = [&](double dx, double dy, double dz) {
    if (anyPeriodic_) wrapMinimumImage(dx, dy, dz);
    return dx * dx + dy * dy + dz * dz;
  };
  relistedFluid_.offset.assign(1, 0);
  relistedFluid_.index.clear();
  relistedFixed_.offset.assign(1, 0);
  relistedFixed_.index.clear();
  for (std::size_t q = 0; q < relistedIndex_.size(); ++q) {
    const std::uint32_t i = relistedIndex_[q];
    const double xi = refX_[i], yi = refY_[i], zi = refZ_[i];
    const int cell = grid_.cellOf(xi, yi, zi);
    for (const std::uint32_t* c = grid_.neighbourCellsBegin(cell); c != grid_.neighbourCellsEnd(cell); ++c)
      for (std::uint32_t j = fluidCellStart_[*c]; j < fluidCellStart_[*c + 1]; ++j)
        if (!relisted_[j] && dist2(xi - refX_[j], yi - refY_[j], zi - refZ_[j]) < r2max) relistedFluid_.index.push_back(j);
    for (std::size_t p = 0; p < q; ++p) {
      const std::uint32_t j = relistedIndex_[p];
      if (dist2(xi - refX_[j], yi - refY_[j], zi - refZ_[j]) < r2max) relistedFluid_.index.push_back(j);
    }
    relistedFluid_.offset.push_back(relistedFluid_.index.size());
    if (!tabulated_ && !fixedCellStart_.empty())
      for (const std::uint32_t* c = grid_.neighbourCellsBegin(cell); c != grid_.neighbourCellsEnd(cell); ++c)
        for (std::uint32_t j = fixedCellStart_[*c]; j < fixedCellStart_[*c + 1]; ++j)
          if (dist2(xi - fixed_.x[j], yi - fixed_.y[j], zi - fixed_.z[j]) < r2max) relistedFixed_.index.push_back(j);
    relistedFixed_.offset.push_back(relistedFixed_.index.size());
  }
  relistsDirty_ = false;
  ++statistics_.relistings;
}

// ------------------------------------------------------------------------------------------------
// One step's parts
// ------------------------------------------------------------------------------------------------

PairIteration Simulation::pairs() const {
  PairIteration::Lists l;
  l.fluid = &fluidNeighbours_;
  l.fixed = &fixedNeighbours_;
  l.relistedFluid = &relistedFluid_;
  l.relistedFixed = &relistedFixed_;
  l.relistedIndex = &relistedIndex_;
  l.relisted = relisted_.data();
  l.listed = listed_;
  return PairIteration(fluid_, fixed_, l, densityKernel_.support(), extent_, halfExtent_, anyPeriodic_);
}

void Simulation::updateDensityAndPressure() {
  updateNeighbourLists();
  viscosityLaw_->update(*this);
  pressureModel_->density(*this);
  resistance_->update(*this);
  pressureModel_->pressure(*this);
}

// Eq. 2: rho_i = sum_j m_j W(r_ij, h) over fluid and fixed particles (the particle itself included).
void Simulation::sumDensity() {
  const std::size_t n = fluid_.size();
  const double w0 = densityKernel_.value(0.0);
  const double* M = fluid_.mass.data();
  const float* FM = fixed_.mass.data();
  double* RHO = fluid_.density.data();
  if (tabulated_) {
    field_.prepare(fluid_.x.data(), fluid_.y.data(), fluid_.z.data(), n);
    fixedGradX_.resize(n); fixedGradY_.resize(n); fixedGradZ_.resize(n);
  }
  // The summation order is the one the engine had before it was restructured (so the presets' runs are
  // unchanged to the last bit): the fixed particles' share is summed on its own (or sampled from the
  // table) and added after the fluid pairs, except for a relisted particle, whose fixed share comes first.
  struct Eq2 {
    using RelistedFixedFirst [[maybe_unused]] = std::true_type; // read by PairIteration (SFINAE)
    Simulation& s;
    const double* M; const float* FM; double* RHO; double w0;
    struct Acc {
      double rho, fixed;
      bool fixedFirst, added;
    };
    double sampleTable(std::size_t i) { // the fixed particles' share, and grad Phi for the force pass
      double d, g[3];
      s.field_.sample(s.fluid_.x[i], s.fluid_.y[i], s.fluid_.z[i], d, g);
      s.fixedGradX_[i] = g[0]; s.fixedGradY_[i] = g[1]; s.fixedGradZ_[i] = g[2];
      return d;
    }
    Acc begin(std::size_t i) {
      Acc a{M[i] * w0, 0.0, i < s.relisted_.size() && s.relisted_[i] != 0, false};
      if (a.fixedFirst && s.tabulated_) a.fixed = sampleTable(i);
      return a;
    }
    void addFixed(Acc& a) {
      if (!a.added) a.rho += a.fixed, a.added = true;
    }
    void fluid(std::size_t, std::size_t j, const Pair& p, Acc& a) {
      if (a.fixedFirst) addFixed(a);
      a.rho += M[j] * s.densityKernel_.value(p.r());
    }
    void mirror(std::size_t j, std::size_t i, const Pair& p) { RHO[j] += M[i] * s.densityKernel_.value(p.r()); }
    void fixed(std::size_t, std::uint32_t k, const Pair& p, Acc& a) {
      a.fixed += static_cast<double>(FM[k]) * s.densityKernel_.value(p.r());
    }
    void finish(std::size_t i, Acc& a) {
      if (!a.fixedFirst && s.tabulated_) a.fixed = sampleTable(i);
      addFixed(a);
      RHO[i] = a.rho;
    }
  } eq2{*this, M, FM, RHO, w0};
  pairs().visit(eq2);
}

void Simulation::updateAccelerations() {
  // The force pass needs the lists and densities of the current particle set: if particles were added
  // or removed since the last density update, do that update first.
  const std::size_t n = fluid_.size();
  const bool stale = !listsValid_ || relistsDirty_ || refX_.size() != n || fluid_.density.size() != n;
  if (pressureModel_->makesAccelerations()) { // its pressure() made them (with the current particle set)
    if (stale) updateDensityAndPressure();
    return;
  }
  if (stale || (tabulated_ && fixedGradX_.size() != n)) updateDensityAndPressure();
  if (parameters_.viscosityModel == ViscosityModel::Morris) forcePass<true>();
  else forcePass<false>();
}

// Eq. 5 (pressure, spiky kernel) and, for Morris, Eq. 7 (viscosity, cubic spline), plus the body force.
template <bool Morris> void Simulation::forcePass() {
  const std::size_t n = fluid_.size();
  const double h = parameters_.smoothingLength;
  const Eigen::Vector3d g = parameters_.bodyForce;
  // p / rho^2 of each particle, used by every pair (Eq. 5).
  pressureOverDensity2_.resize(n);
  double* pr2 = pressureOverDensity2_.data();
#pragma omp parallel for schedule(static) if (n >= kParallelMinimum)
  for (std::size_t i = 0; i < n; ++i) pr2[i] = fluid_.pressure[i] / (fluid_.density[i] * fluid_.density[i]);

  struct Eq5 {
    Simulation& s;
    const double* pr2;
    double h, eta2, fixedPr2, gx, gy, gz;
    const double* M; const double* RHO; const double* MU;
    const double* VX; const double* VY; const double* VZ;
    const float* FM;
    double* AX; double* AY; double* AZ;
    struct Acc { double x, y, z; };
    Acc begin(std::size_t) const { return {gx, gy, gz}; }
    // The pair's acceleration of i per unit mass of j (that of j is minus it per unit mass of i).
    void pairForce(std::size_t i, std::size_t j, const Pair& p, double& fx, double& fy, double& fz) const {
      const double r = p.r();
      double ux, uy, uz;
      if (r > 1e-12 * h) { ux = p.dx / r; uy = p.dy / r; uz = p.dz / r; }
      else { // coincident pair: the spiky gradient is finite, its direction is not; split them
        ux = (i < j) ? 1.0 : -1.0; uy = 0.0; uz = 0.0; // along x, antisymmetric: momentum conserved
      }
      // Eq. 5: a_i -= m_j (p_i/rho_i^2 + p_j/rho_j^2) grad W_spiky
      const double f = -(pr2[i] + pr2[j]) * s.pressureKernel_.derivative(r);
      fx = f * ux; fy = f * uy; fz = f * uz;
      if constexpr (Morris) {
        // Eq. 7: m_j (mu_i + mu_j) / (rho_i rho_j) (r_ij . grad W) / (r_ij^2 + 0.01 h^2) (v_i - v_j)
        const double v = (MU[i] + MU[j]) / (RHO[i] * RHO[j]) * (r * s.densityKernel_.derivative(r)) / (p.r2 + eta2);
        fx += v * (VX[i] - VX[j]); fy += v * (VY[i] - VY[j]); fz += v * (VZ[i] - VZ[j]);
      }
    }
    void fluid(std::size_t i, std::size_t j, const Pair& p, Acc& a) const {
      double fx, fy, fz;
      pairForce(i, j, p, fx, fy, fz);
      a.x += M[j] * fx; a.y += M[j] * fy; a.z += M[j] * fz;
    }
    void mirror(std::size_t j, std::size_t i, const Pair& p) const {
      double fx, fy, fz;
      pairForce(i, j, p, fx, fy, fz);
      AX[j] -= M[i] * fx; AY[j] -= M[i] * fy; AZ[j] -= M[i] * fz;
    }
    void fixed(std::size_t i, std::uint32_t k, const Pair& p, Acc& a) const {
      const double r = p.r();
      double ux = 1.0, uy = 0.0, uz = 0.0; // a fluid particle exactly on a fixed one is pushed along +x
      if (r > 1e-12 * h) { ux = p.dx / r; uy = p.dy / r; uz = p.dz / r; }
      const double mj = static_cast<double>(FM[k]);
      const double f = -mj * (pr2[i] + fixedPr2) * s.pressureKernel_.derivative(r);
      a.x += f * ux; a.y += f * uy; a.z += f * uz;
      if constexpr (Morris) { // fixed particles have zero velocity: the no-slip condition
        const double v = mj * (2.0 * MU[i]) / (RHO[i] * s.fixed_.density) * (r * s.densityKernel_.derivative(r)) / (p.r2 + eta2);
        a.x += v * VX[i]; a.y += v * VY[i]; a.z += v * VZ[i];
      }
    }
    void finish(std::size_t i, Acc& a) const {
      if (s.tabulated_) { // the gradient of the tabulated potential holds the fixed particles' share
        const double c = -(pr2[i] + fixedPr2);
        a.x += c * s.fixedGradX_[i]; a.y += c * s.fixedGradY_[i]; a.z += c * s.fixedGradZ_[i];
      }
      AX[i] = a.x; AY[i] = a.y; AZ[i] = a.z;
    }
  } eq5{*this, pr2, h, 0.01 * h * h, // Eq. 7 regularisation (Morris et al. 1997)
        fixed_.pressure / (fixed_.density * fixed_.density), g.x(), g.y(), g.z(),
        fluid_.mass.data(), fluid_.density.data(), fluid_.viscosity.data(),
        fluid_.vx.data(), fluid_.vy.data(), fluid_.vz.data(), fixed_.mass.data(),
        fluid_.ax.data(), fluid_.ay.data(), fluid_.az.data()};
  pairs().visit(eq5);
}

// ------------------------------------------------------------------------------------------------
// Time step
// ------------------------------------------------------------------------------------------------

double Simulation::maxDragRate() const {
  double g = 0;
  const std::size_t n = fluid_.size();
#pragma omp parallel for schedule(static) reduction(max : g) if (n >= kParallelMinimum)
  for (std::size_t i = 0; i < n; ++i) g = std::max(g, fluid_.dragRate[i]);
  return g;
}

double Simulation::minDragRate() const {
  double g = kInf;
  const std::size_t n = fluid_.size();
#pragma omp parallel for schedule(static) reduction(min : g) if (n >= kParallelMinimum)
  for (std::size_t i = 0; i < n; ++i) g = std::min(g, fluid_.dragRate[i]);
  return g;
}

StepLimits Simulation::currentLimits() const { return integrator_->limits(*this); }

double Simulation::chooseTimeStep(const StepLimits& limits) {
  const ModelParameters& p = parameters_;
  const double stable = limits.stable();
  if (integrator_->constantStep() && centralDifferenceStep_ > 0) return centralDifferenceStep_;
  double dt;
  if (p.fixedTimeStep) {
    dt = *p.fixedTimeStep;
    if (dt > stable) {
      std::string which = "acoustic";
      if (stable == limits.viscous) which = "viscous";
      else if (stable == limits.drag) which = "explicit drag";
      else if (stable == limits.force) which = "force";
      else if (stable == limits.overdamped) which = "overdamped";
      const std::string msg = "time step " + formatSeconds(dt) + " exceeds the " + which + " stability limit " +
                              formatSeconds(stable) + " of the " + integrator_->name() + " integrator";
      if (p.stepLimitPolicy == StepLimitPolicy::Refuse) throw SimulationError(msg);
      if (warnings_.empty() || warnings_.back() != msg + "; clamped") warnings_.push_back(msg + "; clamped");
      dt = stable;
    }
  } else {
    dt = std::min(stable, limits.displacement);
    if (p.maxTimeStep) dt = std::min(dt, *p.maxTimeStep);
  }
  if (!std::isfinite(dt) || dt <= 0) throw SimulationError("no finite time step: nothing limits it (no fluid, no forces)");
  if (integrator_->constantStep()) {
    // Eq. 8 uses one constant step; start the previous positions consistently with the velocities.
    centralDifferenceStep_ = dt;
    for (std::size_t i = 0; i < fluid_.size(); ++i) {
      fluid_.xp[i] = fluid_.x[i] - fluid_.vx[i] * dt;
      fluid_.yp[i] = fluid_.y[i] - fluid_.vy[i] * dt;
      fluid_.zp[i] = fluid_.z[i] - fluid_.vz[i] * dt;
    }
  }
  return dt;
}

double Simulation::nextTimeStep() const {
  if (integrator_->constantStep() && centralDifferenceStep_ > 0) return centralDifferenceStep_;
  const StepLimits l = currentLimits();
  if (parameters_.fixedTimeStep) return std::min(*parameters_.fixedTimeStep, l.stable());
  const double dt = std::min(l.stable(), l.displacement);
  return parameters_.maxTimeStep ? std::min(dt, *parameters_.maxTimeStep) : dt;
}

// ------------------------------------------------------------------------------------------------
// Health and the step
// ------------------------------------------------------------------------------------------------

std::string Simulation::describeParticle(std::size_t i) const {
  std::ostringstream s;
  s.precision(4);
  s << "fluid particle #" << fluid_.id[i] << " at (" << fluid_.x[i] * 1e3 << ", " << fluid_.y[i] * 1e3 << ", "
    << fluid_.z[i] * 1e3 << ") mm";
  return s.str();
}

void Simulation::checkHealth(double dt) const {
  const std::size_t n = fluid_.size();
  // A runaway is a particle far faster than the model allows: ten times the speed of sound for an
  // equation of state; for the incompressible model (no sound speed) the same bound is kept as an
  // absolute 10 m/s, four orders above any creeping cement flow.
  const double vmax = parameters_.runawaySpeedFactor * parameters_.soundSpeed;
  std::size_t firstBad = n;
#pragma omp parallel for schedule(static) reduction(min : firstBad) if (n >= kParallelMinimum)
  for (std::size_t i = 0; i < n; ++i) {
    const double v2 = fluid_.vx[i] * fluid_.vx[i] + fluid_.vy[i] * fluid_.vy[i] + fluid_.vz[i] * fluid_.vz[i];
    const bool finite = std::isfinite(fluid_.x[i]) && std::isfinite(fluid_.y[i]) && std::isfinite(fluid_.z[i]) &&
                        std::isfinite(v2) && std::isfinite(fluid_.density[i]) && std::isfinite(fluid_.pressure[i]);
    if (!finite || v2 > vmax * vmax) firstBad = std::min(firstBad, i);
  }
  if (firstBad == n) return;
  const std::size_t i = firstBad;
  std::ostringstream s;
  s.precision(4);
  s << "simulation unstable at step " << statistics_.steps + 1 << " (t = " << time_ << " s, dt = " << dt << " s): ";
  const double v = std::sqrt(fluid_.vx[i] * fluid_.vx[i] + fluid_.vy[i] * fluid_.vy[i] + fluid_.vz[i] * fluid_.vz[i]);
  if (!std::isfinite(v) || !std::isfinite(fluid_.x[i]) || !std::isfinite(fluid_.density[i]) ||
      !std::isfinite(fluid_.pressure[i]))
    s << describeParticle(i) << " has a non-finite position, velocity, density or pressure";
  else
    s << describeParticle(i) << " moves at " << v << " m/s, over " << parameters_.runawaySpeedFactor
      << " times the speed of sound (runaway)";
  const StepLimits l = currentLimits();
  s << "; " << integrator_->name() << " stability limit " << l.stable() << " s, pressure model "
    << pressureModel_->name() << ": reduce the time step or check the scene";
  throw SimulationError(s.str());
}

double Simulation::step() {
  if (fluid_.size() == 0) throw SimulationError("no fluid particles to simulate");
  updateDensityAndPressure();
  updateAccelerations();
  const double dt = chooseTimeStep(currentLimits());
  integrator_->integrate(*this, dt);
  checkHealth(dt);
  const std::size_t leaving = boundary_->apply(*this);
  if (leaving) {
    escaped_ += leaving;
    listsValid_ = false;
  }
  pressureModel_->stepDone(dt);
  time_ += dt;
  ++statistics_.steps;
  statistics_.smallestStep = statistics_.steps == 1 ? dt : std::min(statistics_.smallestStep, dt);
  statistics_.largestStep = std::max(statistics_.largestStep, dt);
  return dt;
}

double Simulation::kineticEnergy() const {
  double e = 0;
  for (std::size_t i = 0; i < fluid_.size(); ++i)
    e += 0.5 * fluid_.mass[i] * (fluid_.vx[i] * fluid_.vx[i] + fluid_.vy[i] * fluid_.vy[i] + fluid_.vz[i] * fluid_.vz[i]);
  return e;
}

} // namespace cementsph::sph
