#include "cementsph/surfacemetrics/SurfaceDistance.h"

#include <vtkCellArray.h>
#include <vtkCellArrayIterator.h>
#include <vtkDoubleArray.h>
#include <vtkFloatArray.h>
#include <vtkPoints.h>
#include <vtkIdList.h>
#include <vtkPointData.h>
#include <vtkSmartPointer.h>
#include <vtkStaticPointLocator.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <utility>

namespace cementsph::surfacemetrics {

namespace {

using V3 = std::array<double, 3>;

inline double dot(const V3& a, const V3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline V3 sub(const V3& a, const V3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }

// Squared distance from p to triangle (a, b, c): the closest-point-on-triangle construction by
// Voronoi regions (Ericson, Real-Time Collision Detection, 5.1.5).
double pointTriangleDistance2(const V3& p, const V3& a, const V3& b, const V3& c) {
  const V3 ab = sub(b, a), ac = sub(c, a), ap = sub(p, a);
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  auto dist2 = [&p](const V3& q) { const V3 d = sub(p, q); return dot(d, d); };
  if (d1 <= 0 && d2 <= 0) return dist2(a);
  const V3 bp = sub(p, b);
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return dist2(b);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    return dist2({a[0] + v * ab[0], a[1] + v * ab[1], a[2] + v * ab[2]});
  }
  const V3 cp = sub(p, c);
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return dist2(c);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double w = d2 / (d2 - d6);
    return dist2({a[0] + w * ac[0], a[1] + w * ac[1], a[2] + w * ac[2]});
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return dist2({b[0] + w * (c[0] - b[0]), b[1] + w * (c[1] - b[1]), b[2] + w * (c[2] - b[2])});
  }
  const double denom = 1.0 / (va + vb + vc);
  const double v = vb * denom, w = vc * denom;
  return dist2({a[0] + ab[0] * v + ac[0] * w, a[1] + ab[1] * v + ac[1] * w, a[2] + ab[2] * v + ac[2] * w});
}

// A triangle surface prepared for exact point-to-surface queries: vertices in a static point
// locator, vertex -> triangle links, and the longest edge L. For a query x with nearest vertex at
// distance dv, the closest surface point lies in a triangle T at distance d <= dv, and every point
// of T is within L / sqrt(3) of one of T's vertices, so T has a vertex within dv + L / sqrt(3) of
// x: the triangles linked to the vertices in that ball contain the answer. Exact, and much faster
// here than vtkStaticCellLocator::FindClosestPoint in VTK 9.1 (measured: 2.7 s against ~0.3 s for
// 2 x 100k vertices on 2 cores).
struct TriangleSurface {
  std::vector<V3> points;
  std::vector<std::array<vtkIdType, 3>> triangles;
  std::vector<vtkIdType> linkStart, links; // CSR: triangles of vertex v are links[linkStart[v]..]
  double longestEdge = 0.0;
  vtkSmartPointer<vtkStaticPointLocator> locator;

  explicit TriangleSurface(vtkPolyData* surface) {
    const vtkIdType np = surface->GetNumberOfPoints();
    points.resize(static_cast<std::size_t>(np));
    for (vtkIdType i = 0; i < np; ++i) surface->GetPoint(i, points[static_cast<std::size_t>(i)].data());
    vtkCellArray* polys = surface->GetPolys();
    auto it = vtk::TakeSmartPointer(polys->NewIterator());
    for (it->GoToFirstCell(); !it->IsDoneWithTraversal(); it->GoToNextCell()) {
      vtkIdType n;
      const vtkIdType* ids;
      it->GetCurrentCell(n, ids);
      for (vtkIdType k = 1; k + 1 < n; ++k) triangles.push_back({ids[0], ids[k], ids[k + 1]}); // fan
    }
    if (triangles.empty()) throw std::invalid_argument("surface distance: surface has no polygons");
    linkStart.assign(static_cast<std::size_t>(np) + 1, 0);
    for (const auto& t : triangles)
      for (vtkIdType v : t) ++linkStart[static_cast<std::size_t>(v) + 1];
    for (std::size_t i = 1; i < linkStart.size(); ++i) linkStart[i] += linkStart[i - 1];
    links.resize(static_cast<std::size_t>(linkStart.back()));
    std::vector<vtkIdType> fill(linkStart.begin(), linkStart.end() - 1);
    for (std::size_t t = 0; t < triangles.size(); ++t)
      for (vtkIdType v : triangles[t]) {
        links[static_cast<std::size_t>(fill[static_cast<std::size_t>(v)]++)] = static_cast<vtkIdType>(t);
      }
    for (const auto& t : triangles)
      for (int e = 0; e < 3; ++e) {
        const V3 d = sub(points[static_cast<std::size_t>(t[e])], points[static_cast<std::size_t>(t[(e + 1) % 3])]);
        longestEdge = std::max(longestEdge, std::sqrt(dot(d, d)));
      }
    locator = vtkSmartPointer<vtkStaticPointLocator>::New();
    locator->SetDataSet(surface);
    locator->BuildLocator();
  }

