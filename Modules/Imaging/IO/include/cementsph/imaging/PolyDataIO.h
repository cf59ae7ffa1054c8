// Surfaces out: VTK XML PolyData (.vtp), written atomically like every other output.
#pragma once

#include <vtkPolyData.h>
#include <vtkSmartPointer.h>

#include <string>

namespace cementsph::imaging {

void writePolyData(vtkPolyData* surface, const std::string& path);
vtkSmartPointer<vtkPolyData> readPolyData(const std::string& path);

} // namespace cementsph::imaging
