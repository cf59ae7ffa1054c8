#include "cementsph/surfacemetrics/SurfaceDistance.h"

#include <vtkDoubleArray.h>
#include <vtkGenericCell.h>
#include <vtkPointData.h>
#include <vtkSmartPointer.h>
#include <vtkStaticCellLocator.h>

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace cementsph::surfacemetrics {

std::vector<double> vertexDistances(vtkPolyData* from, vtkPolyData* to) {
  if (!from || !to || from->GetNumberOfPoints() == 0 || to->GetNumberOfCells() == 0)
    throw std::invalid_argument("surface distance: empty surface");
  to->BuildCells(); // GetCell must not build lazily inside the parallel loop
  const int threads = std::max(1, omp_get_max_threads());
  // One locator per thread: FindClosestPoint keeps scratch state in the locator.
  std::vector<vtkSmartPointer<vtkStaticCellLocator>> locators(static_cast<std::size_t>(threads));
  for (auto& locator : locators) {
    locator = vtkSmartPointer<vtkStaticCellLocator>::New();
    locator->SetDataSet(to);
    locator->SetNumberOfCellsPerNode(8);
    locator->BuildLocator();
  }
  const vtkIdType n = from->GetNumberOfPoints();
  std::vector<double> distances(static_cast<std::size_t>(n));
#pragma omp parallel num_threads(threads)
  {
    vtkStaticCellLocator* locator = locators[static_cast<std::size_t>(omp_get_thread_num())];
    auto cell = vtkSmartPointer<vtkGenericCell>::New();
#pragma omp for schedule(static)
    for (vtkIdType i = 0; i < n; ++i) {
      double x[3], closest[3], dist2 = 0.0;
      vtkIdType cellId = -1;
      int subId = 0;
      from->GetPoint(i, x);
      locator->FindClosestPoint(x, closest, cell, cellId, subId, dist2);
      distances[static_cast<std::size_t>(i)] = std::sqrt(dist2);
    }
  }
  return distances;
}

DirectedDistance summarise(const std::vector<double>& d) {
  DirectedDistance s;
  s.vertices = d.size();
  if (d.empty()) return s;
  double sum = 0.0;
  for (double v : d) {
    sum += v;
    s.maxMm = std::max(s.maxMm, v);
  }
  s.meanMm = sum / static_cast<double>(d.size());
  double var = 0.0;
  for (double v : d) var += (v - s.meanMm) * (v - s.meanMm);
  s.stdMm = std::sqrt(var / static_cast<double>(d.size()));
  std::vector<double> sorted(d);
  const double rank = 0.95 * static_cast<double>(sorted.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(rank));
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<long>(lo), sorted.end());
  const double vlo = sorted[lo];
  double vhi = vlo;
  if (lo + 1 < sorted.size())
    vhi = *std::min_element(sorted.begin() + static_cast<long>(lo) + 1, sorted.end());
  s.p95Mm = vlo + (rank - static_cast<double>(lo)) * (vhi - vlo);
  return s;
}

namespace {
void attach(vtkPolyData* surface, const std::vector<double>& d) {
  auto array = vtkSmartPointer<vtkDoubleArray>::New();
  array->SetName(kDistanceArrayName);
  array->SetNumberOfTuples(static_cast<vtkIdType>(d.size()));
  std::copy(d.begin(), d.end(), array->GetPointer(0));
  surface->GetPointData()->RemoveArray(kDistanceArrayName);
  surface->GetPointData()->AddArray(array);
  surface->GetPointData()->SetActiveScalars(kDistanceArrayName);
}
} // namespace

SurfaceComparison compareSurfaces(vtkPolyData* a, vtkPolyData* b) {
  const std::vector<double> ab = vertexDistances(a, b);
  const std::vector<double> ba = vertexDistances(b, a);
  SurfaceComparison c;
  c.aToB = summarise(ab);
  c.bToA = summarise(ba);
  const bool aWorse = c.aToB.meanMm >= c.bToA.meanMm;
  c.errorMm = aWorse ? c.aToB.meanMm : c.bToA.meanMm;
  c.errorDirection = aWorse ? "a_to_b" : "b_to_a";
  c.hausdorffMm = std::max(c.aToB.maxMm, c.bToA.maxMm);
  c.hausdorff95Mm = std::max(c.aToB.p95Mm, c.bToA.p95Mm);
  attach(a, ab);
  attach(b, ba);
  return c;
}

} // namespace cementsph::surfacemetrics
