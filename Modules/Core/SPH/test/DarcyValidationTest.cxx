// The paper's Darcy checks (Figs. 4, 5) on a small random lattice (10^3 sites; the full 25^3 protocol
// is `cementsph darcy`, figures in VALIDATION.md). Each assertion states its tolerance.
#include "cementsph/sph/DarcyBenchmark.h"
#include "cementsph/sph/Presets.h"

#include <gtest/gtest.h>

#include <iomanip>
#include <iostream>

using namespace cementsph::sph;

namespace {

DarcyResult runCase(double porosity, double spacingMm, double viscosity, Integrator integrator = Integrator::Overdamped,
                    std::vector<double> forces = {}, double dragCoefficient = 0) {
  ModelPreset preset = modelPreset("default");
  preset.model.integrator = integrator;
  if (dragCoefficient > 0) preset.model.dragCoefficient = dragCoefficient;
  DarcyBenchmark bench(preset.model, preset.hOverD);
  DarcyCase c;
  c.latticeSize = 10;
  c.porosity = porosity;
  c.spacing = spacingMm * 1e-3;
  c.viscosity = viscosity;
  c.seed = 5;
  c.bodyForces = std::move(forces);
  return bench.run(c);
}

} // namespace

class DarcyValidation : public ::testing::Test {
protected:
  static void SetUpTestSuite() {
    reference_ = new DarcyResult(runCase(0.7, 1.0, 10.0));
  }
  static void TearDownTestSuite() { delete reference_; }
  static DarcyResult* reference_;
};
DarcyResult* DarcyValidation::reference_ = nullptr;

TEST_F(DarcyValidation, VelocityIsLinearInBodyForce) {
  EXPECT_TRUE(reference_->converged);
  EXPECT_GE(reference_->r2, 0.999); // issue: R^2 >= 0.999
  std::cout << "porosity 0.7, d 1 mm, 10 Pa.s: k/d^2 " << reference_->dimensionlessPermeability << ", R^2 "
            << reference_->r2 << ", steps " << reference_->steps << "\n";
  EXPECT_EQ(reference_->points.size(), 4u);
}

TEST_F(DarcyValidation, PermeabilityIndependentOfViscosity) {
  // Exact by construction in the overdamped model: v = a / gamma with gamma proportional to mu, and every step
  // limit (overdamped stability ~ gamma, displacement ~ 1/|v|) scales with mu too, so 10x the viscosity takes
  // the same steps through the same positions, 10x longer, and u / F_B falls by exactly 1/mu: k = mu u / (rho0
  // F_B) is unchanged up to round-off (10 is not a power of two, so the last bits differ). 12k steps of
  // particles rearranging past fixed ones amplify that round-off: measured 4.6e-6 (the Cf scaling below, the
  // same construction on a smaller box and fewer steps, 5e-12); allowed 1e-4, 300x tighter than the 3 % before.
  const DarcyResult viscous = runCase(0.7, 1.0, 100.0);
  std::cout << std::setprecision(17) << "k(100 Pa.s) / k(10 Pa.s) - 1 = " << viscous.permeability / reference_->permeability - 1
            << ", steps " << viscous.steps << " vs " << reference_->steps << "\n";
  EXPECT_EQ(viscous.steps, reference_->steps);
  EXPECT_NEAR(viscous.permeability / reference_->permeability, 1.0, 1e-4);
}

TEST_F(DarcyValidation, DimensionlessPermeabilityIndependentOfSpacing) {
  // Exact by construction: halving d halves every length (h = d, positions), the default body forces scale
  // as 1/d (bodyForceSweep), the pressure acceleration cs^2 grad(rho)/rho as 1/d, and gamma ~ m / h^5 as
  // 1/d^2, so velocities halve and the run repeats itself at half the scale with the same steps. The factor
  // 1/2 is a power of two: every product is the same to the last bit, k/d^2 is identical and k is a quarter
  // (measured: both exact; 1e-12 allowed).
  const DarcyResult fine = runCase(0.7, 0.5, 10.0);
  std::cout << std::setprecision(17) << "k/d^2(0.5 mm) / k/d^2(1 mm) - 1 = "
            << fine.dimensionlessPermeability / reference_->dimensionlessPermeability - 1 << ", k ratio "
            << fine.permeability / reference_->permeability << ", steps " << fine.steps << " vs " << reference_->steps << "\n";
  EXPECT_EQ(fine.steps, reference_->steps);
  EXPECT_NEAR(fine.dimensionlessPermeability / reference_->dimensionlessPermeability, 1.0, 1e-12);
  EXPECT_NEAR(fine.permeability / reference_->permeability, 0.25, 0.25e-12); // k itself scales with d^2
}

