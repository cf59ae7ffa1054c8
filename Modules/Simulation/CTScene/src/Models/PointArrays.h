// A named double point array of n tuples, for the engines' cement points (particles_NNNN.vtp).
#pragma once

#include <vtkDoubleArray.h>
#include <vtkSmartPointer.h>

namespace cementsph::scene::detail {

inline vtkSmartPointer<vtkDoubleArray> pointArray(const char* name, int components, vtkIdType n) {
  auto a = vtkSmartPointer<vtkDoubleArray>::New();
  a->SetName(name);
  a->SetNumberOfComponents(components);
  a->SetNumberOfTuples(n);
  return a;
}

} // namespace cementsph::scene::detail
