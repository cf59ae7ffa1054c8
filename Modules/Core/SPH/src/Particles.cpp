#include "cementsph/sph/Particles.h"

namespace cementsph::sph {

namespace {
template <class T> void permuteField(std::vector<T>& v, const std::vector<std::uint32_t>& order, std::vector<T>& scratch) {
  scratch.resize(order.size());
  for (std::size_t k = 0; k < order.size(); ++k) scratch[k] = v[order[k]];
  v.swap(scratch);
}
template <class T> void compactField(std::vector<T>& v, const std::vector<std::uint8_t>& keep) {
  std::size_t w = 0;
  for (std::size_t i = 0; i < v.size(); ++i)
    if (keep[i]) v[w++] = v[i];
  v.resize(w);
}
} // namespace

std::size_t FluidParticles::add(const Eigen::Vector3d& p, const Eigen::Vector3d& v, double m, double rho,
                                double time, std::uint64_t identity) {
  x.push_back(p.x()); y.push_back(p.y()); z.push_back(p.z());
  xp.push_back(p.x()); yp.push_back(p.y()); zp.push_back(p.z());
  vx.push_back(v.x()); vy.push_back(v.y()); vz.push_back(v.z());
  ax.push_back(0); ay.push_back(0); az.push_back(0);
  density.push_back(rho);
  pressure.push_back(0.0);
  mass.push_back(m);
  birthTime.push_back(time);
  viscosity.push_back(0.0);
  dragRate.push_back(0.0);
  porosity.push_back(1.0);
  permeability.push_back(0.0);
  volumeFraction.push_back(1.0);
  front.push_back(0);
  id.push_back(identity);
  return x.size() - 1;
}

std::vector<std::vector<double>*> FluidParticles::doubleFields() {
  return {&x, &y, &z, &xp, &yp, &zp, &vx, &vy, &vz, &ax, &ay, &az, &density, &pressure, &mass, &birthTime,
          &viscosity, &dragRate, &porosity, &permeability, &volumeFraction};
}

void FluidParticles::permute(const std::vector<std::uint32_t>& order) {
  std::vector<double> s;
  for (auto* f : doubleFields()) permuteField(*f, order, s);
  std::vector<std::uint64_t> si;
  permuteField(id, order, si);
  std::vector<std::uint8_t> sf;
  permuteField(front, order, sf);
}

std::size_t FluidParticles::compact(const std::vector<std::uint8_t>& keep) {
  const std::size_t before = size();
  for (auto* f : doubleFields()) compactField(*f, keep);
  compactField(id, keep);
  compactField(front, keep);
  return before - size();
}

void FluidParticles::reserve(std::size_t n) {
  for (auto* f : doubleFields()) f->reserve(n);
  id.reserve(n);
  front.reserve(n);
}

} // namespace cementsph::sph