TEST_F(DarcyValidation, PermeabilityRisesWithPorosity) {
  const DarcyResult tight = runCase(0.5, 1.0, 10.0);
  const DarcyResult open = runCase(0.9, 1.0, 10.0);
  EXPECT_LT(tight.dimensionlessPermeability, reference_->dimensionlessPermeability);
  EXPECT_LT(reference_->dimensionlessPermeability, open.dimensionlessPermeability);
  // and stays below the free-drag value (h/d)^5 / Cf = 1 of porosity 1 (model-notes 3)
  EXPECT_LT(open.dimensionlessPermeability, 1.0);
  std::cout << "k/d^2 at porosity 0.5 / 0.7 / 0.9: " << tight.dimensionlessPermeability << " / "
            << reference_->dimensionlessPermeability << " / " << open.dimensionlessPermeability << "\n";
}

TEST(DarcyCalibration, PermeabilityScalesAsOneOverDragCoefficient) {
  // Overdamped: dt ~ gamma ~ Cf and u ~ 1/Cf, so the same travel per step and k ~ 1/Cf exactly. This
  // is what lets one Cf = 1 sweep calibrate Cf (VALIDATION.md).
  ModelPreset preset = modelPreset("default");
  DarcyCase c;
  c.latticeSize = 8;
  c.porosity = 0.8;
  c.spacing = 1e-3;
  c.viscosity = 10.0;
  c.bodyForces = {2.0, 1.0};
  const DarcyResult base = DarcyBenchmark(preset.model, preset.hOverD).run(c);
  preset.model.dragCoefficient *= 2.5;
  const DarcyResult stiff = DarcyBenchmark(preset.model, preset.hOverD).run(c);
  std::cout << std::setprecision(17) << "k(2.5 Cf) / k(Cf) * 2.5 - 1 = " << stiff.permeability / base.permeability * 2.5 - 1
            << ", steps " << stiff.steps << " vs " << base.steps << "\n";
  EXPECT_EQ(stiff.steps, base.steps);
  EXPECT_NEAR(stiff.permeability / base.permeability, 1.0 / 2.5, 1e-9); // round-off: measured 5e-12
}

TEST(DarcyIntegrators, OverdampedMatchesCentralDifference) {
  // Same medium, same forces: the paper's integrator (Eq. 8, implicit drag) and the overdamped limit.
  // At 1 Pa.s and Cf = 1 the central difference needs ~5k steps per spacing travelled (it is bound by
  // the acoustic step); its step count grows with mu Cf, the overdamped one's does not.
  const std::vector<double> forces{2.0, 1.0};
  const DarcyResult od = runCase(0.8, 1.0, 1.0, Integrator::Overdamped, forces, 1.0);
  const DarcyResult cd = runCase(0.8, 1.0, 1.0, Integrator::CentralDifference, forces, 1.0);
  ASSERT_TRUE(od.converged);
  ASSERT_TRUE(cd.converged);
  // Not exact by construction: the central difference keeps the particles' inertia, which the overdamped limit
  // drops (relaxation time 1/gamma against the step), and the two trajectories part by round-off as well.
  // Measured 7.3e-4; allowed 5e-3 (the issue asked for 2 %).
  EXPECT_NEAR(od.permeability / cd.permeability, 1.0, 5e-3);
  EXPECT_LT(od.steps, cd.steps);
  RecordProperty("overdamped_steps", std::to_string(od.steps));
  RecordProperty("central_difference_steps", std::to_string(cd.steps));
  std::cout << "steps: overdamped " << od.steps << ", central difference " << cd.steps << "; k ratio "
            << od.permeability / cd.permeability << "\n";
}
