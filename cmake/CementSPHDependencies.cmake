# Every third-party package the project uses, found in one place. All come from Debian 12
# (scripts/install-deps.sh installs them).
find_package(Eigen3 3.3 REQUIRED NO_MODULE)
find_package(OpenMP REQUIRED COMPONENTS CXX)
find_package(CLI11 REQUIRED)
find_package(nlohmann_json 3.10 REQUIRED)
find_package(NLopt REQUIRED) # cementsph plan (libnlopt-dev)
# libdeflate (libdeflate-dev): the gzip of the NRRD volumes written (Modules/Imaging/IO/src/NrrdGzip.h). No CMake
# config in Debian 12's 1.14: the library by path (the installed package links it as it links libz).
find_path(CEMENTSPH_LIBDEFLATE_INCLUDE_DIR libdeflate.h REQUIRED)
find_library(CEMENTSPH_LIBDEFLATE_LIBRARY NAMES deflate REQUIRED)

# VTK 9.1: list components explicitly (see shared platform notes). The lists are kept in variables for
# the installed CementSPHConfig.cmake, which finds the same components again.
set(CEMENTSPH_VTK_COMPONENTS
  CommonCore CommonDataModel CommonExecutionModel CommonSystem CommonTransforms CommonMisc
  ChartsCore ViewsContext2D RenderingContext2D RenderingContextOpenGL2
  RenderingCore RenderingOpenGL2 RenderingFreeType RenderingAnnotation RenderingVolume
  InteractionStyle IOImage IOXML IOParallelXML IOLegacy
  FiltersCore FiltersGeneral FiltersGeometry FiltersModeling FiltersSources FiltersExtraction
  ImagingCore ImagingGeneral ImagingMath ImagingStatistics ImagingMorphological
  TestingRendering)
find_package(VTK 9.1 REQUIRED COMPONENTS ${CEMENTSPH_VTK_COMPONENTS})

# ITK 5.2 (Debian): no ITKVtkGlue, so the imaging module carries its own geometry-preserving bridge.
set(CEMENTSPH_ITK_COMPONENTS
  ITKCommon ITKIOImageBase ITKIONRRD ITKIOMeta ITKIONIFTI ITKIOGDCM ITKIOTransformBase
  ITKIOTransformInsightLegacy ITKIOTransformMatlab ITKIOTransformHDF5 ITKRegistrationMethodsv4 ITKOptimizersv4 ITKMetricsv4
  ITKTransform ITKImageGrid ITKImageFilterBase ITKThresholding ITKConnectedComponents
  ITKMathematicalMorphology ITKBinaryMathematicalMorphology ITKSmoothing ITKImageIntensity
  ITKImageStatistics ITKLabelMap ITKDistanceMap ITKTestKernel)
find_package(ITK 5.2 REQUIRED COMPONENTS ${CEMENTSPH_ITK_COMPONENTS})

if(CEMENTSPH_BUILD_TESTING)
  find_package(GTest REQUIRED)
endif()
if(CEMENTSPH_BUILD_BENCHMARKS)
  find_package(benchmark REQUIRED)
endif()
