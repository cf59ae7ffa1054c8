// The study's pictures, drawn off-screen with XYPlot:
//   error_vs_wall_time.png      the paper's Fig. 6 as speed against error: surface error against the
//                               reference (mm) over wall time (s, log axis), one series per integrator,
//                               each point labelled with its particle radius in mm
//   spreading_vs_viscosity.png  the paper's Fig. 8: mean spreading distance (mm) against viscosity (Pa.s),
//                               of the particles and of the segmented simulated CT
//   end_pressure_vs_viscosity.png  the paper's Fig. 9, its simulated half: the outlet pressure at the end of
//                               injection over the sweep's largest, against viscosity (Pa.s)
// Runs without the figure (failed, or no error computable) are left out. The specs are separate from the
// writers so that tests can check them and a render test can draw a fixed one.
#pragma once

#include "cementsph/rendering/XYPlot.h"
#include "cementsph/study/StudyRow.h"

#include <filesystem>
#include <string>
#include <vector>

namespace cementsph::study {

// Throws std::runtime_error if no run has a surface error.
rendering::PlotSpec errorVsWallTimeSpec(const std::vector<StudyRow>& rows);
// Throws std::runtime_error if no run finished.
rendering::PlotSpec spreadingVsViscositySpec(const std::vector<StudyRow>& rows);
// Throws std::runtime_error if no run ended with a positive, finite outlet pressure.
rendering::PlotSpec endPressureVsViscositySpec(const std::vector<StudyRow>& rows);
// The figure's caption (study.md quotes it under the sweep's table).
std::string endPressureCaption();

// Write the PNG atomically (XYPlot); errors as the specs' and writePlotPng's.
void writeErrorVsWallTimePlot(const std::vector<StudyRow>& rows, const std::filesystem::path& png);
void writeSpreadingVsViscosityPlot(const std::vector<StudyRow>& rows, const std::filesystem::path& png);
void writeEndPressureVsViscosityPlot(const std::vector<StudyRow>& rows, const std::filesystem::path& png);

} // namespace cementsph::study
