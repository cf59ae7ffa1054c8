#include "cementsph/sph/Simulation.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

namespace cementsph::sph {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
// Loops that do a few operations per particle run on one thread below this many particles: their
// work is microseconds, and every parallel loop ends in a barrier that costs far more when another
// program holds a core (measured: 2 threads 6x slower than 1 on a loaded 2-core machine).
constexpr std::size_t kParallelMinimum = 16384;

std::string formatSeconds(double s) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3g s", s);
  return b;
}
} // namespace

double StepLimits::stable() const { return std::min({acoustic, viscous, drag, force, overdamped}); }

Simulation::Simulation(const ModelParameters& parameters, const Domain& domain)
    : parameters_(parameters), domain_(domain), densityKernel_(parameters.smoothingLength),
      pressureKernel_(parameters.smoothingLength) {
  validateParameters();
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
    field_.configure(domain_, parameters_.fixedFieldSpacing * parameters_.smoothingLength, parameters_.smoothingLength);
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
    require(p.viscosityModel == ViscosityModel::Drag,
            "the overdamped integrator is the creeping-flow limit of the drag model (Eq. 9): use --viscosity-model drag");
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

void Simulation::addFixedParticle(const Eigen::Vector3d& position, double mass) {
  if (!position.allFinite() || !(mass > 0)) throw SimulationError("fixed particle with a non-finite position or non-positive mass");
  if (!domain_.contains(position)) throw SimulationError("fixed particle placed outside the domain");
  fixed_.add(position, mass);
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
    for (std::size_t k = 0; k < order.size(); ++k) sm[k] = fixed_.mass[order[k]];
    fixed_.mass.swap(sm);
    fixed_.x.shrink_to_fit(); fixed_.y.shrink_to_fit(); fixed_.z.shrink_to_fit(); fixed_.mass.shrink_to_fit();
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
// Density (Eq. 2) and pressure (Eq. 6)
// ------------------------------------------------------------------------------------------------

void Simulation::updateDensityAndPressure() {
  updateNeighbourLists();
  if (anyPeriodic_) densityPass<true>();
  else densityPass<false>();
}

#define CEMENTSPH_MINIMUM_IMAGE(dx, dy, dz) \
  if constexpr (Periodic) wrapMinimumImage(dx, dy, dz);

template <bool Periodic> void Simulation::densityPass() {
  const std::size_t n = fluid_.size();
  const double support2 = densityKernel_.support() * densityKernel_.support();
  const double w0 = densityKernel_.value(0.0);
  const double cs2 = parameters_.soundSpeed * parameters_.soundSpeed, rho0 = parameters_.restDensity;
  const double* X = fluid_.x.data(); const double* Y = fluid_.y.data(); const double* Z = fluid_.z.data();
  const double* M = fluid_.mass.data();
  const double* FX = fixed_.x.data(); const double* FY = fixed_.y.data(); const double* FZ = fixed_.z.data();
  const float* FM = fixed_.mass.data();
  double* RHO = fluid_.density.data();
  double* P = fluid_.pressure.data();
  if (tabulated_) {
    field_.prepare(X, Y, Z, n);
    fixedGradX_.resize(n); fixedGradY_.resize(n); fixedGradZ_.resize(n);
  }
  // The fixed particles' share at particle i: the table (which also gives grad Phi for the force pass),
  // or the pair sum over i's fixed list [begin, end).
  auto fixedDensity = [&](std::size_t i, const std::uint32_t* list, std::uint64_t begin, std::uint64_t end) {
    if (tabulated_) {
      double d, g[3];
      field_.sample(X[i], Y[i], Z[i], d, g);
      fixedGradX_[i] = g[0]; fixedGradY_[i] = g[1]; fixedGradZ_[i] = g[2];
      return d;
    }
    double rho = 0.0;
    for (std::uint64_t k = begin; k < end; ++k) {
      const std::uint32_t j = list[k];
      double dx = X[i] - FX[j], dy = Y[i] - FY[j], dz = Z[i] - FZ[j];
      CEMENTSPH_MINIMUM_IMAGE(dx, dy, dz)
      const double r2 = dx * dx + dy * dy + dz * dz;
      if (r2 < support2) rho += static_cast<double>(FM[j]) * densityKernel_.value(std::sqrt(r2));
    }
    return rho;
  };
  const std::uint32_t* fl = fluidNeighbours_.index.data();
  const std::uint32_t* sl = fixedNeighbours_.index.data();
  const std::size_t listed = listed_;
  const std::uint8_t* relisted = relisted_.data();
#pragma omp parallel for schedule(static)
  for (std::size_t i = 0; i < listed; ++i) {
    if (relisted[i]) continue; // summed from its own lists below
    const double xi = X[i], yi = Y[i], zi = Z[i];
    double rho = M[i] * w0; // the particle itself
    for (std::uint64_t k = fluidNeighbours_.offset[i]; k < fluidNeighbours_.offset[i + 1]; ++k) {
      const std::uint32_t j = fl[k];
      if (relisted[j]) continue; // the pair is in j's lists
      double dx = xi - X[j], dy = yi - Y[j], dz = zi - Z[j];
      CEMENTSPH_MINIMUM_IMAGE(dx, dy, dz)
      const double r2 = dx * dx + dy * dy + dz * dz;
      if (r2 < support2) rho += M[j] * densityKernel_.value(std::sqrt(r2));
    }
    rho += fixedDensity(i, sl, fixedNeighbours_.offset[i], fixedNeighbours_.offset[i + 1]);
    RHO[i] = rho;
    P[i] = cs2 * (rho - rho0);
  }
  // Relisted particles, in ascending order: each pair in their lists adds to both partners.
  for (std::size_t q = 0; q < relistedIndex_.size(); ++q) {
    const std::size_t i = relistedIndex_[q];
    double rho = M[i] * w0 + fixedDensity(i, relistedFixed_.index.data(), relistedFixed_.offset[q], relistedFixed_.offset[q + 1]);
    for (std::uint64_t k = relistedFluid_.offset[q]; k < relistedFluid_.offset[q + 1]; ++k) {
      const std::uint32_t j = relistedFluid_.index[k];
      double dx = X[i] - X[j], dy = Y[i] - Y[j], dz = Z[i] - Z[j];
      CEMENTSPH_MINIMUM_IMAGE(dx, dy, dz)
      const double r2 = dx * dx + dy * dy + dz * dz;
      if (r2 >= support2) continue;
      const double w = densityKernel_.value(std::sqrt(r2));
      rho += M[j] * w;
      RHO[j] += M[i] * w;
      P[j] = cs2 * (RHO[j] - rho0);
    }
    RHO[i] = rho;
    P[i] = cs2 * (rho - rho0);
  }
}

// ------------------------------------------------------------------------------------------------
// Accelerations: pressure (Eq. 5), body force, Morris viscosity (Eq. 7)
// ------------------------------------------------------------------------------------------------

void Simulation::updateAccelerations() {
  // The force pass needs the lists and densities of the current particle set: if particles were added
  // or removed since the last density update, do that update first.
  const std::size_t n = fluid_.size();
  if (!listsValid_ || relistsDirty_ || refX_.size() != n || fluid_.density.size() != n ||
      (tabulated_ && fixedGradX_.size() != n))
    updateDensityAndPressure();
  const bool morris = parameters_.viscosityModel == ViscosityModel::Morris;
  if (anyPeriodic_) morris ? forcePass<true, true>() : forcePass<true, false>();
  else morris ? forcePass<false, true>() : forcePass<false, false>();
}

template <bool Periodic, bool Morris> void Simulation::forcePass() {
  const std::size_t n = fluid_.size();
  const double h = parameters_.smoothingLength;
  const double support2 = 4.0 * h * h;
  const double eta2 = 0.01 * h * h; // Eq. 7 regularisation (Morris et al. 1997)
  const double twoMu = 2.0 * parameters_.viscosity;
  const Eigen::Vector3d g = parameters_.bodyForce;
  // p / rho^2 of each particle, used by every pair (Eq. 5).
  pressureOverDensity2_.resize(n);
  double* pr2 = pressureOverDensity2_.data();
#pragma omp parallel for schedule(static) if (n >= kParallelMinimum)
  for (std::size_t i = 0; i < n; ++i) pr2[i] = fluid_.pressure[i] / (fluid_.density[i] * fluid_.density[i]);
  const double fixedPr2 = fixed_.pressure / (fixed_.density * fixed_.density);
  const double* X = fluid_.x.data(); const double* Y = fluid_.y.data(); const double* Z = fluid_.z.data();
  const double* VX = fluid_.vx.data(); const double* VY = fluid_.vy.data(); const double* VZ = fluid_.vz.data();
  const double* M = fluid_.mass.data(); const double* RHO = fluid_.density.data();
  const double* FX = fixed_.x.data(); const double* FY = fixed_.y.data(); const double* FZ = fixed_.z.data();
  const float* FM = fixed_.mass.data();
  double* AX = fluid_.ax.data(); double* AY = fluid_.ay.data(); double* AZ = fluid_.az.data();
  const double fixedRho = fixed_.density;

  // Eq. 5 (and Eq. 7) for the pair (i, j): the acceleration of i is +(fx, fy, fz) M[j], that of j is
  // -(fx, fy, fz) M[i] (antisymmetric: momentum is conserved pair by pair).
  auto pairForce = [&](std::size_t i, std::size_t j, double& fx, double& fy, double& fz) {
    double dx = X[i] - X[j], dy = Y[i] - Y[j], dz = Z[i] - Z[j];
    CEMENTSPH_MINIMUM_IMAGE(dx, dy, dz)
    const double r2 = dx * dx + dy * dy + dz * dz;
    fx = fy = fz = 0.0;
    if (r2 >= support2) return;
    const double r = std::sqrt(r2);
    double ux, uy, uz;
    if (r > 1e-12 * h) { ux = dx / r; uy = dy / r; uz = dz / r; }
    else { // coincident pair: the spiky gradient is finite, its direction is not; split them
      ux = (i < j) ? 1.0 : -1.0; uy = 0.0; uz = 0.0; // along x, antisymmetric: momentum conserved
    }
    // Eq. 5: a_i -= m_j (p_i/rho_i^2 + p_j/rho_j^2) grad W_spiky
    const double f = -(pr2[i] + pr2[j]) * pressureKernel_.derivative(r);
    fx = f * ux; fy = f * uy; fz = f * uz;
    if constexpr (Morris) {
      // Eq. 7: m_j (mu_i + mu_j) / (rho_i rho_j) (r_ij . grad W) / (r_ij^2 + 0.01 h^2) (v_i - v_j)
      const double v = twoMu / (RHO[i] * RHO[j]) * (r * densityKernel_.derivative(r)) / (r2 + eta2);
      fx += v * (VX[i] - VX[j]); fy += v * (VY[i] - VY[j]); fz += v * (VZ[i] - VZ[j]);
    }
  };
  // The fixed particles' share at particle i: the gradient of the tabulated potential, or the pairs of
  // i's fixed list [begin, end).
  auto fixedForce = [&](std::size_t i, const std::uint32_t* list, std::uint64_t begin, std::uint64_t end,
                        double& ax, double& ay, double& az) {
    const double pi = pr2[i];
    if (tabulated_) {
      const double c = -(pi + fixedPr2);
      ax += c * fixedGradX_[i]; ay += c * fixedGradY_[i]; az += c * fixedGradZ_[i];
      return;
    }
    for (std::uint64_t k = begin; k < end; ++k) {
      const std::uint32_t j = list[k];
      double dx = X[i] - FX[j], dy = Y[i] - FY[j], dz = Z[i] - FZ[j];
      CEMENTSPH_MINIMUM_IMAGE(dx, dy, dz)
      const double r2 = dx * dx + dy * dy + dz * dz;
      if (r2 >= support2) continue;
      const double r = std::sqrt(r2);
      double ux = 1.0, uy = 0.0, uz = 0.0; // a fluid particle exactly on a fixed one is pushed along +x
      if (r > 1e-12 * h) { ux = dx / r; uy = dy / r; uz = dz / r; }
      const double mj = static_cast<double>(FM[j]);
      const double f = -mj * (pi + fixedPr2) * pressureKernel_.derivative(r);
      ax += f * ux; ay += f * uy; az += f * uz;
      if constexpr (Morris) { // fixed particles have zero velocity: the no-slip condition
        const double v = mj * twoMu / (RHO[i] * fixedRho) * (r * densityKernel_.derivative(r)) / (r2 + eta2);
        ax += v * VX[i]; ay += v * VY[i]; az += v * VZ[i];
      }
    }
  };
  const std::uint32_t* fl = fluidNeighbours_.index.data();
  const std::uint32_t* sl = fixedNeighbours_.index.data();
  const std::size_t listed = listed_;
  const std::uint8_t* relisted = relisted_.data();
#pragma omp parallel for schedule(static)
  for (std::size_t i = 0; i < listed; ++i) {
    if (relisted[i]) continue; // summed from its own lists below
    double ax = g.x(), ay = g.y(), az = g.z();
    for (std::uint64_t k = fluidNeighbours_.offset[i]; k < fluidNeighbours_.offset[i + 1]; ++k) {
      const std::uint32_t j = fl[k];
      if (relisted[j]) continue; // the pair is in j's lists
      double fx, fy, fz;
      pairForce(i, j, fx, fy, fz);
      ax += M[j] * fx; ay += M[j] * fy; az += M[j] * fz;
    }
    fixedForce(i, sl, fixedNeighbours_.offset[i], fixedNeighbours_.offset[i + 1], ax, ay, az);
    AX[i] = ax; AY[i] = ay; AZ[i] = az;
  }
  // Relisted particles, in ascending order: each pair in their lists acts on both partners.
  for (std::size_t q = 0; q < relistedIndex_.size(); ++q) {
    const std::size_t i = relistedIndex_[q];
    double ax = g.x(), ay = g.y(), az = g.z();
    for (std::uint64_t k = relistedFluid_.offset[q]; k < relistedFluid_.offset[q + 1]; ++k) {
      const std::uint32_t j = relistedFluid_.index[k];
      double fx, fy, fz;
      pairForce(i, j, fx, fy, fz);
      ax += M[j] * fx; ay += M[j] * fy; az += M[j] * fz;
      AX[j] -= M[i] * fx; AY[j] -= M[i] * fy; AZ[j] -= M[i] * fz;
    }
    fixedForce(i, relistedFixed_.index.data(), relistedFixed_.offset[q], relistedFixed_.offset[q + 1], ax, ay, az);
    AX[i] = ax; AY[i] = ay; AZ[i] = az;
  }
}
#undef CEMENTSPH_MINIMUM_IMAGE

// ------------------------------------------------------------------------------------------------
// Time step
// ------------------------------------------------------------------------------------------------

double Simulation::maxDragRate() const {
  if (parameters_.viscosityModel != ViscosityModel::Drag) return 0;
  double g = 0;
  const std::size_t n = fluid_.size();
#pragma omp parallel for schedule(static) reduction(max : g) if (n >= kParallelMinimum)
  for (std::size_t i = 0; i < n; ++i) g = std::max(g, parameters_.dragRate(fluid_.mass[i], fluid_.density[i]));
  return g;
}

double Simulation::minDragRate() const {
  if (parameters_.viscosityModel != ViscosityModel::Drag) return 0;
  double g = kInf;
  const std::size_t n = fluid_.size();
#pragma omp parallel for schedule(static) reduction(min : g) if (n >= kParallelMinimum)
  for (std::size_t i = 0; i < n; ++i) g = std::min(g, parameters_.dragRate(fluid_.mass[i], fluid_.density[i]));
  return g;
}

StepLimits Simulation::currentLimits() const {
  const ModelParameters& p = parameters_;
  const double h = p.smoothingLength;
  StepLimits l{kInf, kInf, kInf, kInf, kInf, kInf};
  double amax2 = 0, vmax2 = 0;
  const std::size_t n = fluid_.size();
  if (p.integrator == Integrator::Overdamped) {
    const double gmin = minDragRate();
    l.overdamped = p.overdampedStability * gmin * h * h / (p.soundSpeed * p.soundSpeed);
    // v = a / gamma; the fastest particle bounds the step for accuracy.
#pragma omp parallel for schedule(static) reduction(max : vmax2) if (n >= kParallelMinimum)
    for (std::size_t i = 0; i < n; ++i) {
      const double g = p.dragRate(fluid_.mass[i], fluid_.density[i]);
      const double a2 = fluid_.ax[i] * fluid_.ax[i] + fluid_.ay[i] * fluid_.ay[i] + fluid_.az[i] * fluid_.az[i];
      vmax2 = std::max(vmax2, a2 / (g * g));
    }
    if (vmax2 > 0) l.displacement = p.maxDisplacement * h / std::sqrt(vmax2);
    return l;
  }
  l.acoustic = p.acousticCourant * h / p.soundSpeed;
#pragma omp parallel for schedule(static) reduction(max : amax2) if (n >= kParallelMinimum)
  for (std::size_t i = 0; i < n; ++i)
    amax2 = std::max(amax2, fluid_.ax[i] * fluid_.ax[i] + fluid_.ay[i] * fluid_.ay[i] + fluid_.az[i] * fluid_.az[i]);
  if (amax2 > 0) l.force = p.forceCourant * std::sqrt(h / std::sqrt(amax2));
  if (p.integrator == Integrator::Explicit) {
    if (p.viscosityModel == ViscosityModel::Morris) l.viscous = p.viscousNumber * h * h * p.restDensity / p.viscosity;
    if (p.viscosityModel == ViscosityModel::Drag) {
      const double g = maxDragRate();
      if (g > 0) l.drag = 1.0 / g;
    }
  }
  return l;
}

double Simulation::chooseTimeStep(const StepLimits& limits) {
  const ModelParameters& p = parameters_;
  const double stable = limits.stable();
  if (p.integrator == Integrator::CentralDifference && centralDifferenceStep_ > 0) return centralDifferenceStep_;
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
                              formatSeconds(stable) + " of the " + toString(p.integrator) + " integrator";
      if (p.stepLimitPolicy == StepLimitPolicy::Refuse) throw SimulationError(msg);
      if (warnings_.empty() || warnings_.back() != msg + "; clamped") warnings_.push_back(msg + "; clamped");
      dt = stable;
    }
  } else {
    dt = std::min(stable, limits.displacement);
    if (p.maxTimeStep) dt = std::min(dt, *p.maxTimeStep);
  }
  if (!std::isfinite(dt) || dt <= 0) throw SimulationError("no finite time step: nothing limits it (no fluid, no forces)");
  if (p.integrator == Integrator::CentralDifference) {
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
  if (parameters_.integrator == Integrator::CentralDifference && centralDifferenceStep_ > 0) return centralDifferenceStep_;
  const StepLimits l = currentLimits();
  if (parameters_.fixedTimeStep) return std::min(*parameters_.fixedTimeStep, l.stable());
  const double dt = std::min(l.stable(), l.displacement);
  return parameters_.maxTimeStep ? std::min(dt, *parameters_.maxTimeStep) : dt;
}

// ------------------------------------------------------------------------------------------------
// Integration
// ------------------------------------------------------------------------------------------------

void Simulation::integrate(double dt) {
  const ModelParameters& p = parameters_;
  const std::size_t n = fluid_.size();
  const bool drag = p.viscosityModel == ViscosityModel::Drag;
  FluidParticles& f = fluid_;
  switch (p.integrator) {
  case Integrator::CentralDifference: {
    // Eq. 8 with a_i = a_other - gamma v_i and v_i = (r+ - r-) / (2 dt), solved for r+ per particle
    // (the drag acts on a particle's own velocity only, so the system is diagonal):
    //   r+ = [2 r - (1 - gamma dt/2) r- + dt^2 a_other] / (1 + gamma dt/2)
#pragma omp parallel for schedule(static) if (n >= kParallelMinimum)
    for (std::size_t i = 0; i < n; ++i) {
      const double gdt2 = drag ? 0.5 * dt * p.dragRate(f.mass[i], f.density[i]) : 0.0;
      const double inv = 1.0 / (1.0 + gdt2), c = 1.0 - gdt2, dt2 = dt * dt;
      const double nx = (2 * f.x[i] - c * f.xp[i] + dt2 * f.ax[i]) * inv;
      const double ny = (2 * f.y[i] - c * f.yp[i] + dt2 * f.ay[i]) * inv;
      const double nz = (2 * f.z[i] - c * f.zp[i] + dt2 * f.az[i]) * inv;
      f.vx[i] = (nx - f.xp[i]) / (2 * dt);
      f.vy[i] = (ny - f.yp[i]) / (2 * dt);
      f.vz[i] = (nz - f.zp[i]) / (2 * dt);
      f.xp[i] = f.x[i]; f.yp[i] = f.y[i]; f.zp[i] = f.z[i];
      f.x[i] = nx; f.y[i] = ny; f.z[i] = nz;
    }
    break;
  }
  case Integrator::Explicit: {
    // Symplectic Euler: v += dt (a - gamma v); r += dt v.
#pragma omp parallel for schedule(static) if (n >= kParallelMinimum)
    for (std::size_t i = 0; i < n; ++i) {
      const double g = drag ? p.dragRate(f.mass[i], f.density[i]) : 0.0;
      f.vx[i] += dt * (f.ax[i] - g * f.vx[i]);
      f.vy[i] += dt * (f.ay[i] - g * f.vy[i]);
      f.vz[i] += dt * (f.az[i] - g * f.vz[i]);
      f.xp[i] = f.x[i]; f.yp[i] = f.y[i]; f.zp[i] = f.z[i];
      f.x[i] += dt * f.vx[i]; f.y[i] += dt * f.vy[i]; f.z[i] += dt * f.vz[i];
    }
    break;
  }
  case Integrator::Overdamped: {
    // Creeping flow: inertia negligible (gamma dt >> 1), so the drag balances the other forces.
#pragma omp parallel for schedule(static) if (n >= kParallelMinimum)
    for (std::size_t i = 0; i < n; ++i) {
      const double invG = 1.0 / p.dragRate(f.mass[i], f.density[i]);
      f.vx[i] = f.ax[i] * invG; f.vy[i] = f.ay[i] * invG; f.vz[i] = f.az[i] * invG;
      f.xp[i] = f.x[i]; f.yp[i] = f.y[i]; f.zp[i] = f.z[i];
      f.x[i] += dt * f.vx[i]; f.y[i] += dt * f.vy[i]; f.z[i] += dt * f.vz[i];
    }
    break;
  }
  }
}

void Simulation::applyBoundaries() {
  const std::size_t n = fluid_.size();
  FluidParticles& f = fluid_;
  std::vector<std::uint8_t> keep;
  std::size_t leaving = 0;
  double* pos[3] = {f.x.data(), f.y.data(), f.z.data()};
  double* prev[3] = {f.xp.data(), f.yp.data(), f.zp.data()};
  for (int a = 0; a < 3; ++a) {
    const double lo = domain_.lower[a], hi = domain_.upper[a], L = extent_[a];
    if (domain_.periodic[a]) {
      // Re-enter on the opposite side with the same velocity and density (the paper, after Jiang et al.)
      for (std::size_t i = 0; i < n; ++i) {
        if (pos[a][i] >= hi) { pos[a][i] -= L; prev[a][i] -= L; }
        else if (pos[a][i] < lo) { pos[a][i] += L; prev[a][i] += L; }
      }
    } else {
      for (std::size_t i = 0; i < n; ++i)
        if (pos[a][i] < lo || pos[a][i] >= hi) {
          if (keep.empty()) keep.assign(n, 1);
          if (keep[i]) { keep[i] = 0; ++leaving; }
        }
    }
  }
  if (leaving) {
    f.compact(keep);
    escaped_ += leaving;
    listsValid_ = false;
  }
}

std::string Simulation::describeParticle(std::size_t i) const {
  std::ostringstream s;
  s.precision(4);
  s << "fluid particle #" << fluid_.id[i] << " at (" << fluid_.x[i] * 1e3 << ", " << fluid_.y[i] * 1e3 << ", "
    << fluid_.z[i] * 1e3 << ") mm";
  return s.str();
}

void Simulation::checkHealth(double dt) const {
  const std::size_t n = fluid_.size();
  const double vmax = parameters_.runawaySpeedFactor * parameters_.soundSpeed;
  std::size_t firstBad = n;
#pragma omp parallel for schedule(static) reduction(min : firstBad) if (n >= kParallelMinimum)
  for (std::size_t i = 0; i < n; ++i) {
    const double v2 = fluid_.vx[i] * fluid_.vx[i] + fluid_.vy[i] * fluid_.vy[i] + fluid_.vz[i] * fluid_.vz[i];
    const bool finite = std::isfinite(fluid_.x[i]) && std::isfinite(fluid_.y[i]) && std::isfinite(fluid_.z[i]) &&
                        std::isfinite(v2) && std::isfinite(fluid_.density[i]);
    if (!finite || v2 > vmax * vmax) firstBad = std::min(firstBad, i);
  }
  if (firstBad == n) return;
  const std::size_t i = firstBad;
  std::ostringstream s;
  s.precision(4);
  s << "simulation unstable at step " << statistics_.steps + 1 << " (t = " << time_ << " s, dt = " << dt << " s): ";
  const double v = std::sqrt(fluid_.vx[i] * fluid_.vx[i] + fluid_.vy[i] * fluid_.vy[i] + fluid_.vz[i] * fluid_.vz[i]);
  if (!std::isfinite(v) || !std::isfinite(fluid_.x[i]) || !std::isfinite(fluid_.density[i]))
    s << describeParticle(i) << " has a non-finite position, velocity or density";
  else
    s << describeParticle(i) << " moves at " << v << " m/s, over " << parameters_.runawaySpeedFactor
      << " times the speed of sound (runaway)";
  const StepLimits l = currentLimits();
  s << "; " << toString(parameters_.integrator) << " stability limit " << l.stable()
    << " s: reduce the time step or check the scene";
  throw SimulationError(s.str());
}

double Simulation::step() {
  if (fluid_.size() == 0) throw SimulationError("no fluid particles to simulate");
  updateDensityAndPressure();
  updateAccelerations();
  const double dt = chooseTimeStep(currentLimits());
  integrate(dt);
  checkHealth(dt);
  applyBoundaries();
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