  // Per-thread scratch for distance(): the candidate ids, and a stamp per triangle so that each
  // triangle is tested once per query without sorting.
  struct Scratch {
    vtkSmartPointer<vtkIdList> ids = vtkSmartPointer<vtkIdList>::New();
    std::vector<unsigned> stamp;
    unsigned query = 0;
  };

  // Thread-safe: the static locator's queries are, and the scratch is the caller's.
  double distance(const V3& x, Scratch& s) const {
    if (s.stamp.size() != triangles.size()) s.stamp.assign(triangles.size(), 0);
    if (++s.query == 0) { // wrapped: reset the stamps
      std::fill(s.stamp.begin(), s.stamp.end(), 0u);
      s.query = 1;
    }
    double q[3] = {x[0], x[1], x[2]};
    const vtkIdType nearest = locator->FindClosestPoint(q);
    const V3 dn = sub(x, points[static_cast<std::size_t>(nearest)]);
    double best2 = dot(dn, dn); // the nearest vertex: an upper bound of the answer
    const double reach = longestEdge / std::sqrt(3.0) * (1.0 + 1e-9) + 1e-12;
    auto testTrianglesOf = [&](std::size_t vi) {
      for (vtkIdType l = linkStart[vi]; l < linkStart[vi + 1]; ++l) {
        const auto t = static_cast<std::size_t>(links[static_cast<std::size_t>(l)]);
        if (s.stamp[t] == s.query) continue;
        s.stamp[t] = s.query;
        const auto& tri = triangles[t];
        best2 = std::min(best2, pointTriangleDistance2(x, points[static_cast<std::size_t>(tri[0])],
                                                       points[static_cast<std::size_t>(tri[1])],
                                                       points[static_cast<std::size_t>(tri[2])]));
      }
    };
    // The nearest vertex's triangles first: they almost always hold the answer, so the bound below
    // is tight and most other candidates are skipped without testing their triangles.
    testTrianglesOf(static_cast<std::size_t>(nearest));
    locator->FindPointsWithinRadius(std::sqrt(best2) + reach, q, s.ids);
    for (vtkIdType k = 0; k < s.ids->GetNumberOfIds(); ++k) {
      const auto vi = static_cast<std::size_t>(s.ids->GetId(k));
      const V3 d = sub(x, points[vi]);
      const double bound = std::sqrt(best2) + reach; // a vertex farther cannot own a closer triangle
      if (dot(d, d) > bound * bound) continue;
      testTrianglesOf(vi);
    }
    return std::sqrt(best2);
  }
};

} // namespace

std::vector<double> vertexDistances(vtkPolyData* from, vtkPolyData* to) {
  if (!from || !to || from->GetNumberOfPoints() == 0 || to->GetNumberOfCells() == 0)
    throw std::invalid_argument("surface distance: empty surface");
  const TriangleSurface target(to);
  const vtkIdType n = from->GetNumberOfPoints();
  std::vector<double> distances(static_cast<std::size_t>(n));
  // Flying edges writes float points: read them directly rather than through a virtual GetPoint.
  auto* floatArray = vtkFloatArray::SafeDownCast(from->GetPoints()->GetData());
  const float* floats = floatArray && floatArray->GetNumberOfComponents() == 3 ? floatArray->GetPointer(0) : nullptr;
#pragma omp parallel
  {
    TriangleSurface::Scratch scratch;
#pragma omp for schedule(dynamic, 1024)
    for (vtkIdType i = 0; i < n; ++i) {
      V3 x;
      if (floats) {
        const float* f = floats + 3 * i;
        x = {f[0], f[1], f[2]};
      } else {
        from->GetPoint(i, x.data());
      }
      distances[static_cast<std::size_t>(i)] = target.distance(x, scratch);
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
