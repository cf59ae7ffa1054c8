// The incompressible SPH for creeping Darcy flow (pressure_model "particle-darcy",
// src/Models/ParticleDarcy) through runInjection, against the issue 19 oracles:
//  * a uniform open medium (every voxel a pore, no shaft: cannula_wall false): the cement's mean distance
//    from the tip 3R/4 within 2 % (R from V = 4/3 pi R^3, phi = 1); the tip pressure
//    mu Q / (4 pi k)(1/r0 - 1/R) within 10 %, r0 the outlet profile's effective radius computed here
//    independently (1/r0 = 1/b + int_0^b f^2 / r^2 dr for a source uniform in the ball a = 1.194 mm, each
//    particle's share the part of its volume, a sphere of radius rp = (3/(4 pi))^(1/3) d, inside the ball:
//    b = a + rp; here the share is integrated over disk slices, not the engine's lens formula);
//    the volume within 1 % at every snapshot; the step-to-step tip-pressure change (median) below 5 %;
//    the pressure profile at 1.25-2.0 mm (outside the outlet ball, inside 0.7 R) within 5 % of the continuum
//    mu Q / (4 pi k)(int_r^inf f / s^2 ds - 1/R) (1/r - 1/R beyond b; particles' mean pressure in 0.25 mm shells);
//  * p(400) / p(100) = 4.00 within 1 % (creeping Darcy flow: p is proportional to mu);
//  * a hemisphere on an impermeable plane: radius 2^(1/3) times the free sphere's within 3 %;
//  * a scaffold CT (ScaffoldCT.h): cement in solid below 0.5 % of its volume (particles against the rods'
//    voxels, and the simulated CT's rods unchanged), the volume at every snapshot.
// The uniform case also runs voxel-darcy for the record (its figures and the wall-time ratio, printed).
#include "cementsph/scene/InjectionRunner.h"
#include "../src/Models/ParticleDarcy/ParticleDarcyStepping.h"
#include "ScaffoldCT.h"

#include <gtest/gtest.h>
#include <itkImageRegionConstIteratorWithIndex.h>
#include <vtkPointData.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <vector>

using namespace cementsph;
using namespace cementsph::scene;

