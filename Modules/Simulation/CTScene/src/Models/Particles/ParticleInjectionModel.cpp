// The SPH particles as an injection engine (InjectionModel.h), registered as "equation-of-state" (the paper's
// weakly compressible model, Basafa et al. 2013 Eqs. 2-9) and "incompressible" (the particles' Darcy pressure
// solve, Pressure/IncompressibleDarcy.h).
//
// Assembly (as Modules/Core/SPH/test/InjectionScene.h, with the CT's porous solid): the porous solid of the ROI
// (PorousSolid.h) as fixed particles of mass rho0 V_voxel; the cannula emitter (volume-exact, optional wall of
// length cannula_length_mm, clipped to the ROI); the viscosity schedule applied each step. The outlet pressure:
// with the equation of state the paper's six-point ring (TipPressureProbe, model pressure); incompressible, the
// mean pressure of the cement the outlet's source feeds (gauge Pa). The simulation box is the ROI: particles
// leaving it are removed and counted.
#include "cementsph/scene/InjectionModel.h"
#include "../PointArrays.h"
#include "cementsph/scene/InjectionRunner.h"

#include "cementsph/sph/CannulaEmitter.h"
#include "cementsph/sph/HagenPoiseuille.h"
#include "cementsph/sph/ParticleVoxeliser.h"
#include "cementsph/sph/Pressure/IncompressibleDarcy.h"
#include "cementsph/sph/Simulation.h"
#include "cementsph/sph/TipPressureProbe.h"

#include <vtkCellArray.h>
#include <vtkDoubleArray.h>
#include <vtkPointData.h>
#include <vtkPoints.h>

#include <memory>
#include <optional>
#include <stdexcept>

namespace cementsph::scene {

vtkSmartPointer<vtkPolyData> particlesToPolyData(const sph::FluidParticles& f, double time) {
  const vtkIdType n = vtkIdType(f.size());
  auto points = vtkSmartPointer<vtkPoints>::New();
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(n);
  auto make = [n](const char* name, int components) { return detail::pointArray(name, components, n); };
  auto velocity = make("velocity_m_per_s", 3), density = make("density_kg_per_m3", 1),
       pressure = make("pressure_pa", 1), age = make("age_s", 1), viscosity = make("viscosity_pa_s", 1),
       volumeFraction = make("volume_fraction", 1), front = make("front", 1);
  auto verts = vtkSmartPointer<vtkCellArray>::New();
  for (vtkIdType i = 0; i < n; ++i) {
    const std::size_t k = std::size_t(i);
    points->SetPoint(i, f.x[k] * 1e3, f.y[k] * 1e3, f.z[k] * 1e3);
    velocity->SetTuple3(i, f.vx[k], f.vy[k], f.vz[k]);
    density->SetValue(i, f.density[k]);
    pressure->SetValue(i, f.pressure[k]);
    age->SetValue(i, time - f.birthTime[k]);
    viscosity->SetValue(i, f.viscosity[k]);
    volumeFraction->SetValue(i, f.volumeFraction[k]);
    front->SetValue(i, f.front[k]);
    verts->InsertNextCell(1, &i);
  }
  auto poly = vtkSmartPointer<vtkPolyData>::New();
  poly->SetPoints(points);
  poly->SetVerts(verts);
  for (auto* a : {velocity.Get(), density.Get(), pressure.Get(), age.Get(), viscosity.Get(), volumeFraction.Get(),
                  front.Get()})
    poly->GetPointData()->AddArray(a);
  return poly;
}

namespace {

class ParticleInjectionModel final : public InjectionModel {
public:
  void start(const InjectionSetup& in) override {
    const SceneConfig& scene = *in.scene;
    const std::string& name = in.choice->pressureModel;
    if (in.continuum)
      throw std::invalid_argument("scene: bone_model \"continuum\" needs pressure_model \"voxel-darcy\" (got \"" + name +
                                  "\")");
    if (scene.hasSecondTip())
      throw std::invalid_argument("scene: second_tip_withdrawal_mm needs pressure_model \"voxel-darcy\" (the particle "
                                  "models have one outlet; got \"" + name + "\")");
    if (scene.viscosityLaw != "newtonian" || scene.curing().kind() != "none")
      throw std::invalid_argument("scene: viscosity_law \"" + scene.viscosityLaw +
                                  "\" and curing (curing_table, curing_model, cement) need pressure_model "
                                  "\"voxel-darcy\" (the particle models are Newtonian; got \"" + name + "\")");
    scene_ = &scene;
    solid_ = in.solid;
    m_ = in.model;
    incompressible_ = m_.pressureModel == "incompressible";
    tip_ = *scene.tipMm * 1e-3;
    const double d = scene.spacingM();

    spec_.tip = tip_;
    spec_.direction = scene.direction;
    spec_.innerDiameter = scene.cannulaInnerDiameterMm * 1e-3;
    spec_.flowRate = scene.flowRateM3PerS();
    spec_.totalVolume = scene.volumeM3();
    spec_.spacing = d;
    spec_.restDensity = m_.restDensity;
    spec_.buildWall = scene.cannulaWall;
    spec_.wallLength = scene.cannulaLengthMm * 1e-3;
    emitter_ = std::make_unique<sph::CannulaEmitter>(spec_);
    viscosity_ = scene.viscositySchedule();
    m_.viscosity = viscosity_->at(0.0);
    m_.maxTimeStep = emitter_->maxTimeStep();

    sph::Domain domain;
    domain.lower = solid_->lowerM;
    domain.upper = solid_->upperM;
    sim_ = std::make_unique<sph::Simulation>(m_, domain);
    sim_->reserveFluid(emitter_->totalParticles());
    for (const Eigen::Vector3d& p : solid_->positions)
      sim_->addFixedParticle(p, solid_->particleMass, solid_->grid.voxelVolume());
    wallParticles_ = emitter_->addWall(*sim_);
    probe_ = std::make_unique<sph::TipPressureProbe>(
        sph::TipPressureProbe::ringAroundTip(tip_, spec_.direction, 0.5 * spec_.innerDiameter, 6, d));
    // The incompressible model's source: the flow enters the cement within sourceRadius of the outlet.
    sourceRadius_ = 0.5 * spec_.innerDiameter + 0.5 * d;
    if (incompressible_) sim_->setVolumeSource({tip_, sourceRadius_, spec_.flowRate});
    cannulaLength_ = scene.cannulaLengthMm * 1e-3;
    voxeliser_ = std::make_unique<sph::ParticleVoxeliser>(solid_->grid, 2.0 * scene.particleRadiusMm * 1e-3); // h = 2r
  }

