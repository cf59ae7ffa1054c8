// The paper's Darcy checks (Figs. 4, 5) on a small random lattice (10^3 sites; the full 25^3 protocol
// is `cementsph darcy`, figures in VALIDATION.md). Each assertion states its tolerance.
#include "cementsph/sph/DarcyBenchmark.h"
#include "cementsph/sph/Presets.h"

#include <gtest/gtest.h>

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
  const DarcyResult viscous = runCase(0.7, 1.0, 100.0);
  EXPECT_NEAR(viscous.permeability / reference_->permeability, 1.0, 0.03); // issue: within 3 %
  std::cout << "k(100 Pa.s) / k(10 Pa.s) = " << viscous.permeability / reference_->permeability << "\n";
}

TEST_F(DarcyValidation, DimensionlessPermeabilityIndependentOfSpacing) {
  const DarcyResult fine = runCase(0.7, 0.5, 10.0);
  EXPECT_NEAR(fine.dimensionlessPermeability / reference_->dimensionlessPermeability, 1.0, 0.10); // 10 %
  std::cout << "k/d^2(0.5 mm) / k/d^2(1 mm) = " << fine.dimensionlessPermeability / reference_->dimensionlessPermeability << "\n";
  EXPECT_NEAR(fine.permeability / reference_->permeability, 0.25, 0.025); // k itself scales with d^2
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
  EXPECT_NEAR(stiff.permeability / base.permeability, 1.0 / 2.5, 1e-6);
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
  EXPECT_NEAR(od.permeability / cd.permeability, 1.0, 0.02); // issue: within 2 %
  EXPECT_LT(od.steps, cd.steps);
  RecordProperty("overdamped_steps", std::to_string(od.steps));
  RecordProperty("central_difference_steps", std::to_string(cd.steps));
  std::cout << "steps: overdamped " << od.steps << ", central difference " << cd.steps << "; k ratio "
            << od.permeability / cd.permeability << "\n";
}