namespace {
constexpr double kPi = 3.14159265358979323846;

// All pore: -100 HU everywhere.
imaging::ImageType::Pointer uniform(int n, double spacingMm) { return scene::testing::cube(n, spacingMm, -100.f); }

// The share of a sphere of radius rp, its centre r from the tip, inside the ball of radius a about the tip: both
// are symmetric about the line through the two centres, so each slice across it is two concentric disks
// (radii sqrt(rp^2 - z^2) and sqrt(a^2 - (r + z)^2)), overlapping in the smaller one. Midpoint rule in z.
double shareInBall(double r, double a, double rp) {
  const int n = 400;
  double v = 0;
  for (int k = 0; k < n; ++k) {
    const double z = -rp + 2 * rp * (k + 0.5) / n, t = r + z;
    const double rho2 = rp * rp - z * z, sigma2 = a * a - t * t;
    if (sigma2 > 0) v += kPi * std::min(rho2, sigma2) * (2 * rp / n);
  }
  return v / (4.0 / 3 * kPi * rp * rp * rp);
}

// The outlet's source profile: f(r) the enclosed share of a source of density shareInBall, b = a + rp its outer
// radius. The continuum pressure of it in a uniform medium is mu Q / (4 pi k)(phi(r) - 1/R) with
// phi(r) = int_r^inf f(s) / s^2 ds (1/r beyond b), and its source-weighted mean (the outlet pressure) is
// mu Q / (4 pi k)(1/r0 - 1/R) with 1/r0 = 1/b + int_0^b f^2 / r^2 dr (integration by parts).
struct SourceProfile {
  double b;
  int n = 2000;
  std::vector<double> f;
  SourceProfile(double a, double rp) : b(a + rp), f(std::size_t(n) + 1, 0.0) {
    for (int k = 1; k <= n; ++k) { // trapezoid on the enclosed source
      const double r0 = b * (k - 1) / n, r1 = b * k / n;
      f[std::size_t(k)] = f[std::size_t(k) - 1] +
                          0.5 * (shareInBall(r0, a, rp) * r0 * r0 + shareInBall(r1, a, rp) * r1 * r1) * (r1 - r0);
    }
    const double total = f[std::size_t(n)];
    for (double& share : f) share /= total;
  }
  // int_lo^b g(f(r), r) dr by the trapezoid rule on the table (g finite at r = 0: f ~ r^3).
  template <class G> double integral(double lo, G g) const {
    double s = 0;
    for (int k = 1; k <= n; ++k) {
      const double r0 = b * (k - 1) / n, r1 = b * k / n;
      if (r1 <= lo) continue;
      const double g0 = r0 > 0 ? g(f[std::size_t(k) - 1], r0) : 0.0, g1 = g(f[std::size_t(k)], r1);
      s += 0.5 * (g0 + g1) * (r1 - std::max(r0, lo));
    }
    return s;
  }
  double effectiveRadius() const { return 1.0 / (1.0 / b + integral(0.0, [](double ff, double r) { return ff * ff / (r * r); })); }
  double phi(double r) const {
    return r >= b ? 1.0 / r : 1.0 / b + integral(r, [](double ff, double rr) { return ff / (rr * rr); });
  }
};

struct Outcome {
  InjectionRunResult result;
  double wallS;
};

Outcome run(const imaging::ImageType* ct, nlohmann::json j, const std::string& model = "particle-darcy") {
  SceneConfig scene = sceneFromJson(j);
  scene.pressureModel = model;
  const auto t0 = std::chrono::steady_clock::now();
  Outcome r{runInjection(ct, scene, {}), 0};
  r.wallS = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

double medianRelativeChange(const std::vector<TipRecord>& s, double fromTime) {
  std::vector<double> c;
  for (std::size_t k = 1; k < s.size(); ++k)
    if (s[k - 1].time >= fromTime && s[k - 1].tipPa > 0) c.push_back(std::abs(s[k].tipPa / s[k - 1].tipPa - 1));
  if (c.empty()) return 1.0;
  std::nth_element(c.begin(), c.begin() + std::ptrdiff_t(c.size() / 2), c.end());
  return c[c.size() / 2];
}

nlohmann::json uniformScene(double mu) {
  return {{"tip_mm", {6, 6, 6}}, {"volume_ml", 0.1}, {"viscosity_pa_s", mu}, {"particle_radius_mm", 0.15},
          {"cannula_wall", false}, {"pore_permeability_m2", 1e-9}, {"snapshot_interval_s", 0.1}};
}

// 0.05 ml injected 0.15 mm above a solid plate: the uniform 40^3 cube of 0.3 mm voxels with voxels
// firstK..19 solid (z up to 5.85 mm; firstK 0: a half space, 19: one voxel thick with open pore below it).
Outcome runAbovePlate(int firstK) {
  auto ct = uniform(40, 0.3);
  for (int k = firstK; k < 20; ++k)
    for (int j = 0; j < 40; ++j)
      for (int i = 0; i < 40; ++i) ct->SetPixel({{i, j, k}}, 1000.f);
  nlohmann::json scene = uniformScene(100.0);
  scene["volume_ml"] = 0.05;
  return run(ct, scene);
}
} // namespace

TEST(ParticleDarcy, SphericalInjectionInAUniformMedium) {
  const auto ct = uniform(40, 0.3);
  const Outcome r = run(ct, uniformScene(100.0));
  const nlohmann::json& m = r.result.metrics;
  const double V = 0.1e-6, R = std::cbrt(3 * V / (4 * kPi)), mu = 100, Q = 0.05e-6, k = 1e-9;
  const double a = 0.5 * 2.388e-3, d = 0.3e-3;
  const SourceProfile source(a, std::cbrt(3 / (4 * kPi)) * d);
  const double r0 = source.effectiveRadius();
  const double tip = mu * Q / (4 * kPi * k) * (1 / r0 - 1 / R);
  const double noise = medianRelativeChange(r.result.tipSeries, 0.25 * V / Q);
  std::printf("uniform: spreading %.4f mm against 3R/4 %.4f mm; tip %.1f Pa against %.1f Pa (r0 %.4f mm, engine %.4f); "
              "noise %.4f; %zu steps, wall %.1f s, particles %s\n",
              m.at("mean_spreading_distance_mm").get<double>(), 0.75 * R * 1e3, m.at("final_tip_pressure_pa").get<double>(), tip,
              r0 * 1e3, m.at("outlet_effective_radius_mm").get<double>(), noise, std::size_t(m.at("steps")), r.wallS,
              m.at("fluid_particles").dump().c_str());
  std::printf("solver: %s iterations mean, worst residual %s, solve %s s, geometry %s s, front %s\n",
              m.at("pressure_solver_iterations_mean").dump().c_str(), m.at("pressure_solver_worst_residual").dump().c_str(),
              m.at("pressure_solve_wall_s").dump().c_str(), m.at("geometry_wall_s").dump().c_str(), m.at("front_particles").dump().c_str());
  {
    auto* pts = r.result.particles.GetPointer();
    auto* pa = pts->GetPointData()->GetArray("pressure_pa");
    auto* va = pts->GetPointData()->GetArray("velocity_m_per_s");
    const int nb = 16;
    std::vector<double> cnt(nb, 0), ps(nb, 0), vr(nb, 0);
    for (vtkIdType i = 0; i < pts->GetNumberOfPoints(); ++i) {
      double x[3];
      pts->GetPoint(i, x);
      const double rx = x[0] - 6, ry = x[1] - 6, rz = x[2] - 6, rr = std::sqrt(rx * rx + ry * ry + rz * rz);
      const int b = std::min(nb - 1, int(rr / 0.25));
      cnt[b] += 1, ps[b] += pa->GetTuple1(i);
      const double* v = va->GetTuple3(i);
      vr[b] += (v[0] * rx + v[1] * ry + v[2] * rz) / std::max(rr, 1e-9);
    }
    for (int b = 0; b < nb; ++b) {
      const double r1 = 0.25 * b, r2 = r1 + 0.25, shell = 4.0 / 3 * kPi * (r2 * r2 * r2 - r1 * r1 * r1), rm = (r1 + r2) / 2e3;
      const double oracle = mu * Q / (4 * kPi * k) * (source.phi(rm) - 1 / R);
      std::printf("  r %.3f density %.3f p %.0f (oracle %.0f) vr %.3g (oracle %.3g)\n", rm * 1e3, cnt[b] * 0.027 / shell,
                  cnt[b] > 0 ? ps[b] / cnt[b] : 0.0, oracle, cnt[b] > 0 ? vr[b] / cnt[b] : 0.0, Q / (4 * kPi * rm * rm));
      // The profile outside the outlet ball (a = 1.194 mm) and inside 0.7 R: the continuum oracle within 5 %.
      if (r1 >= 1.25 && r2 <= 2.0) {
        EXPECT_NEAR(ps[b] / cnt[b] / oracle, 1.0, 0.05) << "at r = " << rm * 1e3 << " mm";
      }
    }
  }
  EXPECT_NEAR(m["mean_spreading_distance_mm"].get<double>() / (0.75 * R * 1e3), 1.0, 0.02);
  EXPECT_NEAR(m["final_tip_pressure_pa"].get<double>() / tip, 1.0, 0.10);
  EXPECT_LT(noise, 0.05);
  // Multi-rate stepping runs here: the outlet's particles are (R / a)^2 ~ 6x faster than the front's, so the
  // fastest 5 % move more than 0.2 d in the bulk's macro step and must be sub-stepped; and the macro step bounds
  // their sub-steps (none clamped).
  std::printf("sub-steps %s, clamped %s, sub-step moves capped %s\n", m.at("sub_steps").dump().c_str(),
              m.at("sub_steps_clamped").dump().c_str(), m.at("sub_step_moves_capped").dump().c_str());
  EXPECT_GT(m.at("sub_steps").get<std::size_t>(), 0u);
  // A guard, 0 by construction since the macro step is bounded by the fastest Darcy speed (the unit test
  // ParticleDarcyStepping.TheMacroStepBoundsTheFastestDarcyMoveBySubSteps is the check that can fail).
  EXPECT_EQ(m.at("sub_steps_clamped").get<std::size_t>(), 0u);
  for (const auto& h : m["volume_history"]) {
    const double injected = h["volume_injected_ml"].get<double>(), held = h["cement_volume_ml"].get<double>();
    EXPECT_NEAR(held, injected, 0.01 * injected) << "at " << h["time_s"] << " s";
  }
  EXPECT_DOUBLE_EQ(m["fluid_in_solid_fraction"].get<double>(), 0.0);
  // The voxel model on the same case, for the record (cost ratio, its tip pressure).
  const Outcome v = run(ct, uniformScene(100.0), "voxel-darcy");
  std::printf("voxel-darcy on the same case: spreading %.4f mm, tip %.1f Pa, wall %.2f s (particle-darcy / voxel-darcy "
              "wall %.2f)\n", v.result.metrics["mean_spreading_distance_mm"].get<double>(),
              v.result.metrics["final_tip_pressure_pa"].get<double>(), v.wallS, r.wallS / v.wallS);
}

TEST(ParticleDarcy, AHemisphereOnAnImpermeablePlane) {
  // Solid below z = 5.85 mm (voxels k < 20 of 0.3 mm), the tip at 6.0 mm: the cement is the hemisphere of
  // the injected volume about the plane's point below the tip, R_h = 2^(1/3) R (R the free sphere's), its
  // mean distance from that point 3 R_h / 4.
  const Outcome r = runAbovePlate(0);
  auto* pts = r.result.particles.GetPointer();
  double mean = 0;
  std::size_t below = 0;
  for (vtkIdType i = 0; i < pts->GetNumberOfPoints(); ++i) {
    double x[3];
    pts->GetPoint(i, x);
    mean += std::sqrt((x[0] - 6) * (x[0] - 6) + (x[1] - 6) * (x[1] - 6) + (x[2] - 5.85) * (x[2] - 5.85));
    if (x[2] < 5.85) ++below;
  }
  mean /= double(pts->GetNumberOfPoints());
  const double R = std::cbrt(3 * 0.05e-6 / (4 * kPi)) * 1e3, Rh = 4.0 / 3.0 * mean;
  std::printf("hemisphere: radius %.4f mm against 2^(1/3) R = %.4f mm (ratio %.4f); %zu particles below the plane; "
              "%zu steps, wall %.1f s\n", Rh, std::cbrt(2.0) * R, Rh / (std::cbrt(2.0) * R), below,
              std::size_t(r.result.metrics["steps"]), r.wallS);
  EXPECT_NEAR(Rh / (std::cbrt(2.0) * R), 1.0, 0.03);
  EXPECT_EQ(below, 0u);
}

// A one-voxel plate (z 5.55-5.85 mm) with empty open space below it: cement on one side is within a kernel
// support of the pores on the other, so without a line-of-sight test the particles next to the plate took
// p = 0 ghosts through it. The plate is as impermeable as the half space of the test above, so the same
// oracles hold: the hemisphere's radius 2^(1/3) R within 3 %, no particle below the plate, and the pressure
// of the particles next to it (their centres within 0.45 mm of it, 1.6-2.0 mm from the plane point below the
// tip, outside the source ball's reach a + 0.15 + rp = 1.53 mm and inside 0.7 R_h) is the image solution's,
// mu (2 Q) / (4 pi k)(1 / r - 1 / R_h) (the plane mirrors the half source into a full one), within 10 %.
// The same figures are asserted for the thick half space, so the oracle is checked where no strut is thin.
TEST(ParticleDarcy, NoPressureCouplingCrossesAOneVoxelPlate) {
  for (const bool thin : {false, true}) {
    const Outcome r = runAbovePlate(thin ? 19 : 0);
    auto* pts = r.result.particles.GetPointer();
    auto* pa = pts->GetPointData()->GetArray("pressure_pa");
    const double V = 0.05e-6, mu = 100, Q = 0.05e-6, k = 1e-9;
    const double Rh = std::cbrt(3 * V / (2 * kPi)); // 2/3 pi R_h^3 = V
    double mean = 0, wallP = 0, wallOracle = 0;
    std::size_t below = 0, wallCount = 0;
    for (vtkIdType i = 0; i < pts->GetNumberOfPoints(); ++i) {
      double x[3];
      pts->GetPoint(i, x);
      const double rr = std::sqrt((x[0] - 6) * (x[0] - 6) + (x[1] - 6) * (x[1] - 6) + (x[2] - 5.85) * (x[2] - 5.85));
      mean += rr;
      if (x[2] < 5.85) ++below;
      if (x[2] - 5.85 < 0.45 && rr >= 1.6 && rr <= 2.0) {
        wallP += pa->GetTuple1(i);
        wallOracle += mu * 2 * Q / (4 * kPi * k) * (1 / (rr * 1e-3) - 1 / Rh);
        ++wallCount;
      }
    }
    mean /= double(pts->GetNumberOfPoints());
    const double measuredRh = 4.0 / 3.0 * mean * 1e-3;
    std::printf("%s plate: radius %.4f mm against R_h %.4f mm (ratio %.4f); %zu below; %zu particles next to the plate at "
                "1.6-2.0 mm: pressure %.0f Pa against the image solution's %.0f (ratio %.4f); hidden pairs per step %s\n",
                thin ? "one-voxel" : "half-space", measuredRh * 1e3, Rh * 1e3, measuredRh / Rh, below, wallCount,
                wallCount ? wallP / double(wallCount) : 0.0, wallCount ? wallOracle / double(wallCount) : 0.0,
                wallOracle > 0 ? wallP / wallOracle : 0.0, r.result.metrics["pairs_hidden_behind_solid_per_step"].dump().c_str());
    EXPECT_NEAR(measuredRh / Rh, 1.0, 0.03) << (thin ? "one-voxel plate" : "half space");
    EXPECT_EQ(below, 0u);
    ASSERT_GT(wallCount, 10u);
    EXPECT_NEAR(wallP / wallOracle, 1.0, 0.10) << (thin ? "one-voxel plate" : "half space");
  }
}

TEST(ParticleDarcy, PressureIsProportionalToViscosityAndTheCementIsTheSame) {
  // Creeping Darcy flow: p ~ mu, the motion independent of mu. 0.05 ml in the uniform medium.
  const auto ct = uniform(40, 0.3);
  nlohmann::json a = uniformScene(100.0), b = uniformScene(400.0);
  a["volume_ml"] = b["volume_ml"] = 0.05;
  const Outcome low = run(ct, a), high = run(ct, b);
  const nlohmann::json &x = low.result.metrics, &y = high.result.metrics;
  const double ratio = y["final_tip_pressure_pa"].get<double>() / x["final_tip_pressure_pa"].get<double>();
  std::printf("p(400) / p(100) = %.6f; spreading %.6f and %.6f mm\n", ratio, x["mean_spreading_distance_mm"].get<double>(),
              y["mean_spreading_distance_mm"].get<double>());
  EXPECT_NEAR(ratio, 4.0, 0.04);
  EXPECT_NEAR(y["max_tip_pressure_pa"].get<double>() / x["max_tip_pressure_pa"].get<double>(), 4.0, 0.04);
  // The same cement: every particle within 0.05 mm (the surfaces coincide).
  auto* p = low.result.particles.GetPointer();
  auto* q = high.result.particles.GetPointer();
  ASSERT_EQ(p->GetNumberOfPoints(), q->GetNumberOfPoints());
  double worst = 0;
  for (vtkIdType i = 0; i < p->GetNumberOfPoints(); ++i) {
    double u[3], v[3];
    p->GetPoint(i, u), q->GetPoint(i, v);
    worst = std::max(worst, std::sqrt((u[0] - v[0]) * (u[0] - v[0]) + (u[1] - v[1]) * (u[1] - v[1]) + (u[2] - v[2]) * (u[2] - v[2])));
  }
  std::printf("largest particle displacement between the two runs %.3g mm\n", worst);
  EXPECT_LT(worst, 0.05);
}

TEST(ParticleDarcy, NoCementEntersTheScaffoldsSolidAndTheVolumeIsKept) {
  const auto ct = cementsph::scene::testing::scaffold();
  const nlohmann::json j{{"tip_mm", {13, 13, 13}}, {"volume_ml", 0.1}, {"particle_radius_mm", 0.2},
                         {"cannula_length_mm", 5}, {"pore_permeability_m2", 1e-9}, {"snapshot_interval_s", 0.5}};
  const Outcome r = run(ct, j);
  const nlohmann::json& m = r.result.metrics;
  // Independently of the engine's figure: the particles' positions against the rods' voxels (0.5 mm, origin 0).
  auto* pts = r.result.particles.GetPointer();
  std::size_t inRod = 0;
  for (vtkIdType i = 0; i < pts->GetNumberOfPoints(); ++i) {
    double x[3];
    pts->GetPoint(i, x);
    if (cementsph::scene::testing::scaffoldRod(int(std::lround(x[0] / 0.5)), int(std::lround(x[1] / 0.5)),
                                               int(std::lround(x[2] / 0.5))))
      ++inRod;
  }
  const double share = double(inRod) / double(pts->GetNumberOfPoints());
  std::printf("scaffold: %zu of %lld particles in solid (%.4f); engine %.4f; tip %.1f Pa, spreading %.3f mm, %zu steps, "
              "wall %.1f s\n", inRod, (long long)pts->GetNumberOfPoints(), share, m["fluid_in_solid_fraction"].get<double>(),
              m["final_tip_pressure_pa"].get<double>(), m["mean_spreading_distance_mm"].get<double>(), std::size_t(m["steps"]),
              r.wallS);
  std::printf("scaffold: step-to-step tip-pressure change (median) %.4f\n", medianRelativeChange(r.result.tipSeries, 0.5));
  EXPECT_LT(share, 0.005);
  EXPECT_LT(m["fluid_in_solid_fraction"].get<double>(), 0.005);
  // The simulated CT: the rods (1000 HU) hold no cement.
  itk::ImageRegionConstIteratorWithIndex<imaging::ImageType> s(r.result.simulatedCt, r.result.simulatedCt->GetLargestPossibleRegion());
  std::size_t rodsChanged = 0;
  for (; !s.IsAtEnd(); ++s) {
    const auto idx = s.GetIndex();
    if (cementsph::scene::testing::scaffoldRod(int(idx[0]), int(idx[1]), int(idx[2])) && s.Get() != 1000.f) ++rodsChanged;
  }
  EXPECT_EQ(rodsChanged, 0u);
  for (const auto& h : m["volume_history"]) {
    const double injected = h["volume_injected_ml"].get<double>(), held = h["cement_volume_ml"].get<double>();
    EXPECT_NEAR(held, injected, 0.01 * injected) << "at " << h["time_s"] << " s";
  }
}

// A power-law cement (viscosity_law "power-law", K = 100 Pa s^n, n = 0.7) in the uniform medium: Darcy's law
// with the law's viscosity at the Darcy-scale shear rate, mu = K gamma^(n-1), gamma = alpha q / sqrt(k phi),
// alpha = (3n + 1) / (4n) 12 / sqrt(150) (the Rheology module's darcyShearRate, written out here), phi = 1, and
// the superficial speed q = Q f(r) / (4 pi r^2) (f the outlet's enclosed share, SourceProfile):
// dp/dr = -mu q / k = -G f^n r^(-2n), G = (K / k)(alpha / sqrt k)^(n-1) (Q / 4 pi)^n, p(R) = 0, so beyond the
// source p = G (r^(1-2n) - R^(1-2n)) / (2n - 1) (p ~ r^(1-2n)), and the outlet's source-weighted mean pressure
// p_tip = p(b) + G int_0^b f^(n+1) r^(-2n) dr (integration by parts). The profile at 1.25-2.0 mm within 5 %,
// the tip pressure within 10 %, the spreading 3R/4 within 2 % (the shape of a Darcy flow does not depend on
// the law in a uniform medium: the flux is radial whatever the viscosity).
TEST(ParticleDarcy, APowerLawCementFollowsTheDarcyPowerLawProfile) {
  const auto ct = uniform(40, 0.3);
  nlohmann::json j = uniformScene(100.0);
  j.erase("viscosity_pa_s");
  j["viscosity_law"] = "power-law";
  j["consistency_pa_s_n"] = 100.0;
  j["flow_index"] = 0.7;
  const Outcome r = run(ct, j);
  const nlohmann::json& m = r.result.metrics;
  const double K = 100, n = 0.7, V = 0.1e-6, R = std::cbrt(3 * V / (4 * kPi)), Q = 0.05e-6, k = 1e-9;
  const double alpha = (3 * n + 1) / (4 * n) * 12 / std::sqrt(150.0);
  const double G = K / k * std::pow(alpha / std::sqrt(k), n - 1) * std::pow(Q / (4 * kPi), n);
  const SourceProfile source(0.5 * 2.388e-3, std::cbrt(3 / (4 * kPi)) * 0.3e-3);
  const double b = source.b;
  auto outside = [&](double rr) { return G * (std::pow(rr, 1 - 2 * n) - std::pow(R, 1 - 2 * n)) / (2 * n - 1); };
  auto pressure = [&](double rr) {
    return rr >= b ? outside(rr)
                   : outside(b) + G * source.integral(rr, [n](double ff, double s) { return std::pow(ff, n) * std::pow(s, -2 * n); });
  };
  const double tip = outside(b) + G * source.integral(0.0, [n](double ff, double s) { return std::pow(ff, n + 1) * std::pow(s, -2 * n); });
  std::printf("power law: tip %.1f Pa against %.1f Pa (ratio %.4f); spreading %.4f mm against %.4f; viscosity %s-%s Pa s; "
              "%zu steps, wall %.1f s\n", m["final_tip_pressure_pa"].get<double>(), tip, m["final_tip_pressure_pa"].get<double>() / tip,
              m["mean_spreading_distance_mm"].get<double>(), 0.75 * R * 1e3, m["apparent_viscosity_min_pa_s"].dump().c_str(),
              m["apparent_viscosity_max_pa_s"].dump().c_str(), std::size_t(m["steps"]), r.wallS);
  auto* pts = r.result.particles.GetPointer();
  auto* pa = pts->GetPointData()->GetArray("pressure_pa");
  const int nb = 16;
  std::vector<double> cnt(nb, 0), ps(nb, 0);
  for (vtkIdType i = 0; i < pts->GetNumberOfPoints(); ++i) {
    double x[3];
    pts->GetPoint(i, x);
    const double rr = std::sqrt((x[0] - 6) * (x[0] - 6) + (x[1] - 6) * (x[1] - 6) + (x[2] - 6) * (x[2] - 6));
    const int s = std::min(nb - 1, int(rr / 0.25));
    cnt[s] += 1, ps[s] += pa->GetTuple1(i);
  }
  for (int s = 5; s < 8; ++s) { // shells 1.25-2.0 mm
    const double rm = (0.25 * s + 0.125) * 1e-3, oracle = pressure(rm);
    std::printf("  r %.3f mm p %.0f (oracle %.0f, ratio %.4f)\n", rm * 1e3, ps[s] / cnt[s], oracle, ps[s] / cnt[s] / oracle);
    EXPECT_NEAR(ps[s] / cnt[s] / oracle, 1.0, 0.05) << "at r = " << rm * 1e3 << " mm";
  }
  EXPECT_NEAR(m["final_tip_pressure_pa"].get<double>() / tip, 1.0, 0.10);
  EXPECT_NEAR(m["mean_spreading_distance_mm"].get<double>() / (0.75 * R * 1e3), 1.0, 0.02);
  EXPECT_EQ(m["viscosity_law"].get<std::string>(), "power-law");
}

// A law the engine cannot do is refused with one line naming the key (curing: a time factor not built here).
TEST(ParticleDarcy, ACuringCementIsRefusedWithOneLine) {
  const auto ct = uniform(20, 0.3);
  nlohmann::json j = uniformScene(100.0);
  j["tip_mm"] = {3, 3, 3};
  j["curing_model"] = "exponential";
  try {
    run(ct, j);
    ADD_FAILURE() << "a curing cement ran under particle-darcy";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("curing_model"), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
}

// pressure_model "auto" through the driver (ModelSelection.h): a scaffold whose pores are wide (rods 3 voxels
// thick every 20 voxels of 0.5 mm: mean pore chord 15.24 mm, 30 voxels, counted here over the 40^3 region from
// the rod rule) with particles of d = 0.6 mm (25 across) runs particle-darcy; the default scaffold (every 10
// voxels: 7.23 mm) with the preset's d = 1.14 mm (6.3 across, under 8) runs voxel-darcy.
TEST(ParticleDarcy, AutoPicksParticlesWhereTheyResolveThePores) {
  auto chord = [](int period) { // pore length / pore runs along x, y and z
    double length = 0, runs = 0;
    for (int axis = 0; axis < 3; ++axis)
      for (int u = 0; u < 40; ++u)
        for (int v = 0; v < 40; ++v) {
          bool inPore = false;
          for (int t = 0; t < 40; ++t) {
            int c[3];
            c[axis] = t, c[(axis + 1) % 3] = u, c[(axis + 2) % 3] = v;
            const bool pore = !cementsph::scene::testing::scaffoldRod(c[0], c[1], c[2], period, 3);
            if (pore && !inPore) runs += 1;
            if (pore) length += 0.5;
            inPore = pore;
          }
        }
    return length / runs;
  };
  const nlohmann::json j{{"tip_mm", {13, 13, 13}}, {"volume_ml", 0.005}, {"flow_rate_ml_per_s", 0.05},
                         {"cannula_length_mm", 5}, {"snapshot_interval_s", 1.0}};
  nlohmann::json fine = j;
  fine["particle_radius_mm"] = 0.3;
  const InjectionRunResult wide = runInjection(cementsph::scene::testing::scaffold(40, 0.5, 20, 3), sceneFromJson(fine), {});
  EXPECT_EQ(wide.metrics["pressure_model"], "particle-darcy") << wide.metrics["model_reason"];
  EXPECT_NEAR(wide.metrics["dimensionless_numbers"]["mean_pore_chord_mm"].get<double>(), chord(20), 1e-9);
  EXPECT_GE(chord(20) / 0.6, 8.0);
  const InjectionRunResult narrow = runInjection(cementsph::scene::testing::scaffold(), sceneFromJson(j), {});
  EXPECT_EQ(narrow.metrics["pressure_model"], "voxel-darcy") << narrow.metrics["model_reason"];
  EXPECT_LT(chord(10) / 1.14, 8.0);
}

// The stepping rules (ParticleDarcyStepping.h), each against a number worked out here.
// A one-voxel wall (voxels of 1 mm, voxel 1 closed: x in [0.5, 1.5)) with open space on both sides: a step of
// 1.6 mm from x = 0.2 ends at 1.8 (open) but crosses the wall, so it is dropped (x stays 0.2); a step of 0.25 mm
// toward the wall is taken (0.45, open); along y, where nothing is closed, a 3.3 mm step is taken whole.
TEST(ParticleDarcyStepping, AStepNeverCrossesAOneVoxelWall) {
  const auto closedAt = [](const Eigen::Vector3d& p) { return std::floor(p.x() + 0.5) == 1.0; };
  const Eigen::Vector3d spacing(1.0, 1.0, 1.0);
  Eigen::Vector3d pos(0.2, 0.0, 0.0);
  cementsph::scene::particle_darcy::stepAround(pos, Eigen::Vector3d(1.6, 3.3, 0.0), spacing, closedAt);
  EXPECT_DOUBLE_EQ(pos.x(), 0.2);
  EXPECT_DOUBLE_EQ(pos.y(), 3.3);
  cementsph::scene::particle_darcy::stepAround(pos, Eigen::Vector3d(0.25, 0.0, 0.0), spacing, closedAt);
  EXPECT_DOUBLE_EQ(pos.x(), 0.45);
}

// A particle that is not sub-stepped (Darcy move 0.1 <= limit 0.2) with a density correction of 10 a step: its
// move is its Darcy move plus the correction capped at the limit plus its shift, |(0.1 + 0.2, 0.05, 0)|.
TEST(ParticleDarcyStepping, TheDensityCorrectionIsCappedForEveryParticle) {
  using cementsph::scene::particle_darcy::macroMove;
  const Eigen::Vector3d darcy(0.1, 0, 0), u(10.1, 0, 0), shift(0, 0.05, 0);
  const Eigen::Vector3d plain = macroMove(u, darcy, shift, 1.0, false, 0.2);
  EXPECT_NEAR(plain.norm(), std::hypot(0.3, 0.05), 1e-12);
  const Eigen::Vector3d sub = macroMove(u, darcy, shift, 1.0, true, 0.2); // sub-stepped: the correction and shift only
  EXPECT_NEAR(sub.norm(), std::hypot(0.2, 0.05), 1e-12);
}

// The fastest particle's Darcy speed 1 with a correction against it (|u| = 0.3), 99 slow particles (|u| 0.01):
// the macro step may take it at most 4 sub-steps of the limit 0.2 by its Darcy speed, dt <= 4 x 0.2 / 1 = 0.8
// (the bulk's 0.2 / 0.01 = 20 and the growth bound 100 do not bind); with the clipped whole speed (0.3) as the
// bound it was 2.67, 13 sub-steps' worth, clamped to 4 and silently short.
TEST(ParticleDarcyStepping, TheMacroStepBoundsTheFastestDarcyMoveBySubSteps) {
  std::vector<double> speeds(100, 0.01);
  speeds[0] = 0.3;
  cementsph::scene::particle_darcy::MacroStepRule rule;
  rule.limit = 0.2;
  const double dt = cementsph::scene::particle_darcy::macroStep(speeds, 1.0, 1e9, 100.0, rule);
  EXPECT_NEAR(dt, 0.8, 1e-12);
  // Without a correction against the flow the rule is unchanged: the fastest whole speed 0.5 (Darcy 0.4) sets it.
  speeds[0] = 0.5;
  EXPECT_NEAR(cementsph::scene::particle_darcy::macroStep(speeds, 0.4, 1e9, 100.0, rule), 4 * 0.2 / 0.5, 1e-12);
}

// The closed space's sums are read between voxel centres by particle_darcy::blendedTrilinear (the mean of the
// trilinear value and the trilinear blend of the corners' Taylor expansions). On the quadratic
// f(x) = 3 + b.x + x^T A x / 2 (A with cross terms) on a 0.47 x 0.47 x 0.5 cell it must give f exactly at any
// point of the cell, where plain trilinear interpolation errs by 1/2 sum_a A_aa t_a (1 - t_a) spacing_a^2 (checked
// too, so the test tells the two apart).
TEST(ParticleDarcyStepping, TheClosedSumsInterpolantIsExactOnQuadratics) {
  Eigen::Matrix3d A;
  A << 4.0, 1.5, -0.7, 1.5, -2.0, 0.9, -0.7, 0.9, 6.0;
  const Eigen::Vector3d b(0.3, -1.1, 2.0), x0(1.2, -0.4, 0.7), spacing(0.47, 0.47, 0.5);
  const auto f = [&](const Eigen::Vector3d& x) { return 3.0 + b.dot(x) + 0.5 * x.dot(A * x); };
  double value[8];
  Eigen::Vector3d grad[8];
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d xc = x0 + Eigen::Vector3d(c & 1, (c >> 1) & 1, (c >> 2) & 1).cwiseProduct(spacing);
    value[c] = f(xc), grad[c] = b + A * xc;
  }
  for (const Eigen::Vector3d& t : {Eigen::Vector3d(0.5, 0.5, 0.5), Eigen::Vector3d(0.1, 0.8, 0.35), Eigen::Vector3d(0.93, 0.02, 0.6)}) {
    const Eigen::Vector3d x = x0 + t.cwiseProduct(spacing);
    EXPECT_NEAR(cementsph::scene::particle_darcy::blendedTrilinear(value, grad, t, spacing), f(x), 1e-12);
    double plain = 0, error = 0;
    for (int c = 0; c < 8; ++c)
      plain += value[c] * ((c & 1) ? t[0] : 1 - t[0]) * (((c >> 1) & 1) ? t[1] : 1 - t[1]) * (((c >> 2) & 1) ? t[2] : 1 - t[2]);
    for (int a = 0; a < 3; ++a) error += 0.5 * A(a, a) * t[a] * (1 - t[a]) * spacing[a] * spacing[a];
    EXPECT_NEAR(plain - f(x), error, 1e-12);
  }
}

// The colour pass (particle_darcy::colourRun) lists a voxel once, and only once it has colour. On the phantom's
// kernel (d = 1.14 mm, h = 1.5 d) a voxel at r^2 one float below (2h)^2 lies inside the support in single
// precision, but q = r / h rounds to 2 there, so its weight is 0 (checked here first). Two particles reaching it (the
// four-voxel SSE path, and the one-voxel scalar path) must leave it unlisted with no colour; before, each listed it
// (its colour stayed 0), and the report's colour and label volumes counted it twice. A voxel at r = h, reached by
// the same two particles, is listed once with 2 d^3 W(h) = 2 d^3 21 / (16 pi h^3) x 3 / 16 (within 1e-6: float).
TEST(ParticleDarcyStepping, AVoxelIsListedOnceAndOnlyWithColour) {
  const double d = 1.14e-3, h = 1.5 * d;
  const float invH = float(1.0 / h), cs2 = float(4 * h * h), wn = float(d * d * d * 21.0 / (16 * kPi * h * h * h));
  const float edge = std::nextafter(cs2, 0.0f);
  ASSERT_LT(edge, cs2);
  ASSERT_LE(1.0f - 0.5f * (std::sqrt(edge) * invH), 0.0f); // the premise: inside in float, weight 0
  using cementsph::scene::particle_darcy::colourRun;
  const cementsph::scene::particle_darcy::ColourKernel kern(4e-3f, invH, wn, cs2);
  // The four-lane path (four voxels, the others beyond the support), the run's tail in four lanes, and one at a time.
  for (const auto& [n, room] : {std::pair<int, std::size_t>{4, 4}, {1, 4}, {1, 1}}) {
    std::vector<float> colour(4, 0.0f);
    std::vector<std::size_t> touched;
    for (int particle = 0; particle < 2; ++particle) colourRun(colour.data(), 10, n, room, 0.0f, edge, kern, touched);
    EXPECT_TRUE(touched.empty()) << n << " voxels: listed " << touched.size() << " times";
    for (float c : colour) EXPECT_EQ(c, 0.0f);
    const float atH = float(h * h);
    for (int particle = 0; particle < 2; ++particle) colourRun(colour.data(), 10, n, room, 0.0f, atH, kern, touched);
    if (touched.size() != 1u) {
      ADD_FAILURE() << n << " voxels: " << touched.size() << " listed, not 1";
      continue;
    }
    EXPECT_EQ(touched[0], 10u);
    const double expected = 2 * d * d * d * 21.0 / (16 * kPi * h * h * h) * 3.0 / 16.0;
    EXPECT_NEAR(colour[0], expected, 1e-6 * expected);
  }
}

// A run's last n % 4 voxels are summed four lanes at once where the colour array has room past the run, with the
// one-voxel formula: the same bits as one voxel at a time (the figures do not depend on the array's room), and the
// lanes past the run are stored unchanged. 2000 runs of 1-3 voxels (and 5-7: four lanes, then the tail) at random
// offsets within and about the phantom kernel's support, against the same run summed with no room (one at a time).
TEST(ParticleDarcyStepping, TheColourRunsTailIsTheSameBitsInFourLanes) {
  const double d = 1.14e-3, h = 1.5 * d;
  const cementsph::scene::particle_darcy::ColourKernel kern(0.47e-3f, float(1.0 / h), float(d * d * d * 21.0 / (16 * kPi * h * h * h)),
                                                           float(4 * h * h));
  std::uint32_t state = 12345u;
  const auto uniform01 = [&] { return double((state = state * 1664525u + 1013904223u) >> 8) / double(1u << 24); };
  int differing = 0, lanesChanged = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const int n = 1 + trial % 7;
    if (n == 4) continue;
    const float rx0 = float((uniform01() * 2 - 1) * 2.2 * h), ryz2 = float(uniform01() * 4.4 * h * h);
    std::vector<float> lanes(12, 0.0f), single(12, 0.0f);
    for (int k = 0; k < 12; ++k) lanes[std::size_t(k)] = single[std::size_t(k)] = k >= n ? 7.0f : (trial % 2 ? 0.0f : 0.25f);
    std::vector<std::size_t> touchedLanes, touchedSingle;
    cementsph::scene::particle_darcy::colourRun(lanes.data(), 0, n, lanes.size(), rx0, ryz2, kern, touchedLanes);
    cementsph::scene::particle_darcy::colourRun(single.data(), 0, n, std::size_t(n), rx0, ryz2, kern, touchedSingle);
    for (int k = 0; k < n; ++k) differing += lanes[std::size_t(k)] != single[std::size_t(k)];
    for (int k = n; k < 12; ++k) lanesChanged += lanes[std::size_t(k)] != 7.0f;
    EXPECT_EQ(touchedLanes, touchedSingle) << "run of " << n;
  }
  EXPECT_EQ(differing, 0);
  EXPECT_EQ(lanesChanged, 0);
}

