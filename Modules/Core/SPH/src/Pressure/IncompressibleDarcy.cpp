#include "cementsph/sph/Pressure/IncompressibleDarcy.h"

#include "cementsph/sph/Simulation.h"

#include <Eigen/Dense>
#include <Eigen/IterativeLinearSolvers>
#include <Eigen/Sparse>
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <limits>
#include <cmath>
#include <sstream>

namespace cementsph::sph {

namespace {
// G(r) = -2 r W'(r) / (r^2 + eta^2) of Brookshaw's Laplacian, from the cubic spline's (1/r) dW/dr.
inline double laplacianWeight(const CubicSplineKernel& k, double r2, double eta2) {
  return -2.0 * k.derivativeOverR(std::sqrt(r2)) * r2 / (r2 + eta2);
}
} // namespace

namespace {
// a^3 sum over the simple cubic lattice points n a within the support (n != 0) of G(|n a|) times weight(n a).
template <class Weight> double latticeSum(double h, double a, Weight weight) {
  const CubicSplineKernel k(h);
  const double eta2 = 0.01 * h * h, support = k.support();
  const int m = static_cast<int>(std::ceil(support / a));
  double sum = 0.0;
  for (int i = -m; i <= m; ++i)
    for (int j = -m; j <= m; ++j)
      for (int l = -m; l <= m; ++l) {
        const double r2 = a * a * double(i * i + j * j + l * l);
        if (r2 > 0 && r2 < support * support) sum += laplacianWeight(k, r2, eta2) * weight(i * a);
      }
  return sum * a * a * a;
}
} // namespace

double IncompressibleDarcy::laplacianLatticeFactor(double h, double a) {
  // (L x^2) / 2 at a lattice point: 1 for an exact Laplacian (1.013 at a = h, 0.816 at a = 1.26 h).
  return 0.5 * latticeSum(h, a, [](double x) { return x * x; });
}

double IncompressibleDarcy::fullKernelLaplacianSum(double h, double a) {
  // The full kernel of a particle in bulk cement at rest.
  return latticeSum(h, a, [](double) { return 1.0; });
}

void IncompressibleDarcy::density(Simulation& sim) {
  FluidParticles& f = sim.fluid();
  const FixedParticles& fixed = sim.fixed();
  const ModelParameters& p = sim.parameters();
  const std::size_t n = f.size();
  const double rho0 = p.restDensity, h = p.smoothingLength, eta2 = 0.01 * h * h;
  const CubicSplineKernel& W = sim.densityKernel();
  bulk_.resize(n);
  for (std::size_t i = 0; i < n; ++i) bulk_[i] = f.mass[i] / (rho0 * f.porosity[i]);
  solid_.assign(n, 0.0);
  presentSum_.resize(n);
  const bool tabulated = sim.tabulatedFixedSums();
  if (tabulated) sim.prepareFixedField();
  // The full-kernel sum Gamma for this h and the particles' bulk spacing (the first particle's: the
  // emitter makes them all alike; a continuum's porosity changes Omega, not the rule).
  const double spacing = std::cbrt(bulk_.empty() ? h * h * h : bulk_[0]);
  if (gammaH_ != h || gammaSpacing_ != spacing) {
    // Both sums are divided by the lattice factor, so that L is exact for a quadratic pressure on the
    // lattice the cement settles to.
    latticeFactor_ = laplacianLatticeFactor(h, spacing);
    gamma_ = fullKernelLaplacianSum(h, spacing) / latticeFactor_;
    gammaH_ = h;
    gammaSpacing_ = spacing;
  }
  struct Volumes {
    // (fields in order of initialisation)
    const CubicSplineKernel& W;
    const double* bulk; const float* solidVolume;
    double* theta; double* solid; double* present; double eta2, w0, gamma;
    const FixedParticleField* field; bool tabulated; const FluidParticles& f;
    double* gradTheta; // 3 per particle: grad theta (cubic spline; the table's solid share: spiky)
    struct Acc { double theta, solid, present, g[3]; };
    Acc begin(std::size_t i) const { return {bulk[i] * w0, 0.0, 0.0, {0, 0, 0}}; }
    void fluid(std::size_t, std::size_t j, const Pair& p, Acc& a) const {
      const double r = p.r(), w = bulk[j] * W.derivativeOverR(r);
      a.theta += bulk[j] * W.value(r);
      a.present += bulk[j] * laplacianWeight(W, p.r2, eta2);
      a.g[0] += w * p.dx; a.g[1] += w * p.dy; a.g[2] += w * p.dz;
    }
    void mirror(std::size_t j, std::size_t i, const Pair& p) const {
      const double r = p.r(), w = bulk[i] * W.derivativeOverR(r);
      theta[j] += bulk[i] * W.value(r);
      present[j] += bulk[i] * laplacianWeight(W, p.r2, eta2);
      gradTheta[3 * j] -= w * p.dx; gradTheta[3 * j + 1] -= w * p.dy; gradTheta[3 * j + 2] -= w * p.dz;
    }
    void fixed(std::size_t, std::uint32_t s, const Pair& p, Acc& a) const {
      const double v = static_cast<double>(solidVolume[s]), r = p.r(), w = v * W.derivativeOverR(r);
      a.solid += v * W.value(r);
      a.present += v * laplacianWeight(W, p.r2, eta2);
      a.g[0] += w * p.dx; a.g[1] += w * p.dy; a.g[2] += w * p.dz;
    }
    void finish(std::size_t i, Acc& a) const {
      if (tabulated) { // the table holds sum_s V_s W; the solid's share of the Laplacian sum is taken as
                       // its volume fraction of the full sum (the table has no G sums)
        double d, g[3];
        field->sample(f.x[i], f.y[i], f.z[i], d, g);
        a.solid = d;
        a.present += gamma * d;
        a.g[0] += g[0]; a.g[1] += g[1]; a.g[2] += g[2];
      }
      std::copy(a.g, a.g + 3, gradTheta + 3 * i);
      theta[i] = a.theta + a.solid;
      solid[i] = a.solid;
      present[i] = a.present;
    }
  };
  std::vector<double> gradTheta(3 * n, 0.0);
  Volumes v{W, bulk_.data(), fixed.volume.data(), f.volumeFraction.data(), solid_.data(), presentSum_.data(), eta2,
            W.value(0.0), gamma_, &sim.fixedField(), tabulated, f, gradTheta.data()};
  sim.pairs().visit(v);
  std::size_t fronts = 0;
  for (std::size_t i = 0; i < n; ++i) {
    // The front: a kernel not full (theta low) or one-sided (|grad theta| h high: 0.51 on a lattice's
    // free surface, 0 inside; it also finds the front of a blob compressed to theta >= 1).
    const double gn = std::sqrt(gradTheta[3 * i] * gradTheta[3 * i] + gradTheta[3 * i + 1] * gradTheta[3 * i + 1] +
                                gradTheta[3 * i + 2] * gradTheta[3 * i + 2]) * h;
    const bool front = f.volumeFraction[i] < settings_.frontVolumeFraction || gn > settings_.frontGradient;
    f.front[i] = front ? 1 : 0;
    fronts += front ? 1 : 0;
    // The cement's own density: its mass per unit of the volume the solid leaves free; the rest density
    // at the front, where the kernel is cut by the marrow.
    const double free = std::max(1.0 - solid_[i], 0.05);
    f.density[i] = front ? rho0 : rho0 * (f.volumeFraction[i] - solid_[i]) / free;
  }
  stats_.lastFrontParticles = fronts;
}

void IncompressibleDarcy::pressure(Simulation& sim) {
  const auto t0 = std::chrono::steady_clock::now();
  FluidParticles& f = sim.fluid();
  const ModelParameters& p = sim.parameters();
  const std::size_t n = f.size();
  const double rho0 = p.restDensity, h = p.smoothingLength, eta2 = 0.01 * h * h;
  const CubicSplineKernel& W = sim.densityKernel();
  // Mobility lambda = 1 / (rho0 gamma) [m^2 / (Pa s)]: v = -lambda grad p.
  std::vector<double> lambda(n);
  for (std::size_t i = 0; i < n; ++i) {
    if (!(f.dragRate[i] > 0)) throw SimulationError("incompressible model: " + sim.describeParticleForModels(i) +
                                                    " has no resistance (drag rate 0): the Darcy velocity is undefined");
    lambda[i] = 1.0 / (rho0 * f.dragRate[i]);
  }
  // The drift correction removes volumeCorrection of the excess per relaxation time tau. tau is not the
  // step: a step shortened by a fast particle would make the correction, and so the speeds, larger and the
  // next step shorter still (measured: a runaway within 30 steps). It is the longest step the run allows
  // (an injection: one particle's emission interval), or the last step if there is no such bound.
  double tau = p.maxTimeStep ? *p.maxTimeStep : lastStep_;
  if (settings_.relaxationTime > 0) tau = settings_.relaxationTime;
  if (!(tau > 0)) tau = std::numeric_limits<double>::infinity();

  // --- assemble A p = b (symmetric: each row multiplied by Omega_i) ------------------------------------
  using Triplet = Eigen::Triplet<double, int>;
  const int threads = omp_get_max_threads();
  std::vector<std::vector<Triplet>> perThread(static_cast<std::size_t>(threads));
  std::vector<Triplet> mirrored;
  std::vector<double> diagonal(n, 0.0);
  struct Laplacian {
    const CubicSplineKernel& W;
    const double* bulk; const double* lambda; double eta2, invFactor;
    std::vector<std::vector<Triplet>>& perThread; std::vector<Triplet>& mirrored; double* diagonal;
    double coefficient(std::size_t i, std::size_t j, const Pair& p) const {
      const double lij = 2.0 * lambda[i] * lambda[j] / (lambda[i] + lambda[j]); // harmonic mean
      return bulk[i] * bulk[j] * lij * laplacianWeight(W, p.r2, eta2) * invFactor;
    }
    double begin(std::size_t) const { return 0.0; }
    void fluid(std::size_t i, std::size_t j, const Pair& p, double& d) const {
      const double c = coefficient(i, j, p);
      d += c;
      perThread[static_cast<std::size_t>(omp_get_thread_num())].emplace_back(int(i), int(j), -c);
    }
    void mirror(std::size_t j, std::size_t i, const Pair& p) const {
      const double c = coefficient(i, j, p);
      diagonal[j] += c;
      mirrored.emplace_back(int(j), int(i), -c);
    }
    void fixed(std::size_t, std::uint32_t, const Pair&, double&) const {} // no flux into solid
    void finish(std::size_t i, double& d) const { diagonal[i] = d; }
  } lap{W, bulk_.data(), lambda.data(), eta2, 1.0 / latticeFactor_, perThread, mirrored, diagonal.data()};
  sim.pairs().visit(lap);

  // Right-hand side: the source, the drift correction, the bulk-modulus term; the front's coupling to the
  // marrow on the diagonal.
  Eigen::VectorXd b = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(n));
  const VolumeSource& src = sim.volumeSource();
  if (src.rate > 0 && n > 0) {
    std::vector<std::size_t> fed;
    double fedBulk = 0.0;
    for (std::size_t i = 0; i < n; ++i)
      if ((f.position(i) - src.centre).norm() <= src.radius) {
        fed.push_back(i);
        fedBulk += bulk_[i];
      }
    if (fed.empty()) { // nothing within the outlet yet: the particle nearest to it takes the flow
      std::size_t best = 0;
      for (std::size_t i = 1; i < n; ++i)
        if ((f.position(i) - src.centre).squaredNorm() < (f.position(best) - src.centre).squaredNorm()) best = i;
      fed.push_back(best);
      fedBulk = bulk_[best];
    }
    for (std::size_t i : fed) b[Eigen::Index(i)] += src.rate / f.porosity[i] * bulk_[i] / fedBulk;
  }
  const double shift = settings_.regularisation;
  std::size_t nnz = n;
  for (const auto& t : perThread) nnz += t.size();
  nnz += mirrored.size();
  std::vector<Triplet> all;
  all.reserve(nnz);
  for (auto& t : perThread) all.insert(all.end(), t.begin(), t.end());
  all.insert(all.end(), mirrored.begin(), mirrored.end());
  Eigen::VectorXd x0(static_cast<Eigen::Index>(n));
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Index r = Eigen::Index(i);
    double d = diagonal[i];
    if (f.front[i]) // marrow at p = 0 where the kernel misses neighbours (a compressed kernel is scaled to theta = 1)
      d += bulk_[i] * lambda[i] *
           std::max(0.0, gamma_ - presentSum_[i] / (latticeFactor_ * std::max(1.0, f.volumeFraction[i])));
    if (std::isfinite(tau)) {
      // Inside the cement both signs are corrected (a hole closes as an excess spreads); at the front only
      // an excess (a front particle's kernel is cut by the marrow, its theta < 1 is no hole).
      const double excess = f.front[i] ? std::max(0.0, f.volumeFraction[i] - 1.0) : f.volumeFraction[i] - 1.0;
      b[r] += bulk_[i] * settings_.volumeCorrection * excess / tau;
    }
    if (!(d > 0)) d = bulk_[i] * lambda[i] * gamma_; // an isolated particle: couple it to the marrow
    // Regularisation: a relative diagonal shift that pulls towards the last pressure. It keeps the system
    // positive definite where cement has no front (a closed cavity) and, being relative, keeps the solve
    // exactly proportional to the viscosity (Darcy: p ~ mu at a fixed flow).
    b[r] += shift * d * f.pressure[i];
    d *= 1.0 + shift;
    all.emplace_back(int(i), int(i), d);
    x0[r] = f.pressure[i];
  }
  Eigen::SparseMatrix<double, Eigen::RowMajor, int> A(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
  A.setFromTriplets(all.begin(), all.end());

  Eigen::ConjugateGradient<Eigen::SparseMatrix<double, Eigen::RowMajor, int>, Eigen::Lower | Eigen::Upper> cg;
  cg.setTolerance(settings_.solverTolerance);
  cg.setMaxIterations(settings_.solverMaxIterations);
  cg.compute(A);
  Eigen::VectorXd x = cg.solveWithGuess(b, x0);
  if (!x.allFinite()) {
    std::ostringstream s;
    s << "incompressible model: the pressure solve at step " << sim.stepCount() + 1 << " (t = " << sim.time()
      << " s, " << n << " particles) gave non-finite pressures: check the scene's viscosity and permeability";
    throw SimulationError(s.str());
  }
  ++stats_.solves;
  stats_.lastIterations = int(cg.iterations());
  stats_.iterations += std::uint64_t(cg.iterations());
  stats_.lastResidual = cg.error();
  stats_.worstResidual = std::max(stats_.worstResidual, cg.error());
  if (cg.info() != Eigen::Success) ++stats_.unconverged;
  stats_.lastUnknowns = n;
  for (std::size_t i = 0; i < n; ++i) f.pressure[i] = x[Eigen::Index(i)];

  // --- velocity from the renormalised gradient ---------------------------------------------------------
  std::vector<double> moment(6 * n, 0.0), grad(3 * n, 0.0), push(3 * n, 0.0);
  const SpikyKernel& S = sim.pressureKernel();
  struct Gradient {
    const CubicSplineKernel& W; const SpikyKernel& S;
    const double* bulk; const double* P; const float* solidVolume; double* M; double* G; double* U; double h;
    // m: the kernel's moment matrix; g: the difference-form gradient sum; u: sum Omega_j grad W_spiky (the
    // symmetric form's extra term, times 2 p_i: it keeps particles apart, and off the solid)
    struct Acc { double m[6]; double g[3]; double u[3]; };
    Acc begin(std::size_t) const { return Acc{{0, 0, 0, 0, 0, 0}, {0, 0, 0}, {0, 0, 0}}; }
    static void add(double* m, double* g, double w, double dp, const Pair& p) {
      // m += -Omega W'/r r r^T; g += Omega (p_j - p_i) W'/r r (w = Omega W'/r)
      m[0] -= w * p.dx * p.dx; m[1] -= w * p.dx * p.dy; m[2] -= w * p.dx * p.dz;
      m[3] -= w * p.dy * p.dy; m[4] -= w * p.dy * p.dz; m[5] -= w * p.dz * p.dz;
      g[0] += w * dp * p.dx; g[1] += w * dp * p.dy; g[2] += w * dp * p.dz;
    }
    // grad_i W_spiky(r_ij) = W' r_ij / r; a coincident pair is split along x by index (antisymmetric)
    void spiky(std::size_t i, std::size_t j, const Pair& p, double vol, double* u, double sign) const {
      const double r = p.r();
      double ux = (i < j) ? 1.0 : -1.0, uy = 0.0, uz = 0.0;
      if (r > 1e-12 * h) { ux = p.dx / r; uy = p.dy / r; uz = p.dz / r; }
      const double w = sign * vol * S.derivative(r);
      u[0] += w * ux; u[1] += w * uy; u[2] += w * uz;
    }
    void fluid(std::size_t i, std::size_t j, const Pair& p, Acc& a) const {
      add(a.m, a.g, bulk[j] * W.derivativeOverR(p.r()), P[j] - P[i], p);
      spiky(i, j, p, bulk[j], a.u, 1.0);
    }
    void mirror(std::size_t j, std::size_t i, const Pair& p) const {
      // seen from j the vector is -r_ij and the difference p_i - p_j: the g term keeps its sign
      add(M + 6 * j, G + 3 * j, bulk[i] * W.derivativeOverR(p.r()), -(P[i] - P[j]), p);
      spiky(i, j, p, bulk[i], U + 3 * j, -1.0);
    }
    void fixed(std::size_t i, std::uint32_t s, const Pair& p, Acc& a) const {
      spiky(i, std::size_t(-1), p, static_cast<double>(solidVolume[s]), a.u, 1.0);
    }
    void finish(std::size_t i, Acc& a) const {
      std::copy(a.m, a.m + 6, M + 6 * i);
      std::copy(a.g, a.g + 3, G + 3 * i);
      std::copy(a.u, a.u + 3, U + 3 * i);
    }
  } gr{W, S, bulk_.data(), f.pressure.data(), sim.fixed().volume.data(), moment.data(), grad.data(), push.data(), h};
  sim.pairs().visit(gr);
  if (sim.tabulatedFixedSums()) // the table's gradient is sum_s V_s grad W_spiky (weighed by volume)
    for (std::size_t i = 0; i < n; ++i) {
      double d, g[3];
      sim.fixedField().sample(f.x[i], f.y[i], f.z[i], d, g);
      push[3 * i] += g[0]; push[3 * i + 1] += g[1]; push[3 * i + 2] += g[2];
    }
  const Eigen::Vector3d body = p.bodyForce;
#pragma omp parallel for schedule(static) if (n >= kParallelMinimum)
  for (std::size_t i = 0; i < n; ++i) {
    const double* m = &moment[6 * i];
    Eigen::Matrix3d Mi;
    Mi << m[0], m[1], m[2], m[1], m[3], m[4], m[2], m[4], m[5];
    const Eigen::Vector3d g(grad[3 * i], grad[3 * i + 1], grad[3 * i + 2]);
    const double tr = Mi.trace();
    Eigen::Vector3d gradP = Eigen::Vector3d::Zero();
    if (tr > 0) {
      // Renormalise where the moment matrix is well conditioned; else (a particle with neighbours on a
      // line or plane) scale isotropically.
      const double det = Mi.determinant(), t3 = tr / 3.0;
      gradP = det > 1e-3 * t3 * t3 * t3 ? Eigen::Vector3d(Mi.ldlt().solve(g)) : Eigen::Vector3d(g / t3);
    }
    // a = gamma v with v = -lambda (grad p + 2 p_i sum Omega_j grad W_spiky) + body / gamma (the
    // overdamped integrator divides by gamma). The second term is what the symmetric Eq. 5 adds to the
    // difference form: zero in a full kernel, it pushes particles apart and off the solid.
    const Eigen::Vector3d u(push[3 * i], push[3 * i + 1], push[3 * i + 2]);
    const Eigen::Vector3d a = -(gradP + 2.0 * f.pressure[i] * u) / rho0 + body;
    f.ax[i] = a.x(); f.ay[i] = a.y(); f.az[i] = a.z();
  }
  stats_.solveSeconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

} // namespace cementsph::sph