  double time() const override { return sim_->time(); }
  double endSlack() const override { return 0.0; }

  // One step of the engine's own size (its stability and displacement limits); dtMax is not imposed, so that
  // both presets keep their step sequence (VALIDATION.md).
  // The outlet is sampled once after each step (the probe keeps its samples for the paper's baseline).
  void advance(double) override {
    sim_->setViscosity(viscosity_->at(sim_->time() - spec_.startTime));
    emitter_->emit(*sim_);
    sim_->step();
    const double mu = sim_->parameters().viscosity;
    outlet_ = {sim_->time(), outletPressure(),
               sph::hagenPoiseuillePressureDrop(mu, cannulaLength_, spec_.flowRate, spec_.innerDiameter)};
  }

  TipRecord outlet() const override { return outlet_; }

  double injectedVolumeM3() const override { return emitter_->emittedVolume(); }

  // Sum of m / rho with each particle's own density [m^3].
  double cementVolumeM3() const override {
    const sph::FluidParticles& f = sim_->fluid();
    double v = 0;
    for (std::size_t i = 0; i < f.size(); ++i) v += f.mass[i] / f.density[i];
    return v;
  }

  std::string state() const override {
    return std::to_string(sim_->fluid().size()) + " fluid + " + std::to_string(sim_->fixed().size()) +
           " fixed particles, " + std::to_string(sim_->statistics().steps) + " steps";
  }

  std::vector<double> cementDensity() const override { return voxeliser_->density(sim_->fluid()); }

  vtkSmartPointer<vtkPolyData> cement() const override { return particlesToPolyData(sim_->fluid(), sim_->time()); }

  void finish(bool stopped) override {
    if (!stopped) emitter_->emit(*sim_); // the emission up to the end time
    sim_->updateDensityAndPressure();
  }

  std::optional<double> pressureBaselinePa() const override {
    if (incompressible_) return 0.0; // the pressure itself: physical
    return baseline();
  }

