// Particle storage, structure of arrays (one contiguous array per field) so the pair loops stream.
// Positions are double: a step moves a particle ~1e-7 m at coordinates ~1e-2 m, and the central
// difference (Eq. 8) subtracts nearly equal positions (model-notes 3).
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <vector>

namespace cementsph::sph {

struct FluidParticles {
  std::vector<double> x, y, z;    // position [m]
  std::vector<double> xp, yp, zp; // previous position [m] (central difference, Eq. 8)
  std::vector<double> vx, vy, vz; // velocity [m/s]
  std::vector<double> ax, ay, az; // acceleration from pressure, body force and explicit viscosity [m/s^2]
  std::vector<double> density;    // [kg/m^3], Eq. 2
  std::vector<double> pressure;   // [Pa], Eq. 6
  std::vector<double> mass;       // [kg]
  std::vector<double> birthTime;  // [s]
  // Per-particle model fields, so a model may vary in space and time:
  std::vector<double> viscosity;  // mu [Pa s] (ViscosityLaw)
  std::vector<double> dragRate;   // gamma [1/s], a = -gamma v (Resistance: Eq. 9 or k/mu)
  std::vector<double> porosity;   // phi of the medium the particle is in (1 where the pores are resolved)
  std::vector<double> permeability; // k [m^2] of the medium (continuum resistance; 0 where unused)
  std::vector<double> volumeFraction; // theta: kernel sum of cement bulk and solid volume (incompressible)
  std::vector<std::uint8_t> front;    // 1 at the cement front (incompressible: p = 0 there)
  std::vector<std::uint64_t> id;  // stable identity (storage is reordered by cell)

  std::size_t size() const { return x.size(); }
  Eigen::Vector3d position(std::size_t i) const { return {x[i], y[i], z[i]}; }
  Eigen::Vector3d velocity(std::size_t i) const { return {vx[i], vy[i], vz[i]}; }

  // Appends a particle at rest-state density; returns its index.
  std::size_t add(const Eigen::Vector3d& position, const Eigen::Vector3d& velocity, double mass,
                  double density, double time, std::uint64_t id);
  // Reorders every field by `order` (new index k takes old index order[k]).
  void permute(const std::vector<std::uint32_t>& order);
  // Keeps particles with keep[i] != 0, preserving order. Returns how many were removed.
  std::size_t compact(const std::vector<std::uint8_t>& keep);
  void reserve(std::size_t n);
  // Every per-particle double field, for permute/compact/reserve (one list, so a new field is not forgotten).
  std::vector<std::vector<double>*> doubleFields();
};

// The porous solid. Static: binned once. Density and pressure are one value for the whole set
// (the paper keeps them fixed), so a fixed particle costs 3 doubles + 2 floats = 32 bytes.
struct FixedParticles {
  std::vector<double> x, y, z; // [m]
  std::vector<float> mass;     // [kg]
  std::vector<float> volume;   // [m^3] the solid volume it stands for (the incompressible model's no-flux solid)
  double density = 1180.0;     // [kg/m^3], kept fixed
  double pressure = 0.0;       // [Pa], kept fixed: EOS at that density

  std::size_t size() const { return x.size(); }
  // v: the solid volume [m^3] (0: m / density).
  void add(const Eigen::Vector3d& position, double m, double v = 0.0) {
    if (v <= 0) v = m / density;
    x.push_back(position.x());
    y.push_back(position.y());
    z.push_back(position.z());
    mass.push_back(static_cast<float>(m));
    volume.push_back(static_cast<float>(v));
  }
  std::size_t bytesUsed() const {
    return x.capacity() * sizeof(double) * 3 + (mass.capacity() + volume.capacity()) * sizeof(float);
  }
};

} // namespace cementsph::sph