// A voxel listed in one step and not in the next reads a share of 0 (particle_darcy::updateShares), as its colour
// is. The case: a voxel first at r = h from a particle (listed, share > 0), then at r = 2h (1 - 1e-10) from it: inside
// the support in double (the ghosts' test, checked here) but outside in float (the colour pass's, checked: no
// colour, not listed). Before, its share was that of the first step.
TEST(ParticleDarcyStepping, AVoxelNoLongerListedHasNoShare) {
  const double d = 1.14e-3, h = 1.5 * d, r = 2 * h * (1 - 1e-10);
  const float invH = float(1.0 / h), cs2 = float(4 * h * h), wn = float(d * d * d * 21.0 / (16 * kPi * h * h * h));
  using namespace cementsph::scene::particle_darcy;
  const ColourKernel kern(4e-3f, invH, wn, cs2);
  std::vector<float> colour(4, 0.0f);
  std::vector<double> share(4, 0.0);
  const auto shareOf = [&](std::size_t v) { return double(colour[v]) / (d * d * d * 21.0 / (16 * kPi * h * h * h)); };
  std::vector<std::size_t> first, second;
  colourRun(colour.data(), 0, 1, colour.size(), float(h), 0.0f, kern, first);
  updateShares(share, {}, first, shareOf);
  ASSERT_EQ(first.size(), 1u);
  EXPECT_NEAR(share[0], 3.0 / 16.0, 1e-6); // W(h) / W(0)
  for (std::size_t v : first) colour[v] = 0.0f; // the next step's colour pass starts from 0 on the listed voxels
  ASSERT_LT(r * r, 4 * h * h); // the premise: inside in double ...
  colourRun(colour.data(), 0, 1, colour.size(), float(r), 0.0f, kern, second);
  ASSERT_TRUE(second.empty()); // ... outside in float
  updateShares(share, first, second, shareOf);
  EXPECT_EQ(share[0], 0.0);
}