  void report(InjectionSummary& s, nlohmann::json& e) const override {
    const sph::FluidParticles& f = sim_->fluid();
    double fluidMass = 0, spread = 0;
    std::size_t inSolid = 0;
    for (std::size_t i = 0; i < f.size(); ++i) {
      fluidMass += f.mass[i];
      spread += (f.position(i) - tip_).norm();
      std::array<int, 3> ijk{};
      if (solid_->voxelOf(f.position(i), ijk) && solid_->solid[solid_->grid.index(ijk[0], ijk[1], ijk[2])]) ++inSolid;
    }
    if (f.size() > 0) spread /= double(f.size());
    const double emittedMass = double(emitter_->emittedCount()) * emitter_->particleMass();
    const double escapedMass = double(sim_->escapedCount()) * emitter_->particleMass();
    const auto& st = sim_->statistics();
    s.steps = st.steps;
    s.particles = ParticleCounts{f.size(), sim_->fixed().size(), wallParticles_, sim_->escapedCount()};
    s.solidVoxelsKept = solid_->keptVoxels;
    s.resistance = m_.resistanceName();
    s.viscosityLaw = m_.viscosityLaw;
    s.pressureIsPhysical = incompressible_;
    s.tipPressureBaselinePa = baseline().value_or(0.0);
    s.meanSpreadingDistanceMm = spread * 1e3;
    s.massBalanceError = emittedMass > 0 ? (emittedMass - fluidMass - escapedMass) / emittedMass : 0.0;
    s.fluidInSolidFraction = f.size() == 0 ? 0.0 : double(inSolid) / double(f.size());
    s.finalViscosityPaS = sim_->parameters().viscosity;
    s.leakageAssessed = false; // a pore-resolved CT has no soft tissue class

    e["model_caveat"] = incompressible_
                            ? "the particles' incompressible Darcy solve: does not yet meet its pressure oracles "
                              "(VALIDATION.md); the voxel-grid Darcy filling does"
                            : "the paper's weakly compressible model: volume not conserved, pressure not physical "
                              "(a relative model pressure of the equation of state, Eq. 6)";
    e["solid_mass_factor"] = scene_->solidMassFactor;
    e["smallest_time_step_s"] = st.smallestStep;
    e["largest_time_step_s"] = st.largestStep;
    e["integrator"] = sph::toString(m_.integrator);
    e["fixed_particle_sums"] = sph::toString(m_.fixedSums);
    e["fixed_field_bricks"] = sim_->fixedField().bricksFilled();
    e["neighbour_rebuilds"] = st.neighbourRebuilds;
    e["neighbour_relistings"] = st.relistings;
    e["smoothing_length_mm"] = m_.smoothingLength * 1e3;
    if (incompressible_) {
      const auto* darcy = dynamic_cast<const sph::IncompressibleDarcy*>(&sim_->pressureModel());
      const auto& ps = darcy->statistics();
      addPressureSolverFigures(e, ps.solves, ps.iterations, ps.worstResidual, ps.unconverged, ps.solveSeconds);
      e["front_particles"] = ps.lastFrontParticles;
      e["outlet_source_radius_mm"] = sourceRadius_ * 1e3;
    }
  }

private:
  // Pressure at the outlet [Pa]: incompressible, the mean pressure of the cement the source feeds (the
  // pressure the cannula works against: power = Q p); equation of state, the paper's probe (Eq. 6 ring).
  double outletPressure() {
    if (!incompressible_) return probe_->sample(*sim_).meanPressure;
    const sph::FluidParticles& f = sim_->fluid();
    double sum = 0, weight = 0;
    for (std::size_t i = 0; i < f.size(); ++i)
      if ((f.position(i) - tip_).norm() <= sourceRadius_) {
        const double w = f.mass[i] / f.porosity[i];
        sum += w * f.pressure[i];
        weight += w;
      }
    return weight > 0 ? sum / weight : 0.0;
  }

  // The paper's baseline: the mean of the first 0.5 s (the equation of state's pressure is relative); none
  // before 0.5 s have run.
  std::optional<double> baseline() const {
    if (incompressible_) return std::nullopt;
    try {
      return probe_->baseline();
    } catch (const std::logic_error&) {
      return std::nullopt;
    }
  }

  const SceneConfig* scene_ = nullptr;
  const PorousSolid* solid_ = nullptr;
  sph::ModelParameters m_;
  bool incompressible_ = false;
  Eigen::Vector3d tip_;
  sph::CannulaSpec spec_;
  std::unique_ptr<sph::CannulaEmitter> emitter_;
  std::optional<sph::ViscositySchedule> viscosity_;
  TipRecord outlet_{0, 0, 0};
  std::unique_ptr<sph::Simulation> sim_;
  std::size_t wallParticles_ = 0;
  std::unique_ptr<sph::TipPressureProbe> probe_;
  double sourceRadius_ = 0, cannulaLength_ = 0;
  std::unique_ptr<sph::ParticleVoxeliser> voxeliser_;
};

} // namespace

std::unique_ptr<InjectionModel> makeParticleInjectionModel() { return std::make_unique<ParticleInjectionModel>(); }

// The scene keys these engines (incompressible, equation-of-state) read besides the driver's (InjectionModel.h):
// the particles' size and the SPH model's overrides (sph::ModelParameters), the fixed particles' mass, and the
// law and curing only to refuse any but a Newtonian cement.
InjectionModelRegistry::SceneKeys particleSceneKeys() {
  return {"particle_radius_mm", "drag_coefficient", "sound_speed_m_per_s", "integrator", "fixed_particle_sums",
          "fixed_field_spacing_over_h", "max_displacement_over_h", "neighbour_skin_over_h", "solid_mass_factor",
          "viscosity_law", "curing_model"};
}

} // namespace cementsph::scene
