// The one place the neighbour lists are walked. Every pair term of the engine (Eq. 2 density, Eq. 5 and
// Eq. 7 forces, the incompressible model's volume fractions, Laplacian and gradient) is a visitor given to
// PairIteration::visit, so lists, relisting and periodic images are handled once.
//
// A visitor V provides
//   using Acc = ...;                                           a per-particle accumulator
//   Acc begin(std::size_t i);                                  start particle i
//   void fluid(std::size_t i, std::size_t j, const Pair& p, Acc& a);  a fluid pair within the support
//   void mirror(std::size_t j, std::size_t i, const Pair& p);  the same pair's share for j (relisted i only;
//                                                               called serially; p is seen from i: r_i - r_j)
//   void fixed(std::size_t i, std::uint32_t s, const Pair& p, Acc& a); a fixed particle within the support
//   void finish(std::size_t i, Acc& a);                        end particle i (writes its results)
// Listed particles run in parallel (each pair is visited from both partners); the few relisted ones
// (Simulation.h) run afterwards in ascending order, and each of their pairs is visited once, from the
// relisted partner, with mirror() giving the other partner its share. A visitor's fluid() and mirror() must
// therefore be the two halves of one symmetric or antisymmetric pair term.
// A visitor may declare `using RelistedFixedFirst = std::true_type;` to see a relisted particle's
// fixed pairs before its fluid pairs (Eq. 2's density keeps the summation order it had before the core was
// restructured, so the paper preset's runs stay the same to the last bit; VALIDATION.md).
#pragma once

#include "cementsph/sph/NeighbourSearch.h"
#include "cementsph/sph/Particles.h"

#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>
#include <vector>

namespace cementsph::sph {

// A pair's separation r_i - r_j (minimum image on periodic axes) and its square [m, m^2].
struct Pair {
  double dx, dy, dz, r2;
  double r() const { return std::sqrt(r2); }
};

template <class V, class = void> struct RelistedFixedFirst : std::false_type {};
template <class V>
struct RelistedFixedFirst<V, std::void_t<typename V::RelistedFixedFirst>> : V::RelistedFixedFirst {};

class PairIteration {
public:
  struct Lists {
    const NeighbourList* fluid = nullptr;     // per listed particle
    const NeighbourList* fixed = nullptr;     // per listed particle (empty when the fixed sums are tabulated)
    const NeighbourList* relistedFluid = nullptr;
    const NeighbourList* relistedFixed = nullptr;
    const std::vector<std::uint32_t>* relistedIndex = nullptr;
    const std::uint8_t* relisted = nullptr;   // per fluid particle
    std::size_t listed = 0;                   // particles [0, listed) have lists of their own
  };

  PairIteration(const FluidParticles& fluid, const FixedParticles& fixed, const Lists& lists, double support,
                const double extent[3], const double halfExtent[3], bool periodic)
      : fluid_(fluid), fixed_(fixed), lists_(lists), support2_(support * support), periodic_(periodic) {
    for (int a = 0; a < 3; ++a) { extent_[a] = extent[a]; half_[a] = halfExtent[a]; }
  }

  double support2() const { return support2_; }

  template <class Visitor> void visit(Visitor& v) const {
    if (periodic_) run<true>(v);
    else run<false>(v);
  }

  // The minimum-image separation on periodic axes (half = +inf on open ones, so they pass).
  void wrap(double& dx, double& dy, double& dz) const {
    if (dx > half_[0]) dx -= extent_[0]; else if (dx < -half_[0]) dx += extent_[0];
    if (dy > half_[1]) dy -= extent_[1]; else if (dy < -half_[1]) dy += extent_[1];
    if (dz > half_[2]) dz -= extent_[2]; else if (dz < -half_[2]) dz += extent_[2];
  }

private:
  template <bool Periodic> bool fluidPair(std::size_t i, std::size_t j, Pair& p) const {
    p.dx = fluid_.x[i] - fluid_.x[j]; p.dy = fluid_.y[i] - fluid_.y[j]; p.dz = fluid_.z[i] - fluid_.z[j];
    if constexpr (Periodic) wrap(p.dx, p.dy, p.dz);
    p.r2 = p.dx * p.dx + p.dy * p.dy + p.dz * p.dz;
    return p.r2 < support2_;
  }
  template <bool Periodic> bool fixedPair(std::size_t i, std::uint32_t s, Pair& p) const {
    p.dx = fluid_.x[i] - fixed_.x[s]; p.dy = fluid_.y[i] - fixed_.y[s]; p.dz = fluid_.z[i] - fixed_.z[s];
    if constexpr (Periodic) wrap(p.dx, p.dy, p.dz);
    p.r2 = p.dx * p.dx + p.dy * p.dy + p.dz * p.dz;
    return p.r2 < support2_;
  }

  template <bool Periodic, class Visitor> void run(Visitor& v) const {
    const NeighbourList& fl = *lists_.fluid;
    const NeighbourList& sl = *lists_.fixed;
    const bool haveFixed = !sl.index.empty();
    const std::uint8_t* relisted = lists_.relisted;
    const std::size_t listed = lists_.listed;
#pragma omp parallel for schedule(static)
    for (std::size_t i = 0; i < listed; ++i) {
      if (relisted[i]) continue; // visited from its own lists below
      auto acc = v.begin(i);
      Pair p;
      for (std::uint64_t k = fl.offset[i]; k < fl.offset[i + 1]; ++k) {
        const std::uint32_t j = fl.index[k];
        if (relisted[j]) continue; // the pair is in j's lists
        if (fluidPair<Periodic>(i, j, p)) v.fluid(i, j, p, acc);
      }
      if (haveFixed)
        for (std::uint64_t k = sl.offset[i]; k < sl.offset[i + 1]; ++k) {
          const std::uint32_t s = sl.index[k];
          if (fixedPair<Periodic>(i, s, p)) v.fixed(i, s, p, acc);
        }
      v.finish(i, acc);
    }
    const std::vector<std::uint32_t>& rel = *lists_.relistedIndex;
    const NeighbourList& rf = *lists_.relistedFluid;
    const NeighbourList& rs = *lists_.relistedFixed;
    for (std::size_t q = 0; q < rel.size(); ++q) {
      const std::size_t i = rel[q];
      auto acc = v.begin(i);
      Pair p;
      const auto fixedPairs = [&] {
        for (std::uint64_t k = rs.offset[q]; k < rs.offset[q + 1]; ++k) {
          const std::uint32_t s = rs.index[k];
          if (fixedPair<Periodic>(i, s, p)) v.fixed(i, s, p, acc);
        }
      };
      if constexpr (RelistedFixedFirst<Visitor>::value) fixedPairs();
      for (std::uint64_t k = rf.offset[q]; k < rf.offset[q + 1]; ++k) {
        const std::uint32_t j = rf.index[k];
        if (fluidPair<Periodic>(i, j, p)) {
          v.fluid(i, j, p, acc);
          v.mirror(j, i, p);
        }
      }
      if constexpr (!RelistedFixedFirst<Visitor>::value) fixedPairs();
      v.finish(i, acc);
    }
  }

  const FluidParticles& fluid_;
  const FixedParticles& fixed_;
  Lists lists_;
  double support2_;
  double extent_[3], half_[3];
  bool periodic_;
};

} // namespace cementsph::sph