// A particle whose position is not finite stops the run with sph::SimulationError naming it and why
// (particle_darcy::fieldCell, read by closedSumsAt), as does a sum that is not finite (requireFiniteSum); before,
// a NaN position indexed the closed sums' field with the integer the NaN converts to. A finite position: its cell
// and cell coordinates by hand (origin 0, spacing 0.5, 4 nodes per axis: (0.6, 1.9, -0.7) -> cell (1, 3, -1),
// t = (0.2, 0.8, 0), z clamped to the padded grid's -1).
TEST(ParticleDarcyStepping, ANonFinitePositionOrSumStopsTheRunSayingWhere) {
  using namespace cementsph::scene::particle_darcy;
  const Eigen::Vector3d origin(0, 0, 0), spacing(0.5, 0.5, 0.5);
  const int size[3] = {4, 4, 4};
  const auto where = [] { return std::string("particle 7 at step 12"); };
  int c[3];
  Eigen::Vector3d t;
  fieldCell(Eigen::Vector3d(0.6, 1.9, -0.7), origin, spacing, size, c, t, where);
  EXPECT_EQ(c[0], 1);
  EXPECT_EQ(c[1], 3);
  EXPECT_EQ(c[2], -1);
  EXPECT_NEAR(t[0], 0.2, 1e-12);
  EXPECT_NEAR(t[1], 0.8, 1e-12);
  EXPECT_NEAR(t[2], 0.0, 1e-12);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const Eigen::Vector3d& p : {Eigen::Vector3d(0.6, nan, 0.2), Eigen::Vector3d(std::numeric_limits<double>::infinity(), 0, 0)}) {
    try {
      fieldCell(p, origin, spacing, size, c, t, where);
      ADD_FAILURE() << "no error for a position that is not finite";
    } catch (const cementsph::sph::SimulationError& e) {
      EXPECT_NE(std::string(e.what()).find("particle 7 at step 12: its position is not finite"), std::string::npos) << e.what();
    }
  }
  EXPECT_NO_THROW(requireFiniteSum(0.25, "number density", where));
  try {
    requireFiniteSum(nan, "number density", where);
    ADD_FAILURE() << "no error for a sum that is not finite";
  } catch (const cementsph::sph::SimulationError& e) {
    EXPECT_NE(std::string(e.what()).find("particle 7 at step 12: its number density is not finite"), std::string::npos) << e.what();
  }
}

// A pressure solve whose solution is not finite stops the run with sph::SimulationError naming the solve and the
// particle (particle_darcy::requireFiniteSolution, after solvePressure's two solves); before, a NaN solve counted as
// converged (its residual compares false) and the particles stood still (a NaN step is refused as a closed voxel's).
TEST(ParticleDarcyStepping, ANonFiniteSolveStopsTheRunNamingTheParticle) {
  using cementsph::scene::particle_darcy::requireFiniteSolution;
  const auto where = [] { return std::string("step 40, the pressure solve"); };
  Eigen::VectorXd x(4);
  x << 1.0, -2.0, 0.5, 4.0;
  EXPECT_NO_THROW(requireFiniteSolution(x, "Darcy pressure", where));
  x[2] = std::numeric_limits<double>::quiet_NaN();
  try {
    requireFiniteSolution(x, "Darcy pressure", where);
    ADD_FAILURE() << "no error for a solution that is not finite";
  } catch (const cementsph::sph::SimulationError& e) {
    EXPECT_NE(std::string(e.what()).find("step 40, the pressure solve: the Darcy pressure of particle 2 is not finite"), std::string::npos)
        << e.what();
  }
}
