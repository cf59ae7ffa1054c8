// permeability.csv (DarcyTable.h), the table `cementsph darcy` writes: one row from numbers the test sets, with
// the Kozeny-Carman column computed here (phi^3 / (180 (1 - phi)^2) = 0.125 / 45 at phi 0.5), and the refusal of
// a non-finite fit.
#include "cementsph/sph/DarcyTable.h"
#include "cementsph/sph/Simulation.h"

#include <gtest/gtest.h>

#include <limits>

namespace {

using namespace cementsph::sph;

DarcyResult result() {
  DarcyResult r;
  r.input.spacing = 0.5e-3;
  r.input.viscosity = 100;
  r.porosity = 0.5;
  r.slope = 2.5e-6;
  r.r2 = 0.999;
  r.permeability = 2.5e-4;
  r.dimensionlessPermeability = 0.004;
  r.steps = 1200;
  r.wallSeconds = 1.5;
  r.converged = true;
  r.intercept = -1e-9;
  return r;
}

TEST(DarcyTable, OneRowPerCaseWithTheKozenyCarmanValueAndTheModel) {
  const std::string csv = darcyPermeabilityCsv({result()}, {0.5, 12.5, "central-difference"});
  const std::string header =
      "porosity,spacing_mm,viscosity_pa_s,slope_s,r2,permeability_m2,dimensionless_permeability,"
      "kozeny_carman_dimensionless,steps,wall_s,converged,intercept_m_per_s,h_over_d,drag_coefficient,integrator\n";
  ASSERT_EQ(csv.substr(0, header.size()), header);
  EXPECT_EQ(csv.substr(header.size()),
            "0.5,0.5,100,2.5e-06,0.999,0.00025,0.004,0.0027777778,1200,1.5,1,-1e-09,0.5,12.5,central-difference\n");
}

TEST(DarcyTable, ANonFiniteFitIsAFailedRunNamingItsPorosity) {
  DarcyResult r = result();
  r.r2 = std::numeric_limits<double>::quiet_NaN();
  try {
    (void)darcyPermeabilityCsv({r}, {0.5, 12.5, "explicit"});
    FAIL() << "a NaN went into the table";
  } catch (const SimulationError& e) {
    EXPECT_NE(std::string(e.what()).find("porosity 0.5"), std::string::npos) << e.what();
  }
}

} // namespace
