// Surfaces out: VTK XML PolyData (.vtp), written atomically like every other output.
#pragma once

#include <vtkPolyData.h>
#include <vtkSmartPointer.h>

#include <string>
#include <vector>

namespace cementsph::imaging {

void writePolyData(vtkPolyData* surface, const std::string& path);
// The same VTK XML PolyData file, its arrays appended raw and uncompressed, written by us in one pass: for the
// injection's snapshots (a 5 ml run writes a hundred), where VTK's writer cost about 3x the file system's own
// time per byte and LZ4 saved a tenth of the bytes of single-precision fields (issue 23, BENCHMARKS.md). VTK's
// reader and ParaView read it as any .vtp (PolyDataWriterTest reads it back with vtkXMLPolyDataReader). It
// takes points, the four cell arrays and numeric point, cell and field data in VTK's standard memory layout;
// anything else (a string array, an implicit array) is written by writePolyData instead.
void writePolyDataUncompressed(vtkPolyData* points, const std::string& path);
// A VTK XML parallel PolyData file (.pvtp) whose data is the union of the .vtp pieces named (paths relative to
// its folder), each of which has the point arrays of `prototype` (names, types, components): how a snapshot that
// only adds points names the pieces written before it instead of writing them again (issue 23). VTK's
// vtkXMLPPolyDataReader and ParaView read it as one dataset. Throws std::invalid_argument where an array has no
// name or no word type (the pieces could not be described).
void writePolyDataPieces(const std::string& path, vtkPolyData* prototype, const std::vector<std::string>& pieceFiles);
vtkSmartPointer<vtkPolyData> readPolyData(const std::string& path);

} // namespace cementsph::imaging
